"""The marker-servoing lab in a real browser (Debian's Chromium): the camera picture the panel shows
holds ArUco marker 7 (found again by OpenCV's detector in the browser's own pixels), Play
servos the arm until the panel says Done with the camera truly within 3 mm of its goal
(the scene's ground truth), the point cloud is drawn in the 3D view when ticked, and asking for a
marker that is not there stops the servo and says so."""

from __future__ import annotations

import io
import re

import numpy as np
import pytest

from testkit.browser import canvas_pixels, close_notifications, panel_image, save_shot, serving, wait_until

LAB = "marker_servoing"


def _text(page) -> str:
    return page.locator("body").inner_text()


@pytest.mark.browser
def test_the_marker_lab_finds_servoes_and_shows_the_cloud(built, page):
    from PIL import Image

    from ejsrl.vision import detect_markers

    with serving(built(LAB)) as (app, url):
        page.goto(url)
        page.wait_for_selector("canvas", state="attached", timeout=45_000)
        page.get_by_role("button", name="Restart").wait_for(timeout=45_000)
        close_notifications(page)
        wait_until(lambda: "marker 7 found" in _text(page), what="the status line")
        # the point cloud: off at start (it would hide the marker); ticked, the orange points are drawn in the 3D view
        def orange() -> int:
            px = canvas_pixels(page)
            return int(((px[:, :, 0] > 200) & (np.abs(px[:, :, 1] - 165) < 45) & (px[:, :, 2] < 80)).sum())

        before = orange()  # the robot's own orange-ish shading
        assert len(app.model.cloud) == 0
        page.get_by_label("Show depth points").check()
        wait_until(lambda: len(app.model.cloud) > 1000 and orange() > before + 1000, what="the orange depth points")
        page.get_by_label("Show depth points").uncheck()
        wait_until(lambda: orange() < before + 100, what="the depth points hidden")

        page.get_by_role("button", name="Play").first.click()
        wait_until(lambda: bool(app.model.done), timeout=120, what="the servo to reach its goal")
        wait_until(lambda: "Done: the camera is at its goal pose" in _text(page), what="Done in the panel")
        really = float(re.search(r"really: ([0-9.]+) mm", _text(page)).group(1))
        assert really < 3.0 and app.model.true_err < 3.0
        save_shot(page, "marker_servoing")

        # follow marker 8, which is not in the scene: the servo stops and says so
        box = page.get_by_label("Marker id to follow")
        box.fill("8")
        box.press("Enter")
        wait_until(lambda: app.model.marker_id == 8, what="the marker id on the server")
        page.get_by_role("button", name="Restart").click()
        wait_until(lambda: "Marker 8 not in view: the servo has stopped" in _text(page), what="the lost marker")
        assert not app.model.found and np.all(app.model.qdot == 0)
        # the picture the browser shows (no corner circles now): OpenCV finds marker 7 in its pixels
        img = panel_image(page)

        def shown_ids() -> list[int]:
            shown = np.asarray(Image.open(io.BytesIO(img.screenshot())).convert("RGB"))
            return [m.id for m in detect_markers(shown, "aruco_4x4_50")]

        wait_until(lambda: shown_ids() == [7], what="marker 7 in the browser's picture")
        assert app.error is None
