"""The 2D drawing panel in a real browser: where elements land, crisp edges, dragging with a
constraint, keys only while the panel (or the 3D view) has the focus, a world per tab, and
markup in a text element drawn as text."""

from __future__ import annotations

import base64
import io
import re
import tempfile
from pathlib import Path

import numpy as np
import pytest

from testkit.browser import wait_until

SLOW = 120_000

SPEC = """
ejs: 1
title: Drawing test
model:
  variables:
    px: 1.0
    py: 2.0
    bx: 0.0
    by: -2.0
    count: 0
    count3: 0
    label_text: "<b>bold</b><img src=x onerror=window.__pwn=1>"
    pic: {expr: "np.full((2, 2, 3), [0, 200, 0], dtype=np.uint8)"}
view:
  - markdown: {text: "Notes about the lab"}
  - folder:
      label: The panel
      children:
        - drawing:
            x_range: [-4, 4]
            y_range: [-3, 3]
            height: 300
            keys: {ArrowUp: "count = count + 1", a: "count = count + 10"}
            children:
              - particle: {name: red, position: [px, py], radius: 0.3, color: "#ff0000"}
              - particle: {name: blue, position: [bx, by], radius: 0.3, color: "#0000ff", drag: {bind: bx, along: x, region: [-2, 2, -3, 3]}}
              - text: {position: [0, -1], text: "{label_text}", size: 16, color: black}
              - image: {source: pic, position: [-3, 2], size: [1, 1]}
  - keyboard: {keys: {ArrowUp: "count3 = count3 + 1"}}
  - slider: {bind: px, min: -3, max: 3, label: Red x}
  - scene:
      - sphere: {position: [0, 0, 0], radius: 0.3, color: gray}
"""


@pytest.fixture(scope="module")
def lab():
    """The test lab built and served with a simulation per tab; yields ``(app, url)``."""
    from ejsgen.cli import build
    from ejsrl.app import load_app

    with tempfile.TemporaryDirectory() as tmp:
        spec = Path(tmp) / "drawing_test.ejs.yaml"
        spec.write_text(SPEC)
        out = build(spec, Path(tmp) / "app")
        app = load_app(out)
        server = app.serve("127.0.0.1", 0, block=False, per_client=True, max_sessions=3, grace=30.0)
        try:
            yield app, f"http://127.0.0.1:{server.get_port()}"
        finally:
            app.stop()
            server.stop()


def open_tab(context, url: str):
    page = context.new_page()
    page.bring_to_front()
    page.set_default_timeout(SLOW)
    page.goto(url)
    page.wait_for_selector("canvas.ejs2d-c[data-drawn]", timeout=SLOW)
    wait_until(lambda: "/s/" in page.evaluate("location.href"), what="the tab's session address")
    return page


def session_model(app, page):
    token = re.search(r"/s/([A-Za-z0-9_-]+)/", page.evaluate("location.href")).group(1)
    return app.classroom.sessions[token].app


def canvas_box(page) -> dict:
    return page.locator("canvas.ejs2d-c").first.bounding_box()


def world_to_css(box: dict, x: float, y: float, bounds=(-4.0, 4.0, -3.0, 3.0)) -> tuple[float, float]:
    """Where (x, y) lands in the canvas (CSS px from its top-left), by the rule the reference
    states: equal aspect, the smaller scale of the two ranges, the window centred."""
    x0, x1, y0, y1 = bounds
    w, h = box["width"], box["height"]
    s = min(w / (x1 - x0), h / (y1 - y0))
    return w / 2 + (x - (x0 + x1) / 2) * s, h / 2 - (y - (y0 + y1) / 2) * s


def scale(box: dict, bounds=(-4.0, 4.0, -3.0, 3.0)) -> float:
    return min(box["width"] / (bounds[1] - bounds[0]), box["height"] / (bounds[3] - bounds[2]))


@pytest.mark.browser
def test_a_red_circle_lands_where_the_bounds_put_it_with_crisp_edges(lab, browser_context):
    from PIL import Image

    app, url = lab
    page = browser_context.new_page()
    page.set_default_timeout(SLOW)
    cdp = browser_context.new_cdp_session(page)
    cdp.send("Emulation.setDeviceMetricsOverride", {"width": 1280, "height": 800, "deviceScaleFactor": 2, "mobile": False})
    try:
        page.goto(url)
        page.wait_for_selector("canvas.ejs2d-c[data-drawn]", timeout=SLOW)
        assert page.evaluate("devicePixelRatio") == 2
        box = canvas_box(page)
        # the canvas's backing store is its CSS size times the ratio: vectors drawn at full resolution
        size = page.evaluate("(() => { const c = document.querySelector('canvas.ejs2d-c'); return [c.width, c.height]; })()")
        assert size == [round(box["width"] * 2), round(box["height"] * 2)]
        # the canvas's device pixels, as the screen shows them at ratio 2
        url_png = page.evaluate("document.querySelector('canvas.ejs2d-c').toDataURL('image/png')")
        shot = np.asarray(Image.open(io.BytesIO(base64.b64decode(url_png.split(",", 1)[1]))).convert("RGB")).astype(int)
        assert shot.shape[:2] == (size[1], size[0])
        cx, cy = world_to_css(box, 1.0, 2.0)
        r = 0.3 * scale(box)
        X, Y = int(round(cx * 2)), int(round(cy * 2))
        assert tuple(shot[Y, X]) == (255, 0, 0), f"the centre of the red circle is {shot[Y, X]}"
        # the red area is the disc of radius r around (cx, cy): its extent along the row through the centre
        row = shot[Y]
        red = np.where((row[:, 0] > 200) & (row[:, 1] < 60) & (row[:, 2] < 60))[0]
        assert abs(red.min() / 2 - (cx - r)) < 1.0 and abs((red.max() + 1) / 2 - (cx + r)) < 1.0
        col = shot[:, X]
        red_c = np.where((col[:, 0] > 200) & (col[:, 1] < 60) & (col[:, 2] < 60))[0]
        assert abs(red_c.min() / 2 - (cy - r)) < 1.0 and abs((red_c.max() + 1) / 2 - (cy + r)) < 1.0
        # crisp: from full red to the white background within 2 device pixels on each side
        right = row[red.max() + 1 : red.max() + 6]
        blurred = [p for p in right if not (tuple(p) == (255, 255, 255) or (p[0] > 200 and p[1] < 60))]
        assert len(blurred) <= 2, f"the edge is blurred over {len(blurred)} device pixels: {right.tolist()}"
        assert tuple(row[red.max() + 4]) == (255, 255, 255)
        # an image item: its pixels fill the square its position and size give
        gx, gy = world_to_css(box, -3.0, 2.0)
        half = 0.5 * scale(box) * 2 - 2  # device pixels, a little inside the edge
        for dx, dy in ((0, 0), (-half, -half), (half, half)):
            assert tuple(shot[int(round(gy * 2 + dy)), int(round(gx * 2 + dx))]) == (0, 200, 0)
    finally:
        page.close()


@pytest.mark.browser
def test_a_drag_moves_the_bound_variable_along_x_inside_its_region(lab, browser_context):
    app, url = lab
    page = open_tab(browser_context, url)
    try:
        model = session_model(app, page).model
        box = canvas_box(page)
        sx, sy = world_to_css(box, 0.0, -2.0)
        tx, ty = world_to_css(box, 3.5, 0.5)  # past the region's xmax (2), and off the line y = -2
        page.mouse.move(box["x"] + sx, box["y"] + sy)
        page.mouse.down()
        page.mouse.move(box["x"] + (sx + tx) / 2, box["y"] + (sy + ty) / 2, steps=4)
        wait_until(lambda: 0.5 < model.bx < 2.0, what="bx to follow the mouse while it is held")
        page.mouse.move(box["x"] + tx, box["y"] + ty, steps=4)
        page.mouse.up()
        wait_until(lambda: model.bx == 2.0, what="bx clamped to the region's xmax, 2")
        assert model.by == -2.0  # along x: y is not written
        # the next frame shows the blue disc where the constraint put it
        wait_until(lambda: page.evaluate(
            "(() => { const E = window.__ejs2d; const p = Object.values(E.panels).find(q => q.canvas && q.canvas.isConnected && q.frame);"
            " return p.text.indexOf('\"id\":\"blue\"') >= 0; })()"), what="a frame with the blue disc")
    finally:
        page.close()


@pytest.mark.browser
def test_keys_act_only_while_their_panel_or_the_3d_view_has_the_focus(lab, browser_context):
    app, url = lab
    page = open_tab(browser_context, url)
    try:
        model = session_model(app, page).model
        box = canvas_box(page)
        page.mouse.click(box["x"] + 5, box["y"] + 5)  # focus the panel (off any element)
        page.keyboard.press("ArrowUp")
        wait_until(lambda: model.count == 1, what="ArrowUp on the focused panel: count = 1")
        assert model.count3 == 0
        page.get_by_text("Notes about the lab").click()  # the focus leaves the panel
        page.keyboard.press("ArrowUp")
        page.mouse.click(box["x"] + 5, box["y"] + 5)
        page.keyboard.press("a")  # a marker: once it is applied, the ArrowUp before it would have been too
        wait_until(lambda: model.count >= 11, what="'a' on the focused panel")
        assert model.count == 11, "ArrowUp with the focus elsewhere changed the panel's variable"
        assert model.count3 == 0
        # the 3D view: click it, and its own keys act (the panel's do not)
        scene = page.locator("canvas[data-engine]").first.bounding_box()
        page.mouse.click(scene["x"] + scene["width"] / 3, scene["y"] + scene["height"] / 2)
        page.evaluate("window.__reached = []; window.addEventListener('keydown', e => window.__reached.push(e.key))")
        page.keyboard.press("ArrowUp")
        wait_until(lambda: model.count3 == 1, what="ArrowUp on the 3D view: count3 = 1")
        assert model.count == 11
        # a key the lab does not map is left to the page (the 3D camera's keys), a mapped one is taken
        page.keyboard.press("w")
        wait_until(lambda: page.evaluate("window.__reached").count("w") == 1, what="'w' to reach the page")
        assert "ArrowUp" not in page.evaluate("window.__reached")
    finally:
        page.close()


@pytest.mark.browser
def test_two_tabs_are_two_worlds(lab, browser_context):
    app, url = lab
    a = open_tab(browser_context, url)
    b = open_tab(browser_context, url)
    try:
        ma, mb = session_model(app, a).model, session_model(app, b).model
        assert ma is not mb
        a.bring_to_front()
        box = canvas_box(a)
        sx, sy = world_to_css(box, 0.0, -2.0)
        tx, _ = world_to_css(box, -1.5, -2.0)
        a.mouse.move(box["x"] + sx, box["y"] + sy)
        a.mouse.down()
        a.mouse.move(box["x"] + tx, box["y"] + sy, steps=5)
        a.mouse.up()
        wait_until(lambda: abs(ma.bx + 1.5) < 0.05, what="tab A's bx dragged to -1.5")
        assert mb.bx == 0.0, "dragging in one tab moved the other tab's world"
        frame_b = b.evaluate("(() => Object.values(window.__ejs2d.panels).find(q => q.frame).text)()")
        assert frame_b is not None and '"id":"blue"' in frame_b
    finally:
        a.close()
        b.close()


@pytest.mark.browser
def test_markup_in_a_text_element_is_drawn_as_text(lab, browser_context):
    from PIL import Image

    app, url = lab
    page = open_tab(browser_context, url)
    try:
        binding = session_model(app, page).views[0].panel.drawings[0]
        texts = [it for it in binding.frame["items"] if it["t"] == "text"]
        assert texts[0]["text"] == "<b>bold</b><img src=x onerror=window.__pwn=1>"
        # nothing became markup: no element from the text, no script ran
        assert page.evaluate("window.__pwn") is None
        assert page.locator('img[src="x"]').count() == 0
        assert page.locator("[data-ejs2d] b").count() == 0
        # ... and the text is on the canvas: dark pixels around its anchor (0, -1)
        box = canvas_box(page)
        shot = np.asarray(Image.open(io.BytesIO(page.locator("canvas.ejs2d-c").first.screenshot())).convert("L")).astype(int)
        cx, cy = world_to_css(box, 0.0, -1.0)
        band = shot[int(cy) - 8 : int(cy) + 8, int(cx) - 150 : int(cx) + 150]
        assert (band < 100).sum() > 150, "no text drawn at its anchor"
        # it is as wide as the whole string in the canvas's font, not as "bold" alone
        width = page.evaluate("(() => { const c = document.createElement('canvas').getContext('2d'); c.font = '16px sans-serif';"
                              " return c.measureText('<b>bold</b><img src=x onerror=window.__pwn=1>').width; })()")
        dark_cols = np.where((band < 100).any(axis=0))[0]
        assert dark_cols.max() - dark_cols.min() > 0.8 * width
    finally:
        page.close()


@pytest.mark.browser
def test_the_panel_survives_its_folder_closed_and_opened(lab, browser_context):
    app, url = lab
    page = open_tab(browser_context, url)
    try:
        model = session_model(app, page).model
        shown = ("(() => { const c = document.querySelector('canvas.ejs2d-c');"
                 " return !!c && c.checkVisibility() && Math.abs(c.getBoundingClientRect().height - 300) < 1; })()")
        page.get_by_text("The panel").first.click()  # close the folder
        wait_until(lambda: not page.evaluate(shown), what="the folder to close")
        page.get_by_text("The panel").first.click()  # ... and open it again
        wait_until(lambda: page.evaluate(shown), what="the folder to open again")
        boxes: list = []  # the folder's opening animation moves the canvas: wait until it stays put
        wait_until(lambda: boxes.append(canvas_box(page)) or (len(boxes) > 3 and boxes[-1] == boxes[-2] == boxes[-3]),
                   what="the canvas to stop moving")
        # drawn again (the red disc at (1, 2)), and a drag still reaches the server
        box = canvas_box(page)
        cx, cy = world_to_css(box, 1.0, 2.0)
        rgb = page.evaluate(f"(() => {{ const c = document.querySelector('canvas.ejs2d-c'); const r = devicePixelRatio;"
                            f" return Array.from(c.getContext('2d').getImageData(Math.round({cx} * r), Math.round({cy} * r), 1, 1).data); }})()")
        assert rgb[:3] == [255, 0, 0]
        sx, sy = world_to_css(box, 0.0, -2.0)
        tx, _ = world_to_css(box, 1.0, -2.0)
        page.mouse.move(box["x"] + sx, box["y"] + sy)
        page.mouse.down()
        page.mouse.move(box["x"] + tx, box["y"] + sy, steps=4)
        page.mouse.up()
        wait_until(lambda: abs(model.bx - 1.0) < 0.05, what="bx dragged to 1 after the folder opened again")
    finally:
        page.close()


@pytest.fixture(scope="module")
def projectile():
    """The projectile example built and served a simulation per tab; yields ``(app, url)``."""
    from ejsgen.cli import build
    from ejsrl.app import load_app
    from testkit import EXAMPLES

    with tempfile.TemporaryDirectory() as tmp:
        app = load_app(build(EXAMPLES / "projectile_2d.ejs.yaml", Path(tmp) / "app"))
        server = app.serve("127.0.0.1", 0, block=False, per_client=True, max_sessions=2, grace=30.0)
        try:
            yield app, f"http://127.0.0.1:{server.get_port()}"
        finally:
            app.stop()
            server.stop()


@pytest.mark.browser
def test_the_projectile_lab_moved_by_mouse_and_keys_lands_where_physics_says(projectile, browser_context):
    from testkit.browser import hide_notifications, save_shot

    app, url = projectile
    page = open_tab(browser_context, url)
    try:
        lab = session_model(app, page)
        m = lab.model
        # the panel has the window (no 3D scene), x_range [-1, 21], y_range [-1, 11], axes: its plot
        # area is inset for the tick labels, so points are found through the page's own mapping
        def css(x: float, y: float) -> tuple[float, float]:
            return tuple(page.evaluate(f"window.__ejs2d.toPx(Object.keys(window.__ejs2d.panels)[0], {x}, {y})"))

        _settle_height(page)  # as high as its ranges need: scrolled into the window, all of it
        page.locator("canvas.ejs2d-c").first.scroll_into_view_if_needed()
        hide_notifications(page)  # a GPU-less browser's notice, at the bottom-left here, covers the launcher
        box = canvas_box(page)
        sx, sy = css(m.x0, m.y0)
        tx, ty = css(3.0, 2.0)
        page.mouse.move(box["x"] + sx, box["y"] + sy)
        page.mouse.down()
        page.mouse.move(box["x"] + tx, box["y"] + ty, steps=5)
        page.mouse.up()
        wait_until(lambda: abs(m.x0 - 3.0) < 0.1 and abs(m.y0 - 2.0) < 0.1, what="the launcher dragged to (3, 2)")
        assert (m.x, m.y) == (m.x0, m.y0)  # on_drag: rest(): the ball waits on the launcher
        page.keyboard.press("ArrowUp")  # the panel has the focus since the drag: 51 degrees
        wait_until(lambda: m.angle == 51.0, what="ArrowUp: the angle up by one degree")
        page.keyboard.press("Space")  # play
        wait_until(lambda: not lab.is_playing() and m.t > 0, timeout=60, what="the ball to land")
        v, a, g = m.v0, np.radians(m.angle), m.g
        t_land = (v * np.sin(a) + np.sqrt((v * np.sin(a)) ** 2 + 2 * g * m.y0)) / g
        assert abs(m.x - (m.x0 + v * np.cos(a) * t_land)) < 1e-4
        # the trace on the page runs from the launcher to the landing point
        wait_until(lambda: '"t":"polyline"' in page.evaluate("Object.values(window.__ejs2d.panels)[0].text"), what="the trace")
        save_shot(page, "projectile_2d")
    finally:
        page.close()


def _settle_height(page) -> None:
    """Wait until the panel's height (set by the page from its ranges) stays the same."""
    last: list = []

    def settled() -> bool:
        last.append(page.locator("canvas.ejs2d-c").first.bounding_box()["height"])
        return len(last) > 3 and len(set(last[-4:])) == 1

    wait_until(settled, what="the panel's height to settle")


def _shown_x_range(page) -> tuple[float, float]:
    """The world x range the panel shows, read from its pixels alone: the plot area's frame (the
    dark columns that run down most of the canvas) and the three seagreen targets at x = 10, 14, 18
    (a straight line through their centres maps x to pixels)."""
    from PIL import Image

    img = np.asarray(Image.open(io.BytesIO(page.locator("canvas.ejs2d-c").first.screenshot())).convert("RGB")).astype(int)
    green = (np.abs(img - [46, 139, 87]).sum(axis=2) < 30)
    cols = np.flatnonzero(green.any(axis=0))
    groups = np.split(cols, np.flatnonzero(np.diff(cols) > 3) + 1)
    assert len(groups) == 3, f"three targets expected, found {len(groups)}"
    centres = [g.mean() for g in groups]
    b, a = np.polyfit([10.0, 14.0, 18.0], centres, 1)
    grey = ((img.max(axis=2) < 200) & (np.ptp(img, axis=2) < 30)).mean(axis=0)  # the frame's grey, maybe blurred over 2 px
    frame = np.flatnonzero(grey > 0.5)
    runs = np.split(frame, np.flatnonzero(np.diff(frame) > 1) + 1)
    assert len(runs) >= 2, f"the plot area's frame not found ({frame})"
    left, right = runs[0].mean(), runs[-1].mean()
    return (left + 0.5 - a) / b, (right + 0.5 - a) / b


@pytest.mark.browser
def test_an_equal_aspect_panel_is_as_high_as_its_ranges_need(projectile, browser_context):
    # the trial: x_range [-1, 21] in a panel 1,160 px wide and 340 high showed -17 ... 37; with no
    # height given the panel follows the ranges' aspect, so they fill it (a few % at most beyond)
    app, url = projectile
    page = open_tab(browser_context, url)
    try:
        for width, height in ((1280, 800), (560, 800)):
            page.set_viewport_size({"width": width, "height": height})
            wait_until(lambda: page.locator("canvas.ejs2d-c").first.bounding_box()["width"] < width - 100, what="the panel's width")
            _settle_height(page)
            lo, hi = _shown_x_range(page)
            assert abs(lo - -1.0) < 0.03 * 22 and abs(hi - 21.0) < 0.03 * 22, (width, lo, hi)
            box = page.locator("canvas.ejs2d-c").first.bounding_box()
            assert box["height"] <= height - 100 + 1  # within the window
    finally:
        page.close()


WRONG_SHAPE = """
ejs: 1
title: A set of the wrong shape
model:
  variables:
    P: {expr: "np.zeros((20, 3))"}
view:
  - drawing:
      x_range: [-2, 2]
      y_range: [-2, 2]
      children:
        - particle: {name: ball, position: [1, 1], radius: 0.4, color: "#ff0000"}
        - point: {name: spray, position: P, size: 4}
"""


@pytest.mark.browser
def test_an_element_of_the_wrong_shape_leaves_the_rest_drawn_and_the_error_in_sight(browser_context, tmp_path):
    # the trial: an N x 3 set where N x 2 is needed blanked the whole panel, and in a lab without a
    # 3D scene the error box sat under the notifications, its left part hidden
    from PIL import Image

    from ejsgen.cli import build
    from ejsrl.app import load_app

    spec = tmp_path / "wrong.ejs.yaml"
    spec.write_text(WRONG_SHAPE)
    app = load_app(build(spec, tmp_path / "app"))
    server = app.serve("127.0.0.1", 0, block=False, per_client=True, max_sessions=2, grace=5.0)
    page = open_tab(browser_context, f"http://127.0.0.1:{server.get_port()}")
    try:
        lab = session_model(app, page)
        assert lab.error is not None and "spray" in lab.error.message and "(20, 3)" in lab.error.message
        box = page.get_by_text("Error at", exact=False).first
        box.wait_for(timeout=SLOW)
        page.wait_for_selector(".mantine-Notification-root", timeout=SLOW)  # the error's notification (and the browser's)
        err = page.locator("div:has(> b:text('Error at'))").first.bounding_box()
        for i in range(page.locator(".mantine-Notification-root").count()):
            note = page.locator(".mantine-Notification-root").nth(i).bounding_box()
            overlap_x = min(err["x"] + err["width"], note["x"] + note["width"]) - max(err["x"], note["x"])
            overlap_y = min(err["y"] + err["height"], note["y"] + note["height"]) - max(err["y"], note["y"])
            assert overlap_x <= 0 or overlap_y <= 0, (err, note)
        # the red ball is drawn where it belongs, and the panel writes the error on itself
        img = np.asarray(Image.open(io.BytesIO(page.locator("canvas.ejs2d-c").first.screenshot())).convert("RGB")).astype(int)
        pos = page.evaluate("window.__ejs2d.toPx(Object.keys(window.__ejs2d.panels)[0], 1, 1)")
        r, g, b = img[int(pos[1]), int(pos[0])]
        assert r > 200 and g < 60 and b < 60, (r, g, b)
        reddish_note = (np.abs(img - [201, 42, 42]).sum(axis=2) < 60).sum()  # the note's text colour (#c92a2a)
        assert reddish_note > 50
    finally:
        page.close()
        app.stop()
        server.stop()
