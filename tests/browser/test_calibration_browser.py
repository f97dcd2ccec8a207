"""Lab 9, camera calibration, in a real browser (Debian's Chromium): a student presses
Capture (the view count goes up, no estimate yet), then Take the tour; the board's views
are captured one by one and the estimated fx, fy, cx, cy appear in the panel, within 1 %
(fx, fy) and 2 px (cx, cy) of the true camera's.

With ``EJSGEN_GALLERY=1`` the screenshot is also written to
``examples/gallery/camera_calibration.png`` (the picture of ``examples/README.md``).
"""

from __future__ import annotations

import io
import re

import numpy as np
import pytest
from PIL import Image

from testkit.browser import close_notifications, panel_image, save_shot, serving, wait_until

FX, FY, CX, CY = 610.0, 605.0, 326.0, 244.0  # the lab's true camera


def _panel_text(page) -> str:
    return page.locator("body").inner_text()


@pytest.mark.browser
def test_capture_and_tour_show_the_estimate(built, page):
    with serving(built("camera_calibration")) as (app, url):
        page.goto(url)
        page.wait_for_selector("canvas", state="attached", timeout=45_000)
        page.get_by_role("button", name="Capture", exact=True).wait_for(timeout=45_000)
        assert page.get_by_text("Camera calibration with a chessboard", exact=True).first.is_visible()
        close_notifications(page)
        wait_until(lambda: panel_image(page).count() > 0, what="the camera's view in the panel")
        first = np.asarray(Image.open(io.BytesIO(panel_image(page).screenshot())).convert("RGB")).astype(int)
        # the board is in the camera's view: dark squares and light ones
        grey = first.mean(axis=2)
        assert (grey < 60).mean() > 0.02 and (grey > 150).mean() > 0.3

        page.get_by_role("button", name="Capture", exact=True).click()
        wait_until(lambda: "Views: 1" in _panel_text(page), what="the first view to be counted")
        assert "view 1 added" in _panel_text(page)
        assert re.search(r"fx = \u2013 px", _panel_text(page)), "no estimate from one view: a dash, not nan"
        assert not re.search(r"\bnan\b", _panel_text(page))

        page.get_by_role("button", name="Take the tour").click()
        wait_until(lambda: app.model.tour_index == 12 and not app.is_playing(), timeout=90, what="the tour to end")
        assert app.error is None
        wait_until(lambda: "Views: 13" in _panel_text(page), what="13 views in the panel")
        text = _panel_text(page)
        fx, fy = (float(v) for v in re.search(r"fx = ([\d.]+) px .*fy = ([\d.]+) px", text).groups())
        cx, cy = (float(v) for v in re.search(r"cx = ([\d.]+) px .*cy = ([\d.]+) px", text).groups())
        assert abs(fx - FX) / FX < 0.01 and abs(fy - FY) / FY < 0.01, (fx, fy)
        assert abs(cx - CX) < 2.0 and abs(cy - CY) < 2.0, (cx, cy)
        rms = float(re.search(r"Reprojection error: ([\d.]+) px", text).group(1))
        assert 0.0 < rms < 0.3

        close_notifications(page)
        png = save_shot(page, "camera_calibration")
        shot = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
        assert shot.reshape(-1, 3).std(axis=0).max() > 20  # not a blank page
