"""The multi-robot lab (paper figure 15) run headless: the 3R arm's base follows the PA-10
link it is mounted on, its camera rides on the 3R tool, and the camera's view changes
as the arms move.

References: ``pa10().fkine_all`` from the CSV's joint values, and the same chain with
standard DH written out here from the PA-10's published table.
"""

from __future__ import annotations

import numpy as np
import pytest
from testkit.labs import LABS, dh_frames, headless, matrices, vector

from ejsrl.robotics import models

# PA-10 standard DH (d, a, alpha, offset): shoulder 0.317 m, upper arm 0.45 m, forearm 0.48 m, flange 0.07 m
PA10 = [(0.317, 0, -np.pi / 2, 0), (0, 0, np.pi / 2, 0), (0.45, 0, -np.pi / 2, 0), (0, 0, np.pi / 2, 0),
        (0.48, 0, -np.pi / 2, 0), (0, 0, np.pi / 2, 0), (0.07, 0, 0, 0)]
ARM3 = [(0.10, 0.0, np.pi / 2, 0), (0.0, 0.16, 0.0, 0), (0.0, 0.12, 0.0, 0)]


def ry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1.0]])


def rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


T_MOUNT = np.array([[1, 0, 0, -0.07], [0, 1, 0, 0], [0, 0, 1, 0.24], [0, 0, 0, 1.0]]) @ ry(-np.pi / 2)
T_TOOL_CAM = ry(np.pi / 2) @ rz(np.pi)


@pytest.fixture(scope="module")
def lab(built):
    return built(LABS["multi"])


def test_the_mounted_arm_and_its_camera_follow_the_pa10(lab):
    d = headless(lab, 4.0, vars="t,q1,q2,T_base,T_cam", every=5)
    q1, q2 = vector(d, "q1", 7), vector(d, "q2", 3)
    T_base, T_cam = matrices(d, "T_base"), matrices(d, "T_cam")
    assert np.ptp(q1[:, 0]) > 0.2 and np.ptp(q2[:, 0]) > 0.2  # the demo moves both arms
    travel = np.linalg.norm(T_base[:, :3, 3] - T_base[0, :3, 3], axis=1).max()
    assert travel > 0.1  # so the 3R arm's base travels with the PA-10's forearm
    link4 = models.pa10().fkine_all(q1)[:, 4]  # batched over the CSV rows
    np.testing.assert_allclose(T_base, link4 @ T_MOUNT, atol=1e-9)
    for k in range(len(q1)):
        written_out = dh_frames(q1[k], PA10)[4] @ T_MOUNT
        np.testing.assert_allclose(T_base[k], written_out, atol=1e-9)
        np.testing.assert_allclose(T_cam[k], T_base[k] @ dh_frames(q2[k], ARM3)[-1] @ T_TOOL_CAM, atol=1e-9)


def test_the_joints_follow_their_sliders_without_the_demo(lab):
    target1, target2 = [20, 40, -10, 70, 15, 30, 0], [60, 20, -50]
    d = headless(lab, 5.0, vars="t,q1,q2,T_base", every=10,
                 sets={"demo": "false", "q1_deg": str(target1), "q2_deg": str(target2)})
    np.testing.assert_allclose(vector(d, "q1", 7)[-1], np.radians(target1), atol=1e-3)
    np.testing.assert_allclose(vector(d, "q2", 3)[-1], np.radians(target2), atol=1e-3)
    T_base = matrices(d, "T_base")[-1]
    np.testing.assert_allclose(T_base, dh_frames(np.radians(target1), PA10)[4] @ T_MOUNT, atol=1e-3)


def test_the_camera_view_changes_as_the_arms_move(lab):
    from ejsrl.app import load_app
    from ejsrl.world.rendering import BACKGROUND

    app = load_app(lab)
    first = app.capture("eih")
    assert first.shape == (240, 320, 3)
    background = np.rint(np.array(BACKGROUND) * 255)
    assert np.mean(np.abs(first.astype(float) - background).sum(axis=2) > 30) > 0.3  # it sees the table
    assert app.run_headless(2.0) == 0
    later = app.capture("eih")
    assert np.mean(np.abs(later.astype(int) - first.astype(int)).sum(axis=2) > 30) > 0.05
