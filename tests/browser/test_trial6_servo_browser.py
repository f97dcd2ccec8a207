"""The visual-servoing lab in a real browser (Debian's Chromium), as a new user's trial drove it.

1. The start sliders dragged (with the keyboard) to q1 = 0, q5 = -10, q6 = -200 lose the
   square: the panel says so in words that stay (target lost, how many corners, the servo
   stopped, what to do), shows a dash, not "0.00 px", for the error, and Reset brings the
   default start back, servoing again.
2. The goal turned 180 degrees about the optical axis (Chaumette's case): after Play, the
   retreat warning is in the panel and stays there after the alert is gone.
"""

from __future__ import annotations

import re

import pytest

from testkit.browser import close_notifications, serving, wait_until
from testkit import ARTIFACTS

LAB = "paper/visual_servoing_eih"


def _text(page) -> str:
    return page.locator("body").inner_text()


def _open(page, url: str) -> None:
    page.goto(url)
    page.wait_for_selector("canvas", state="attached", timeout=45_000)
    page.get_by_role("button", name="Restart").wait_for(timeout=45_000)
    close_notifications(page)


def _key(page, app, index: int, key: str, done) -> None:
    """Press ``key`` on the ``index``-th slider of the panel until the server has the value."""
    slider = page.get_by_role("slider").nth(index)
    for _attempt in range(3):  # a key press can be lost on a loaded machine
        slider.focus()
        slider.press(key)
        try:
            wait_until(done, timeout=15, what=f"slider {index} at its {key} on the server")
            return
        except AssertionError:
            print("slider", index, "shown", slider.get_attribute("aria-valuenow"))
    raise AssertionError(f"slider {index}'s {key} never reached the server")


@pytest.mark.browser
def test_a_lost_target_is_said_plainly_and_reset_brings_it_back(built, page):
    with serving(built(LAB)) as (app, url):
        _open(page, url)
        wait_until(lambda: "Servoing: the corners are moving" in _text(page), what="the status line")
        page.get_by_text("Start configuration", exact=True).first.click()
        wait_until(lambda: page.get_by_role("slider").count() >= 10, what="the start sliders")
        # sliders: gain, tolerance, size, goal turn, then q1 .. q6
        _key(page, app, 4, "Home", lambda: app.model.q_start_deg[0] == 0)
        _key(page, app, 8, "End", lambda: app.model.q_start_deg[4] == -10)
        _key(page, app, 9, "Home", lambda: app.model.q_start_deg[5] == -200)
        page.get_by_role("button", name="Play").first.click()
        wait_until(lambda: app.model.t > 1.0, timeout=60, what="a second of servoing")
        app.pause()
        found = app.model.found
        assert found < 4
        wait_until(lambda: f"Target lost: {found} of 4 corners found" in _text(page), what="the lost-target status")
        close_notifications(page)  # the alert is gone: the status stays
        page.wait_for_timeout(1000)
        text = _text(page)
        assert "the servo has stopped" in text and "start sliders" in text and "press Reset" in text
        assert re.search(r"error: –\s+\|v\| = –", text), text
        assert "0.00 px" not in text
        page.screenshot(path=str(ARTIFACTS / "trial6_servo_lost.png"))
        # the red circles: only the corners found
        assert app.model.seen.shape == (found, 2)

        page.get_by_role("button", name="Reset").first.click()
        wait_until(lambda: list(app.model.q_start_deg) == [34, 45, -182, 8, -48, -135], what="the default start")
        wait_until(lambda: "Servoing: the corners are moving" in _text(page), what="servoing again after Reset")
        assert "Target lost" not in _text(page)
        assert app.error is None


@pytest.mark.browser
def test_the_half_turn_goal_shows_the_retreat_warning(built, page):
    with serving(built(LAB)) as (app, url):
        _open(page, url)
        _key(page, app, 3, "End", lambda: app.model.goal_turn == 180)
        page.get_by_role("button", name="Play").first.click()
        wait_until(lambda: "camera is retreating" in _text(page), timeout=90, what="the retreat warning")
        close_notifications(page)
        wait_until(lambda: app.model.t > 2.0, timeout=90, what="two seconds of the run")
        text = _text(page)
        assert "camera is retreating" in text and "stopped the arm" in text and "PBVS" in text
        page.screenshot(path=str(ARTIFACTS / "trial6_servo_retreat.png"))
        assert app.error is None
