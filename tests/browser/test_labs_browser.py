"""The paper's labs, built by ejsgen and served in-process, in a real browser (Debian's Chromium).

What a student does first in each lab: open it, see the arm and the panel, press Play and
watch things move. Each test checks that on the server (the arm's links move in the
world) and on screen (the 3D canvas changes), and that a screenshot is not empty; in the
visual-servoing lab, the camera image in the panel changes as the arm moves.

With ``EJSGEN_GALLERY=1`` in the environment the screenshots are also written, at 640x400,
to ``examples/gallery/<lab>.png`` (the pictures of ``examples/README.md``).
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np
import pytest
from PIL import Image

from testkit.browser import canvas_pixels, close_notifications, panel_image, save_shot, serving, wait_until


@dataclass
class Lab:
    spec: str  # name under examples/, for the ``built`` fixture
    title: str  # the app's title, shown in the panel
    button: str  # a button of the lab, to know the panel is there
    link: str  # a world node that moves when the lab plays
    play_for: float  # simulated seconds to wait for after Play
    play: str = "Play"  # the button that sets it going


LABS = {
    "six_axis_kinematics": Lab("paper/six_axis_kinematics", "Six-axis arm kinematics (paper lab 1)", "Solve and move", "arm.link6", 1.0),
    "path_planning_434": Lab("paper/path_planning_434", "Path planning (4-3-4 and friends)", "Plan and move", "puma.link6", 0.5),
    "inverse_dynamics_payload": Lab("paper/inverse_dynamics_payload", "Inverse dynamics with a payload", "Play", "puma.link6", 1.0),
    "visual_servoing_eih": Lab("paper/visual_servoing_eih", "Eye-in-hand visual servoing", "Restart", "puma.link6", 1.5),
    "pid_dc_motor_control": Lab("paper/pid_dc_motor_control", "PID control of a 3R arm with DC motors", "Restart", "rrr.link3", 0.6),
    "multi_robot_eih": Lab("paper/multi_robot_eih", "Multi-robot system with an eye-in-hand camera", "Play", "arm3.link3", 1.5),
    "pick_and_place": Lab("paper/pick_and_place", "Pick and place from a conveyor belt", "Stop program", "puma.link6", 2.0,
                          play="Run program"),
}


@pytest.fixture
def served(request, built):
    """The lab of the test's parameter, served on a free port: (lab, app, url)."""
    lab = LABS[request.param]
    with serving(built(lab.spec)) as (app, url):
        yield lab, app, url


@pytest.mark.browser
@pytest.mark.parametrize("served", list(LABS), indirect=True)
def test_lab_plays_in_the_browser(served, page):
    lab, app, url = served
    page.goto(url)
    page.wait_for_selector("canvas", state="attached", timeout=45_000)
    page.get_by_role("button", name=lab.button).first.wait_for(timeout=45_000)
    assert page.get_by_text(lab.title, exact=True).first.is_visible()
    assert page.locator("canvas").first.bounding_box()["width"] > 300
    close_notifications(page)
    servo = lab.spec.endswith("visual_servoing_eih")
    if servo:
        wait_until(lambda: panel_image(page).count() > 0, what="the camera image in the panel")
        picture0 = panel_image(page).screenshot()
        src0 = panel_image(page).get_attribute("src")

    link0 = app.world[lab.link].T_world().copy()
    before = canvas_pixels(page)

    page.get_by_role("button", name=lab.play).first.click()
    t0 = app.model.t
    wait_until(lambda: app.model.t > t0 + lab.play_for, what=f"t to advance {lab.play_for} s after Play")
    assert app.is_playing() and app.error is None

    # the arm moved in the world ...
    link1 = app.world[lab.link].T_world()
    assert np.linalg.norm(link1[:3, 3] - link0[:3, 3]) > 0.01 or np.abs(link1[:3, :3] - link0[:3, :3]).max() > 0.05
    # ... and on screen
    wait_until(lambda: np.mean(np.abs(canvas_pixels(page) - before).sum(axis=2) > 30) > 0.002, timeout=20,
               what="the 3D view to change")
    if servo:
        wait_until(lambda: panel_image(page).get_attribute("src") != src0, what="a new camera image")
        picture1 = np.asarray(Image.open(io.BytesIO(panel_image(page).screenshot())).convert("RGB")).astype(int)
        first = np.asarray(Image.open(io.BytesIO(picture0)).convert("RGB")).astype(int)
        assert picture1.shape == first.shape
        assert np.mean(np.abs(picture1 - first).sum(axis=2) > 60) > 0.02  # the square moved in the picture

    close_notifications(page)
    png = save_shot(page, request_name(lab))
    shot = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    assert shot.shape[0] >= 400 and shot.shape[1] >= 640
    assert shot.reshape(-1, 3).std(axis=0).max() > 20  # not a blank page


def request_name(lab: Lab) -> str:
    return lab.spec.split("/")[-1]
