"""UI polish a new user noticed, in a real browser (Debian's Chromium).

Each test opens a lab as a student would and checks what they see: number boxes that
show their whole value, a lab without a 3D scene that gives the window to its panel, ...
Screenshots go to ``test-artifacts/polish_*.png``.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from ejsgen.cli import build
from testkit.browser import ARTIFACTS, serving, wait_until, project


def open_lab(page, url: str) -> None:
    page.goto(url)
    page.get_by_role("button", name="Reset").first.wait_for(timeout=45_000)
    # hide the GPU-less browser's notice, which covers the top left corner
    page.add_style_tag(content=".mantine-Notification-root { display: none !important; }")


def shot(page, name: str) -> None:
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / f"polish_{name}.png"))


NUMBERS = """\
ejs: 1
title: Number boxes
model:
  variables:
    t: 0.0
    dt: 0.1
    a: {expr: "np.pi / 2"}
    b: {expr: "-np.pi / 4"}
    c: {expr: "np.pi * 100"}
    k: 250.0
  evolution:
    - code: t = t + dt
view:
  - slider: {bind: a, min: -3.14, max: 3.14, step: 0.01, label: "a set point (rad)"}
  - slider: {bind: b, min: -2.6, max: 2.6, step: 0.01, label: "b set point (rad)"}
  - slider: {bind: k, min: 1, max: 1000, step: 1, label: "Current limit (A)"}
  - number: {bind: c, step: 0.01, label: "c"}
"""


@pytest.mark.browser
def test_number_boxes_show_their_whole_value(tmp_path: Path, page):
    """A slider's box and a number field show the value to their step, never cut off."""
    spec = tmp_path / "numbers.ejs.yaml"
    spec.write_text(NUMBERS)
    with serving(build(spec, tmp_path / "out")) as (app, url):
        open_lab(page, url)
        boxes = page.locator("input.mantine-NumberInput-input")
        boxes.nth(3).wait_for()
        assert boxes.count() == 4
        shown = [boxes.nth(i).input_value() for i in range(4)]
        # to the step's precision, as the slider's own marks are
        assert shown == ["1.57", "-0.79", "250", "314.16"], shown
        panel_right = page.get_by_role("button", name="Reset").first.bounding_box()
        for i in range(4):
            box = boxes.nth(i)
            # the text fits in its box (nothing scrolled out of sight) ...
            assert box.evaluate("e => e.scrollWidth <= e.clientWidth"), (shown[i], box.evaluate("e => [e.scrollWidth, e.clientWidth]"))
            # ... and the box is inside the panel
            bb = box.bounding_box()
            assert bb["x"] + bb["width"] <= panel_right["x"] + panel_right["width"] + 1, (bb, panel_right)
        shot(page, "numbers")


def lorenz_points(seconds: float = 40.0, h: float = 0.002) -> np.ndarray:
    """The Lorenz attractor (sigma 10, rho 28, beta 8/3, from (1, 1, 1)) as examples/lorenz
    draws it: (x, y, z - 25) * 0.05, by a plain RK4 of its own (N, 3)."""
    def f(s: np.ndarray) -> np.ndarray:
        x, y, z = s
        return np.array([10.0 * (y - x), x * (28.0 - z) - y, x * y - 8.0 / 3.0 * z])

    s = np.array([1.0, 1.0, 1.0])
    out = []
    for i in range(int(seconds / h)):
        k1 = f(s)
        k2 = f(s + h / 2 * k1)
        k3 = f(s + h / 2 * k2)
        k4 = f(s + h * k3)
        s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if i % 10 == 0:
            out.append(s.copy())
    return (np.array(out) - [0.0, 0.0, 25.0]) * 0.05


@pytest.mark.browser
def test_lorenz_first_view_shows_the_whole_attractor(built, page):
    """A student's new tab (its own simulation, from t = 0) sees the whole butterfly, not a tangle up close."""
    from ejsrl.app import load_app

    app = load_app(built("lorenz"))
    server = app.serve("127.0.0.1", 0, block=False, per_client=True)
    try:
        open_lab(page, f"http://127.0.0.1:{server.get_port()}")
        wait_until(lambda: len(server.get_clients()) == 1, what="the page to connect")
        camera = next(iter(server.get_clients().values())).camera
        wait_until(lambda: camera.look_at is not None and np.linalg.norm(np.asarray(camera.position) - [3.0, 3.0, 3.0]) > 1e-6,
                   what="the framed camera to be reported back")
        points = lorenz_points()

        def framed() -> bool:  # the client reports its camera as it moves: wait for where it settles
            ndc = project(camera, points)
            return bool(np.all(np.abs(ndc) < 1.0) and (ndc.max(axis=0) - ndc.min(axis=0)).max() > 0.6)

        try:
            wait_until(framed, what="the first view to frame the attractor")
        except AssertionError:
            pass  # the assertions below say what is wrong
        ndc = project(camera, points)
        assert np.all(np.abs(ndc) < 1.0), np.abs(ndc).max(axis=0)  # every loop in the picture ...
        span = ndc.max(axis=0) - ndc.min(axis=0)
        assert span.max() > 0.6, span  # ... and large in it
        shot(page, "lorenz")
    finally:
        app.stop()
        server.stop()


def time_readings(page) -> list[str]:
    """Every 't = <number>' the page shows (the panel's own readout, labels; not the plots'
    legends, which say which t their values are at: 'θ = 0.2 at t = 0.5')."""
    import re

    return re.findall(r"(?<![\w(])(?<!at )t = -?[0-9.]+", page.locator("body").inner_text().replace("\xa0", " "))


@pytest.mark.browser
@pytest.mark.parametrize("step", ["step1_pendulum", "step2_plot"])
def test_tutorial_shows_the_time_once(step, built, page):
    """The tutorial's pendulum shows t once (the panel's readout under Play), while it plays."""
    with serving(built(f"tutorial/{step}")) as (app, url):
        open_lab(page, url)
        page.get_by_role("button", name="Play").first.click()
        wait_until(lambda: app.model.t > 0.2, what="the pendulum to play")
        page.get_by_text("θ = ", exact=False).first.wait_for()
        assert len(time_readings(page)) == 1, time_readings(page)
        shot(page, f"time_{step}")


@pytest.mark.browser
def test_a_lab_without_a_scene_gives_the_window_to_its_panel(built, page):
    """Tutorial step 2 (plots, no scene): no empty 3D area; the panel, with the About text, spans the window."""
    with serving(built("tutorial/step2_plot")) as (app, url):
        open_lab(page, url)
        width = page.viewport_size["width"]
        play = page.get_by_role("button", name="Play").first
        wait_until(lambda: play.bounding_box()["width"] > 0.8 * width, timeout=20,
                   what="the panel to span the window")
        about = page.get_by_text("A simple pendulum. Press", exact=False).first
        assert about.is_visible()
        # no 3D view shows: the strip the client keeps of it left of the panel is blank
        # (no grid, no axes, no logo; the panel's shadow aside)
        left = int(play.bounding_box()["x"]) - 30  # clear of the panel's shadow
        strip = np.asarray(Image.open(io.BytesIO(page.screenshot(clip={"x": 0, "y": 0, "width": left, "height": 800}))).convert("RGB")).astype(int)
        assert (strip.max(axis=(0, 1)) - strip.min(axis=(0, 1))).max() == 0, "something shows left of the panel"
        # the plots use the room: as wide as the panel, and still wholly readable in height
        chart = page.locator("div[data-key^=\"plot-\"] canvas").first
        wait_until(lambda: (chart.bounding_box() or {}).get("width", 0) > 0, what="the first chart to be laid out")
        box = chart.bounding_box()
        assert box["width"] > 0.75 * width and box["height"] < 0.5 * page.viewport_size["height"], box
        shot(page, "no_scene")
