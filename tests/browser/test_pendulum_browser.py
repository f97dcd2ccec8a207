"""The pendulum example, built by ejsgen and served, in a real browser (Debian's Chromium).

What a student does: open the app, see the 3D view and the panel, move the Length slider
(the model's L changes on the server and the bob moves), press Play (t advances), press
Reset (back to the start).
"""

from __future__ import annotations


import numpy as np
import pytest

from testkit.browser import ARTIFACTS, canvas_pixels, serving, settled, wait_until
from testkit import EXAMPLES


@pytest.fixture
def pendulum_app(tmp_path):
    from ejsgen.cli import build

    with serving(build(EXAMPLES / "pendulum.ejs.yaml", tmp_path / "pendulum")) as served:
        yield served


@pytest.mark.browser
def test_pendulum_in_the_browser(pendulum_app, page):
    app, url = pendulum_app
    page.goto(url)
    page.wait_for_selector("canvas", state="attached", timeout=45_000)
    page.get_by_text("Length (m)").first.wait_for(timeout=45_000)
    assert page.locator("canvas").first.bounding_box()["width"] > 300
    assert page.get_by_text("Damped pendulum", exact=True).first.is_visible()
    assert page.get_by_text("Damping", exact=True).first.is_visible()
    for name in ("Play", "Step", "Reset", "Kick"):
        assert page.get_by_role("button", name=name).first.is_visible(), name
    wait_until(lambda: page.get_by_text("Energy: 4.510 J").count() > 0, what="the interpolated energy label")
    page.screenshot(path=str(ARTIFACTS / "pendulum_loaded.png"))

    bob0 = app.world["bob"].T_world()[:3, 3].copy()
    before = settled(lambda: canvas_pixels(page), what="the first frames of the 3D view")  # before comparing pixels

    slider = page.get_by_role("slider").first
    slider.focus()
    slider.press("End")  # L to its maximum, 3.0 m
    wait_until(lambda: abs(app.model.L - 3.0) < 1e-9, what="L == 3.0 on the server after End on the slider")
    bob1 = app.world["bob"].T_world()[:3, 3]
    assert np.allclose(bob1, [3.0 * np.sin(1.0), 0.0, -3.0 * np.cos(1.0)])  # fixed relations ran, sphere moved
    assert np.linalg.norm(bob1 - bob0) > 1.0

    def moved_on_screen() -> bool:
        return np.mean(np.abs(canvas_pixels(page) - before) > 30) > 0.001

    wait_until(moved_on_screen, what="the bob to move on screen")

    page.get_by_role("button", name="Play").click()
    wait_until(lambda: app.model.t > 0.5, what="t > 0.5 after Play")
    assert app.is_playing()

    page.get_by_role("button", name="Reset").click()
    wait_until(lambda: app.model.t == 0.0 and not app.is_playing(), what="t == 0 after Reset")
    assert app.model.theta == 1.0 and app.model.L == 1.0
    page.screenshot(path=str(ARTIFACTS / "pendulum_after_reset.png"))
