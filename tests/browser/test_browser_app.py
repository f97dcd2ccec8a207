"""A hand-built app in a real browser: the panel, the 3D canvas, and the round trip to the model."""

from __future__ import annotations

import pytest

from testkit.browser_lab import make_app
from testkit.browser import ARTIFACTS, wait_until


# served_app comes first in the tests' arguments so that it is torn down after the page's
# screenshot is taken (with the server still up).
@pytest.fixture
def served_app():
    app = make_app()
    server = app.serve("127.0.0.1", 0, block=False)
    yield app, f"http://127.0.0.1:{server.get_port()}"
    app.stop()
    server.stop()


def open_app(page, url: str) -> None:
    page.goto(url)
    page.wait_for_selector("canvas", state="attached", timeout=45_000)
    page.get_by_text("Length").first.wait_for(timeout=45_000)


@pytest.mark.browser
def test_panel_scene_slider_play_and_reset(served_app, page):
    app, url = served_app
    open_app(page, url)

    # the 3D view and the panel's parts are there
    assert page.locator("canvas").count() >= 1
    assert page.locator("canvas").first.bounding_box()["width"] > 200
    for text in ("Pendulum", "Play", "Step", "Reset", "Break it"):
        assert page.get_by_text(text, exact=True).first.is_visible(), text

    # moving the slider in the browser changes the model's variable on the server
    slider = page.get_by_role("slider").first
    slider.focus()
    slider.press("ArrowRight")
    wait_until(lambda: abs(app.model.L - 1.1) < 1e-9, what="L == 1.1 after one step of the slider")
    slider.press("End")
    wait_until(lambda: abs(app.model.L - 2.0) < 1e-9, what="L == 2.0 after End on the slider")
    assert abs(app.model.x - 2.0 * __import__("math").sin(0.6)) < 1e-9  # the fixed relations ran

    # Play advances the independent variable; the button turns into Pause
    page.get_by_role("button", name="Play").click()
    wait_until(lambda: app.model.t > 0.3, what="t > 0.3 after Play")
    page.get_by_role("button", name="Pause").wait_for()
    page.get_by_text("t", exact=True).first.wait_for()

    # Reset returns to the initial state
    page.get_by_role("button", name="Reset").click()
    wait_until(lambda: app.model.t == 0.0 and app.model.L == 1.0 and not app.is_playing(), what="the initial state after Reset")
    wait_until(lambda: slider.get_attribute("aria-valuenow") == "1", what="the slider showing L = 1 again")


@pytest.mark.browser
def test_user_code_errors_are_shown_in_the_panel(served_app, page):
    app, url = served_app
    open_app(page, url)
    page.get_by_role("button", name="Break it").click()
    wait_until(lambda: app.error is not None, what="the error to be recorded")
    # the red box in the panel (the <b> heading) and a notification
    box = page.locator("b", has_text="Error at pendulum.ejs.yaml:27:7")
    box.wait_for()
    note = page.locator(".mantine-Notification-title", has_text="Error at pendulum.ejs.yaml:27:7")
    note.wait_for()
    assert "ZeroDivisionError" in page.content()
    assert not app.is_playing()
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / "error_shown.png"))
    page.get_by_role("button", name="Reset").click()
    box.wait_for(state="hidden")
    note.wait_for(state="detached")
    assert app.error is None
