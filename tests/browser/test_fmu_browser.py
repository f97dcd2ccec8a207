"""Lab 8 (the paper's figure 13, joint drives in an FMU) in a real browser (Debian's Chromium).

A student opens it, presses Play and watches the arm go to the paper's set points while
the FMU computes the torques; then lowers the amplifier's current limit (a tunable FMU
parameter) with its slider: the FMU refuses the next step, the simulation pauses and the
panel shows the FMU's own message at the spec line of the FMU; Reset re-instantiates it.

With ``EJSGEN_GALLERY=1`` the screenshot is also written, at 640x400, to
``examples/gallery/fmu_motor_control.png`` (the picture of ``examples/README.md``).
"""

from __future__ import annotations

import io
import os

import numpy as np
import pytest
from PIL import Image
from testkit import ROOT
from testkit.browser import ARTIFACTS, close_notifications, serving, wait_until

SET_POINTS = np.array([np.pi / 2, np.pi / 3, -np.pi / 4])
TITLE = "Position control of a 3-DOF arm with an FMU (paper, figure 13)"


@pytest.fixture
def served(built):
    with serving(built("paper/fmu_motor_control")) as (app, url):
        yield app, url


def scene_canvas(page) -> int | None:
    """The index of the 3D view's canvas (the widest outside the plots), once it is laid out."""
    widths = page.evaluate("() => [...document.querySelectorAll('canvas')].map(c => c.closest('div[data-ejs2d]') ? 0 : c.getBoundingClientRect().width)")
    if not widths or max(widths) < 300:
        return None
    return widths.index(max(widths))


def scene_pixels(page) -> np.ndarray:
    """The 3D view as an (H, W, 3) int array (what the user sees of the scene)."""
    png = page.locator("canvas").nth(scene_canvas(page) or 0).screenshot(timeout=60_000)
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def hide_notices(page) -> None:
    """Hide the GPU-less browser's 'software WebGL' notice, which may cover the scene."""
    page.add_style_tag(content=".mantine-Notification-root:not(:has(.mantine-Notification-title)) { display: none !important; }")


@pytest.mark.browser
def test_the_fmu_lab_plays_reaches_the_set_points_and_shows_an_fmu_failure(served, page):
    app, url = served
    page.goto(url)
    page.wait_for_selector("canvas", state="attached", timeout=45_000)
    page.get_by_role("button", name="Play").first.wait_for(timeout=45_000)
    assert page.get_by_text(TITLE, exact=True).first.is_visible()
    wait_until(lambda: scene_canvas(page) is not None, timeout=60, what="the 3D view to be laid out")
    close_notifications(page)
    link0 = app.world["arm3.link3"].T_world().copy()
    before = scene_pixels(page)

    page.get_by_role("button", name="Play").first.click()
    wait_until(lambda: app.model.t > 2.5, timeout=90, what="2.5 simulated seconds after Play")
    assert app.error is None
    assert np.abs(app.model.q - SET_POINTS).max() < 0.02  # at the set points, driven by the FMU's torques
    assert np.linalg.norm(app.world["arm3.link3"].T_world()[:3, 3] - link0[:3, 3]) > 0.05
    wait_until(lambda: np.mean(np.abs(scene_pixels(page) - before).sum(axis=2) > 30) > 0.002, what="the arm to move on screen")
    hide_notices(page)
    png = page.screenshot()
    ARTIFACTS.mkdir(exist_ok=True)
    (ARTIFACTS / "lab_fmu_motor_control.png").write_bytes(png)
    if os.environ.get("EJSGEN_GALLERY"):
        Image.open(io.BytesIO(png)).convert("RGB").resize((640, 400), Image.LANCZOS).save(ROOT / "examples" / "gallery" / "fmu_motor_control.png", optimize=True)

    # the current limit: a tunable parameter of the FMU, sent to it when the slider moves
    page.get_by_role("tab", name="FMU parameters").click()
    slider = page.get_by_role("slider").filter(visible=True).last
    slider.focus()
    slider.press("Home")  # 1 A: below the current that holds the arm up against gravity
    wait_until(lambda: app.error is not None, what="the FMU to refuse the step")
    assert not app.is_playing()
    spec = (ROOT / "examples" / "paper" / "fmu_motor_control.ejs.yaml").read_text().splitlines()
    line = next(k for k, text in enumerate(spec, 1) if text.strip() == "drives:")
    page.locator("b", has_text=f"Error at fmu_motor_control.ejs.yaml:{line}:3").first.wait_for()
    assert "exceeds the amplifier's limit i_max = 1 A" in page.content()  # the FMU's own message
    (ARTIFACTS / "lab_fmu_motor_control_error.png").write_bytes(page.screenshot())

    old = app.model._ejs_fmus
    page.get_by_role("button", name="Reset").first.click()
    wait_until(lambda: app.model._ejs_fmus not in (None, old), what="Reset to instantiate the FMU again")
    with app.lock:
        assert old.closed and app.error is None and app.model.t == 0.0
    assert app.model.i_max == 1000.0
