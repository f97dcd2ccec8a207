"""The six-axis kinematics lab (paper figures 4-7) run headless: the tool pose is the
product of the paper's DH matrices, and inverse kinematics followed by the joint motion
puts the tool on the target.

References: the DH product and the roll-pitch-yaw rotation written out here.
"""

from __future__ import annotations

import numpy as np
import pytest
from testkit.labs import LABS, dh_frames, headless, matrices, vector

# the paper's table (figure 4): (d, a, alpha, offset) with L1 = 0.45, A2 = 0.40, L4 = 0.40, L6 = 0.10
TABLE = [(0.45, 0.0, -np.pi / 2, np.pi / 2), (0.0, 0.40, 0.0, -np.pi / 2), (0.0, 0.0, np.pi / 2, np.pi),
         (0.40, 0.0, -np.pi / 2, 0.0), (0.0, 0.0, np.pi / 2, 0.0), (0.10, 0.0, 0.0, 0.0)]


def rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rz(yaw) Ry(pitch) Rx(roll) as a 4x4 rotation."""
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    T = np.eye(4)
    T[:3, :3] = Rz @ Ry @ Rx
    return T


def target(x, y, z, roll_deg, pitch_deg, yaw_deg) -> np.ndarray:
    T = rpy(*np.radians([roll_deg, pitch_deg, yaw_deg]))
    T[:3, 3] = [x, y, z]
    return T


@pytest.fixture(scope="module")
def lab(built):
    return built(LABS["kinematics"])


@pytest.mark.parametrize("goal", [
    {},  # the default target: (0.35, 0.35, 0.30) m, tool pointing down
    {"X": "-0.3", "Y": "0.45", "Z": "0.5", "roll_deg": "30", "pitch_deg": "150", "yaw_deg": "-40"},
])
def test_the_tool_reaches_the_target_through_the_dh_chain(lab, goal):
    d = headless(lab, 2.5, vars="t,q,T06,solved", every=5, sets=goal)
    q, T06 = vector(d, "q", 6), matrices(d, "T06")
    assert np.all(d["solved"] == 1)
    for k in range(len(q)):  # forward kinematics at every row: the paper's A01 A12 ... A56
        np.testing.assert_allclose(T06[k], dh_frames(q[k], TABLE)[-1], atol=1e-12)
    values = {"X": 0.35, "Y": 0.35, "Z": 0.30, "roll_deg": 0.0, "pitch_deg": 180.0, "yaw_deg": 0.0}
    values.update({k: float(v) for k, v in goal.items()})
    T_goal = target(*values.values())
    assert np.linalg.norm(T06[0, :3, 3] - T_goal[:3, 3]) > 0.1  # it starts elsewhere
    np.testing.assert_allclose(T06[-1], T_goal, atol=1e-6)  # and ends on the target (2 s motion)
    assert np.ptp(q, axis=0).max() > 0.2


def test_a_target_out_of_reach_is_reported_and_the_arm_stays(lab):
    d = headless(lab, 1.0, vars="t,q,solved", every=10, sets={"X": "1.5"})
    assert np.all(d["solved"] == 0)
    q = vector(d, "q", 6)
    np.testing.assert_allclose(q, np.tile(np.radians([0, 20, 35, 0, 35, 0]), (len(q), 1)), atol=1e-12)
