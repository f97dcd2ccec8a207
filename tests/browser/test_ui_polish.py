"""The panel and the 3D view look right to a student (issue #10, item 13), in a real browser.

Each test checks one thing a user would notice and saves a screenshot under
``test-artifacts/ui_polish_*.png``: the lab's instructions open, a panel wide enough for
its title and plots (and the width a spec asks for), labels that keep their spaces and
never turn into code boxes, a matrix shown as one aligned block, plot legends with
values, arrow keys on a slider that leave the 3D view alone, trail colours as written (mediumpurple, not a washed-out lilac),
a first view that frames the scene, and the camera image of a camera lab in sight.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from testkit.browser import ARTIFACTS, serving, settled, wait_until, project
from ejsgen.cli import build

TITLE = "A rather long title for a lab, which the panel shows whole"

SPEC = f"""\
ejs: 1
title: {TITLE}
description: |
  **Instructions:** move the slider, then press Play.
model:
  variables:
    t: 0.0
    dt: 0.05
    a: {{value: 1.0, unit: m}}
    T: {{expr: "np.array([[1.0, 0, 0, 0.25], [0, -1.0, 0, -12.5], [0, 0, 1, 0.5], [0, 0, 0, 1]])"}}
  evolution:
    - code: t = t + dt
view:
  - slider: {{bind: a, min: 0, max: 2, step: 0.1, label: "a = {{a:.1f}} m"}}
  - label: {{text: "one  two   three"}}
  - label: {{text: "    indented, not code"}}
  - label: {{text: "T = {{T:+.3f}}"}}
  - plot: {{title: "a(t)", series: [{{y: a, label: alpha}}], window: 5}}
  - scene:
      - grid: {{size: 2, cell: 0.25}}
      - trail: {{name: path, point: "[a - 1, 0, 0.1*t]", color: mediumpurple, width: 8}}
simulation: {{panel_width: 520}}
"""


@pytest.fixture
def polish_lab(tmp_path: Path):
    spec = tmp_path / "polish.ejs.yaml"
    spec.write_text(SPEC)
    with serving(build(spec, tmp_path / "out")) as (app, url):
        yield app, url


def open_lab(page, url: str) -> None:
    page.goto(url)
    page.wait_for_selector("canvas", state="attached", timeout=45_000)
    page.get_by_role("button", name="Reset").first.wait_for(timeout=45_000)
    # hide the GPU-less browser's notice, which covers the top left corner
    page.add_style_tag(content=".mantine-Notification-root { display: none !important; }")


def in_viewport(page, locator) -> bool:
    box = locator.bounding_box()
    size = page.viewport_size
    return box is not None and box["y"] >= 0 and box["y"] + box["height"] <= size["height"] and box["x"] >= 0 \
        and box["x"] + box["width"] <= size["width"]


def shot(page, name: str) -> None:
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / f"ui_polish_{name}.png"))


@pytest.mark.browser
def test_panel_about_title_labels_matrix_and_plot(polish_lab, page):
    app, url = polish_lab
    open_lab(page, url)

    # the lab's instructions are open from the start, in sight
    instructions = page.get_by_text("Instructions:").first
    instructions.wait_for()
    assert instructions.is_visible() and in_viewport(page, instructions)

    # the panel is as wide as the spec asks (520 px), and its title is not cut short
    play = page.get_by_role("button", name="Play").first
    assert play.bounding_box()["width"] > 470
    title = page.get_by_text(TITLE, exact=True).first
    assert title.evaluate("e => e.scrollWidth <= e.clientWidth")

    # labels keep their spaces; an indented label is text, not a code box
    spaced = page.locator("p", has_text="one").first
    assert spaced.inner_text().replace("\xa0", " ") == "one  two   three"
    indented = page.locator("p", has_text="indented, not code").first
    assert indented.inner_text().replace("\xa0", " ") == "    indented, not code"
    assert page.locator("pre, code", has_text="indented").count() == 0

    # the slider's label follows its value
    page.get_by_text("a = 1.0 m", exact=True).first.wait_for()

    # a 4x4 matrix is one block of four aligned rows
    block = page.locator("p", has_text="T =").locator("span").first
    rows = block.inner_text().replace("\xa0", " ").split("\n")
    assert rows == [
        "[ +1.000  +0.000  +0.000  +0.250]",
        "[ +0.000  -1.000  +0.000 -12.500]",
        "[ +0.000  +0.000  +1.000  +0.500]",
        "[ +0.000  +0.000  +0.000  +1.000]",
    ]
    assert block.evaluate("e => getComputedStyle(e).fontFamily").lower().find("mono") >= 0
    widths = block.evaluate("e => { const r = document.createRange(); r.selectNodeContents(e);"
                            " return Array.from(r.getClientRects()).map(c => Math.round(c.width)).filter(w => w > 0); }")
    assert len(widths) == 4 and len(set(widths)) == 1, widths  # every row as wide: aligned columns

    # the line below the plot shows the series' latest value (not "--")
    page.get_by_role("button", name="Play").first.click()
    wait_until(lambda: app.model.t > 0.5, what="t > 0.5 after Play")
    legend = page.get_by_text("alpha = 1", exact=False).first
    legend.wait_for()
    assert "at t = " in legend.inner_text() or "at t = " in page.locator("p", has_text="alpha = 1").first.inner_text()
    assert page.get_by_text("--", exact=True).count() == 0
    shot(page, "panel")


@pytest.mark.browser
def test_arrow_keys_on_a_slider_leave_the_3d_view_alone(polish_lab, page):
    app, url = polish_lab
    open_lab(page, url)
    clients = lambda: list(server_of(app).get_clients().values())  # noqa: E731
    wait_until(lambda: len(clients()) == 1, what="the page to connect")
    camera = clients()[0].camera
    wait_until(lambda: camera.position is not None, what="the browser's camera")
    before = settled(lambda: np.array(camera.position), what="the first view (framing is applied on connect)")
    slider = page.get_by_role("slider").first
    slider.focus()
    page.keyboard.down("ArrowRight")
    page.wait_for_timeout(600)
    page.keyboard.up("ArrowRight")
    wait_until(lambda: app.model.a > 1.05, what="the slider to move a")
    settled(lambda: np.array(camera.position), what="the camera after the key")
    assert np.allclose(np.array(camera.position), before, atol=1e-6), "the 3D view moved with the slider's arrow key"
    # elsewhere, the arrow keys still turn the view
    box = page.locator("canvas[data-engine]").first.bounding_box()
    page.mouse.click(box["x"] + 40, box["y"] + box["height"] - 120)
    page.keyboard.down("ArrowRight")
    page.wait_for_timeout(600)
    page.keyboard.up("ArrowRight")
    wait_until(lambda: not np.allclose(np.array(camera.position), before, atol=1e-3), timeout=10,
               what="the view to turn with the arrow key on the canvas")


@pytest.mark.browser
def test_a_trail_is_drawn_in_its_own_colour(polish_lab, page):
    app, url = polish_lab
    open_lab(page, url)
    page.get_by_role("button", name="Play").first.click()
    wait_until(lambda: len(app.world["path"].props["points"]) > 40, what="the trail to grow")
    app.pause()
    # mediumpurple is (147, 112, 219); read as linear RGB it would show as about (199, 178, 240)
    purple = np.array([147, 112, 219])

    def purple_pixels() -> int:
        return int((np.abs(scene_pixels(page) - purple).sum(axis=2) < 40).sum())

    wait_until(lambda: purple_pixels() > 100, what="the trail's mediumpurple in the 3D view")
    shot(page, "trail")


def scene_pixels(page) -> np.ndarray:
    """The 3D view (three.js's canvas) as an (H, W, 3) int array."""
    png = page.locator("canvas[data-engine]").first.screenshot()
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def server_of(app):
    """The viser server an app serves on (the view keeps it)."""
    return app.views[0].server


def content_points(name: str, world) -> np.ndarray:
    """What each example's scene shows at start, from the world's own data (N, 3)."""
    if name == "pendulum":  # its view looks at the middle of the swing: the bob at either side of it
        bob = world["bob"].T_world()[:3, 3]
        other = bob * [-1.0, 1.0, 1.0]
        return np.array([[0.0, 0.0, 0.0], bob + 0.08, bob - 0.08, other + 0.08, other - 0.08])
    if name == "van_der_pol":
        dot = world["dot"].T_world()[:3, 3]
        return np.array([dot + 0.1, dot - 0.1, [2.5, 2.5, 0.0], [-2.5, -2.5, 0.0]])
    if name == "mass_spring_chain":
        return np.vstack([np.asarray(world["masses"].props["points"]), np.asarray(world["springs"].props["points"])])
    raise KeyError(name)


@pytest.mark.browser
@pytest.mark.parametrize("name", ["pendulum", "van_der_pol", "mass_spring_chain"])
def test_the_first_view_frames_the_scene(name, built, page):
    with serving(built(name)) as (app, url):
        open_lab(page, url)
        clients = lambda: list(server_of(app).get_clients().values())  # noqa: E731
        wait_until(lambda: len(clients()) == 1, what="the page to connect")
        camera = clients()[0].camera
        wait_until(lambda: camera.look_at is not None and np.linalg.norm(np.asarray(camera.position) - [3.0, 3.0, 3.0]) > 1e-6,
                   what="the framed camera to be reported back")
        settled(lambda: (tuple(camera.position), tuple(camera.look_at)), what="the framed camera to settle")
        with app.lock:
            pts = content_points(name, app.world)
        ndc = project(camera, pts)
        # everything is in the picture ...
        assert np.all(np.abs(ndc) < 1.0), ndc
        # ... and not lost in a corner: the content spans a good part of the view
        span = ndc.max(axis=0) - ndc.min(axis=0)
        assert span.max() > 0.5, span
        shot(page, f"framing_{name}")


@pytest.mark.browser
def test_the_camera_image_of_a_camera_lab_is_in_sight(built, page):
    with serving(built("paper/visual_servoing_eih")) as (app, url):
        open_lab(page, url)
        image = page.locator("img[src^='blob:']").first
        image.wait_for()
        wait_until(lambda: image.bounding_box() is not None and image.bounding_box()["height"] > 100,
                   what="the camera image to be shown")
        assert in_viewport(page, image), image.bounding_box()
        # and the lab's instructions are open beside it
        assert page.get_by_text("A camera rides on the tool", exact=False).first.is_visible()
        shot(page, "camera_lab")
        png = Image.open(io.BytesIO(image.screenshot())).convert("RGB")
        assert np.asarray(png).std() > 10  # a picture, not a blank box


TICKS_SPEC = """\
ejs: 1
title: Ticks
model:
  variables:
    t: 123450.0
    dt: 0.5
    y: 0.0
  evolution:
    - code: t = t + dt
  fixed_relations: |
    y = -123456.0 + 0.5*sin(t)
view:
  - plot: {title: small values at large times, series: [{y: y, label: y}], window: 10}
"""


@pytest.mark.browser
def test_plot_tick_labels_are_not_cut_at_the_edges(tmp_path, page):
    spec = tmp_path / "ticks.ejs.yaml"
    spec.write_text(TICKS_SPEC)
    with serving(build(spec, tmp_path / "out")) as (app, url):
        open_lab(page, url)
        page.get_by_role("button", name="Play").first.click()
        wait_until(lambda: app.model.t > 123466, what="a window of points in the plot")
        app.pause()
        canvas = page.locator("div[data-key^=\"plot-\"] canvas").first
        settled(lambda: canvas.screenshot(), what="the paused plot")
        png = np.asarray(Image.open(io.BytesIO(canvas.screenshot())).convert("RGB")).astype(int)
        ink = png.sum(axis=2) < 500  # text and lines, not the white background
        # no tick label touches the chart's left or right edge (it would be cut there)
        assert not ink[:, :2].any(), "a y tick label is cut at the left edge"
        assert not ink[:, -2:].any(), "an x tick label is cut at the right edge"
        # and the x tick labels (123,450 ...) do not run into each other: gaps between them
        rows = ink[-60:]  # the bottom strip: the plot area's bottom edge, tick labels and the axis title
        edge = [i for i, r in enumerate(rows) if r.mean() > 0.8]
        rows = rows[edge[-1] + 1 :] if edge else rows  # below the edge
        label_rows = [r for r in rows if r.sum() > 20]
        assert label_rows, "no x tick labels"
        widest = max(label_rows, key=lambda r: r.sum())
        cols = np.flatnonzero(widest)
        groups = np.split(cols, np.flatnonzero(np.diff(cols) > 8) + 1)
        widths = [int(g[-1] - g[0]) for g in groups]
        assert len(groups) >= 2 and max(widths) < 75, f"the x tick labels run into each other: {widths}"
        shot(page, "ticks")
