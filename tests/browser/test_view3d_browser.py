"""The 3D view's camera and the frames it shows, in a real browser (Debian's Chromium).

What a user sees: the camera the spec sets (a coloured sphere is where that camera puts it,
worked out here from the spec's numbers alone), a button whose action calls ``set_view``
turns the view, Restore view brings the spec's camera back (after the user dragged it too),
a reloaded tab keeps the camera code asked for, each tab of a class has a camera of its own,
a followed object stays at the centre while it moves, and a pendulum's rod stays on its bob
in every screenshot taken while it swings, rigid or stretching (sent as points, as before
the fix, the rod was off its bob by a median 3-3.6 px and up to 19-24 px here).
"""

from __future__ import annotations

import io
import math
import re

import numpy as np
import pytest

from testkit.browser import ARTIFACTS, settled, wait_until

SLOW = 120_000

LAB = """\
ejs: 1
title: Camera
model:
  variables:
    t: 0.0
    dt: 0.01
    theta: 1.2
    omega: 0.0
    x: 0.0
    z: 0.0
  evolution:
    - ode: {{equations: {{theta: omega, omega: -9.81*sin(theta)}}}}
  fixed_relations: |
    x = {length}*sin(theta)
    z = -{length}*cos(theta)
view:
  - button: {{label: Look down, action: "set_view(preset='top', fov=30)"}}
  - scene:
{view}
      - sphere: {{name: marker, position: [0.6, 0, 0.3], radius: 0.04, color: "#00c000"}}
      - line: {{name: rod, points: "[[0, 0, 0], [x, 0, z]]", color: "#0000ff", width: 3}}
      - sphere: {{name: bob, position: [x, 0, z], radius: 0.05, color: "#ff0000"}}
simulation: {{fps: 30, autoplay: {autoplay}}}
"""

#: the spec's camera in the tests that check it: in front, looking at the pivot's level
SPEC_VIEW = "      - view: {position: [0.2, -3.2, -0.3], target: [0.2, 0, -0.3], fov: 50}"
SPEC_POSITION, SPEC_TARGET, SPEC_FOV = np.array([0.2, -3.2, -0.3]), np.array([0.2, 0.0, -0.3]), math.radians(50)


def build_lab(tmp_path, view: str, *, autoplay: bool = False, length: str = "1"):
    """The lab with ``view`` (a line of the scene, or nothing); ``length``: the rod's length (an expression)."""
    from ejsgen.cli import build

    spec = tmp_path / "camera.ejs.yaml"
    spec.write_text(LAB.format(view=view, autoplay="true" if autoplay else "false", length=f"({length})"))
    return build(spec, tmp_path / "app")


def open_lab(page, url: str | None) -> None:
    """Open ``url`` in ``page`` (None: the page is loading already, a reload) and wait for the lab."""
    if url is not None:
        page.goto(url)
    page.wait_for_selector("canvas", state="attached", timeout=SLOW)
    page.get_by_role("button", name="Restore view").first.wait_for(timeout=SLOW)
    # hide the GPU-less browser's notice, which covers part of the scene
    page.add_style_tag(content=".mantine-Notification-root { display: none !important; }")


def canvas(page) -> np.ndarray:
    """The 3D canvas as (H, W, 3) ints; the axes gizmo in its bottom-left corner painted over."""
    from PIL import Image

    img = np.asarray(Image.open(io.BytesIO(page.locator("canvas").first.screenshot())).convert("RGB")).astype(int)
    img = img.copy()
    img[-120:, :120] = 255
    return img


def disc(img: np.ndarray, colour: str) -> tuple[np.ndarray, int] | None:
    """Centre (x, y) in pixels of the disc of a sphere drawn in ``colour`` ('red' or 'green'),
    the middle of its pixels' box (shading moves a mean, not the box), and its pixel count."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    mask = (r > g + 60) & (r > b + 60) if colour == "red" else (g > r + 60) & (g > b + 60)
    ys, xs = np.nonzero(mask)
    if len(xs) < 12:
        return None
    h, w = mask.shape
    if xs.min() < 2 or ys.min() < 2 or xs.max() > w - 3 or ys.max() > h - 3:
        return None  # cut by the edge: its box is not the disc's
    return np.array([(xs.min() + xs.max()) / 2.0, (ys.min() + ys.max()) / 2.0]), len(xs)


def pixel_of(point: np.ndarray, position: np.ndarray, target: np.ndarray, up: np.ndarray, fov: float, size: tuple[int, int]) -> np.ndarray:
    """Where a pinhole camera (position, target, up, vertical fov in radians) draws ``point`` on a
    canvas of ``size`` (width, height): (x, y) pixels from the top left."""
    w, h = size
    f = (target - position) / np.linalg.norm(target - position)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    rel = point - position
    depth = rel @ f
    tan_v = math.tan(fov / 2.0)
    ndc = np.array([(rel @ r) / depth / (tan_v * w / h), (rel @ u) / depth / tan_v])
    return np.array([(ndc[0] + 1.0) / 2.0 * w, (1.0 - ndc[1]) / 2.0 * h])


def the_client(app):
    clients = list(app.views[0].server.get_clients().values())
    return clients[0] if len(clients) == 1 else None


def camera_at(app, position, target, *, fov: float | None = None, tol: float = 1e-3):
    """The tab's camera, as its browser reports it, is at ``position`` looking at ``target``."""

    def check() -> bool:
        client = the_client(app)
        if client is None:
            return False
        cam = client.camera
        try:
            ok = np.allclose(cam.position, position, atol=tol) and np.allclose(cam.look_at, target, atol=tol)
            return ok and (fov is None or abs(cam.fov - fov) < 1e-3)
        except AssertionError:  # not reported yet
            return False

    return check


@pytest.fixture
def shared(tmp_path):
    """The lab with the spec's camera, one simulation for every tab: yields ``(app, url)``."""
    from testkit.browser import serving

    with serving(build_lab(tmp_path, SPEC_VIEW)) as served:
        yield served


@pytest.mark.browser
def test_the_spec_camera_set_view_reset_view_and_a_reload(shared, page):
    app, url = shared
    open_lab(page, url)
    wait_until(camera_at(app, SPEC_POSITION, SPEC_TARGET, fov=SPEC_FOV), what="the spec's camera, reported by the browser")
    # the marker sphere is where the spec's camera, worked out from the spec's numbers, draws it
    img = settled(lambda: canvas(page), what="the picture of the reported camera")
    h, w = img.shape[:2]
    want = pixel_of(np.array([0.6, 0.0, 0.3]), SPEC_POSITION, SPEC_TARGET, np.array([0.0, 0.0, 1.0]), SPEC_FOV, (w, h))
    seen = disc(img, "green")
    assert seen is not None, "the marker is not in the picture"
    assert np.linalg.norm(seen[0] - want) < 3.0, (seen[0], want)
    # square-on to the x-z plane: the pivot (0, 0, 0) and the marker's height differ by what the spec says
    page.screenshot(path=str(ARTIFACTS / "view3d_spec_camera.png"))

    # a button whose action calls set_view(preset='top', fov=30): the view looks straight down
    page.get_by_role("button", name="Look down").click()

    def looks_down() -> bool:
        client = the_client(app)
        try:
            d = np.asarray(client.camera.look_at) - np.asarray(client.camera.position)
            return d[2] < 0 and np.linalg.norm(d[:2]) < 1e-3 * abs(d[2]) and abs(client.camera.fov - math.radians(30)) < 1e-3
        except (AssertionError, AttributeError):
            return False

    wait_until(looks_down, what="the camera to look straight down after set_view(preset='top')")
    cam = the_client(app).camera
    img = settled(lambda: canvas(page), what="the picture of the camera looking down")
    want = pixel_of(np.array([0.6, 0.0, 0.3]), np.asarray(cam.position), np.asarray(cam.look_at), np.array([0.0, 1.0, 0.0]),
                    math.radians(30), (img.shape[1], img.shape[0]))
    seen = disc(img, "green")
    assert seen is not None and np.linalg.norm(seen[0] - want) < 3.0, (seen, want)
    page.screenshot(path=str(ARTIFACTS / "view3d_set_view_top.png"))

    # a reloaded tab is shown the camera code asked for
    page.reload()
    open_lab(page, None)
    wait_until(looks_down, what="the reloaded tab to look down as set_view asked")

    # the user drags the view about; Restore view puts the spec's camera back
    box = page.locator("canvas").first.bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(cx, cy)
    page.mouse.down()
    page.mouse.move(cx + 150, cy + 60, steps=8)
    page.mouse.up()
    page.get_by_role("button", name="Restore view").click()
    wait_until(camera_at(app, SPEC_POSITION, SPEC_TARGET, fov=SPEC_FOV), what="Restore view to bring the spec's camera back")


@pytest.mark.browser
def test_a_followed_object_stays_at_the_centre(tmp_path, page):
    from ejsrl.app import load_app

    view = "      - view: {position: [0, -2.5, -0.6], follow: bob, follow_offset: true, fov: 40}"
    app = load_app(build_lab(tmp_path, view, autoplay=True))
    server = app.serve("127.0.0.1", 0, block=False, per_client=True, max_sessions=2, grace=30.0)
    try:
        open_lab(page, f"http://127.0.0.1:{server.get_port()}")
        wait_until(lambda: "/s/" in page.evaluate("location.href"), what="the tab's session")
        token = re.search(r"/s/([A-Za-z0-9_-]+)/", page.evaluate("location.href")).group(1)
        mine = app.classroom.sessions[token].app
        wait_until(lambda: mine.model.t > 0.5, what="the pendulum to swing")
        centres, xs = [], []
        for _ in range(25):
            img = canvas(page)
            seen = disc(img, "red")
            with mine.lock:
                xs.append(mine.model.x)
            if seen is not None:
                centres.append(seen[0] - np.array([img.shape[1] / 2.0, img.shape[0] / 2.0]))
        page.screenshot(path=str(ARTIFACTS / "view3d_follow.png"))
    finally:
        app.stop()
        server.stop()
    assert max(xs) - min(xs) > 0.5, "the bob hardly moved: nothing was followed"
    assert len(centres) >= 20, f"the bob was off the picture in {25 - len(centres)} of 25 screenshots"
    off = np.linalg.norm(np.array(centres), axis=1)
    print(f"bob off the centre: median {np.median(off):.2f} px, max {off.max():.2f} px")
    # the bob swings over ~1.9 m (several hundred pixels) while the picture keeps it at the centre
    assert np.median(off) < 2.0 and off.max() < 4.0, off


@pytest.mark.browser
@pytest.mark.parametrize("length", ["1", "1 + 0.3*sin(7*t)"], ids=["rigid", "stretching"])
def test_the_rod_stays_on_its_bob_while_it_swings(tmp_path, page, length):
    """Screenshots while playing: how far the rod's end is from the bob, in pixels: the distance from
    the bob's centre to the rod's line, or the gap between the rod's visible end and the bob's disc.

    Sent as points (``ejsrl.view._lines.RIGID_LINES = False``, as before the fix) the rod is
    drawn a browser frame after the bob: in this very set-up median 3.0 px, p90 7.3 px, max
    23.6 px (rigid) and 3.6 / 10.6 / 18.7 px (stretching); sent as poses, 0.5 / 0.9 / 1.5 px
    and 0.5 / 0.9 / 1.3 px: drawn in the same frame, also when the rod stretches and shrinks as
    it swings (an elastic pendulum)."""
    from testkit.browser import serving

    view = "      - view: {position: [0, -3.6, -0.6], target: [0, 0, -0.6], fov: 50}"
    with serving(build_lab(tmp_path, view, autoplay=True, length=length)) as (app, url):
        open_lab(page, url)
        wait_until(lambda: app.model.t > 1.0, what="the pendulum to swing (and stretch to both ends)")
        gaps, thetas = [], []
        for _ in range(40):
            img = canvas(page)
            with app.lock:
                thetas.append(app.model.theta)
            bob = disc(img, "red")
            r, g, b = img[..., 0], img[..., 1], img[..., 2]
            blue = (b > r + 60) & (b > g + 60)
            if bob is None or blue.sum() < 30:
                continue
            ys, xs = np.nonzero(blue)
            pts = np.column_stack([xs, ys]).astype(float)
            mid = pts.mean(axis=0)
            direction = np.linalg.svd(pts - mid, full_matrices=False)[2][0]
            rel = bob[0] - mid
            if rel @ direction < 0:
                direction = -direction  # from the pivot towards the bob
            across = abs(rel[0] * direction[1] - rel[1] * direction[0])
            # along the rod: its visible end must reach the bob's disc (radius: half its box's width)
            ys_r, xs_r = np.nonzero((r > g + 60) & (r > b + 60))
            radius = (xs_r.max() - xs_r.min()) / 2.0
            short = max(0.0, (rel @ direction - radius) - ((pts - mid) @ direction).max())
            gaps.append(max(across, short))
        page.screenshot(path=str(ARTIFACTS / "view3d_rod_and_bob.png"))
    assert max(thetas) - min(thetas) > 1.0, "the pendulum hardly swung"
    assert len(gaps) >= 30, f"only {len(gaps)} of 40 screenshots showed the rod and the bob"
    gaps_arr = np.array(gaps)
    print(f"rod to bob: median {np.median(gaps_arr):.2f} px, p90 {np.percentile(gaps_arr, 90):.2f} px, max {gaps_arr.max():.2f} px")
    assert np.median(gaps_arr) < 1.5 and gaps_arr.max() < 3.0, gaps_arr


@pytest.fixture
def classroom(tmp_path):
    """The lab served with a simulation per tab: yields ``(app, url)``."""
    from ejsrl.app import load_app

    app = load_app(build_lab(tmp_path, SPEC_VIEW))
    server = app.serve("127.0.0.1", 0, block=False, per_client=True, max_sessions=2, grace=30.0)
    yield app, f"http://127.0.0.1:{server.get_port()}"
    app.stop()
    server.stop()


@pytest.mark.browser
def test_each_tab_of_a_class_has_its_own_camera(classroom, browser_context):
    app, url = classroom

    def session_of(page):
        token = re.search(r"/s/([A-Za-z0-9_-]+)/", page.evaluate("location.href")).group(1)
        return app.classroom.sessions[token]

    def reported(page):
        view = session_of(page).view
        cam = view.client.camera
        return np.asarray(cam.position, dtype=float), np.asarray(cam.look_at, dtype=float)

    def settles(page, check):
        def ok() -> bool:
            try:
                return session_of(page).view is not None and check(*reported(page))
            except (AssertionError, AttributeError):
                return False

        return ok

    at_spec = lambda p, t: np.allclose(p, SPEC_POSITION, atol=1e-3) and np.allclose(t, SPEC_TARGET, atol=1e-3)  # noqa: E731
    down = lambda p, t: (t - p)[2] < 0 and np.linalg.norm((t - p)[:2]) < 1e-3 * abs((t - p)[2])  # noqa: E731
    pages = []
    try:
        for _ in range(2):
            page = browser_context.new_page()
            page.set_default_timeout(SLOW)
            pages.append(page)
            open_lab(page, url)
            wait_until(lambda: "/s/" in page.evaluate("location.href"), what="the tab's session")
        a, b = pages
        for page in pages:
            wait_until(settles(page, at_spec), timeout=60, what="each tab to show the spec's camera")
        a.bring_to_front()
        a.get_by_role("button", name="Look down").click()
        wait_until(settles(a, down), timeout=60, what="tab A to look down")
        b.bring_to_front()
        b.wait_for_timeout(500)
        assert settles(b, at_spec)(), "tab B's camera moved with tab A's set_view"
        a.bring_to_front()
        a.reload()
        open_lab(a, None)
        wait_until(settles(a, down), timeout=60, what="tab A, reloaded, to look down still")
    finally:
        for page in pages:
            page.close()
