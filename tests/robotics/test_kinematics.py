"""Forward kinematics and Jacobians against finite differences and Robotics Toolbox values."""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.robotics import Link, Robot, models
from ejsrl.robotics.transforms import vex

from testkit.robotics import ALL_MODELS, random_q, with_base_tool


def fd_jacob0(robot: Robot, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """World-frame geometric Jacobian by central differences of fkine."""
    J = np.zeros((6, robot.n))
    T = robot.fkine(q)
    for j in range(robot.n):
        dq = np.zeros(robot.n)
        dq[j] = h
        Tp, Tm = robot.fkine(q + dq), robot.fkine(q - dq)
        J[:3, j] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        dR = (Tp[:3, :3] - Tm[:3, :3]) / (2 * h)
        J[3:, j] = vex(dR @ T[:3, :3].T)
    return J


@pytest.mark.parametrize("name", ALL_MODELS)
def test_jacobians_match_finite_differences(name):
    robot = with_base_tool(ALL_MODELS[name]())
    rng = np.random.default_rng(7)
    for q in random_q(robot, rng, 5):
        J0 = robot.jacob0(q)
        np.testing.assert_allclose(J0, fd_jacob0(robot, q), atol=1e-7)
        R = robot.fkine(q)[:3, :3]
        Je = robot.jacobe(q)
        np.testing.assert_allclose(np.vstack((R @ Je[:3], R @ Je[3:])), J0, atol=1e-12)


@pytest.mark.parametrize("name", ALL_MODELS)
def test_batched_kinematics_equal_single_calls(name):
    robot = with_base_tool(ALL_MODELS[name]())
    Q = random_q(robot, np.random.default_rng(3), 7)
    T = robot.fkine(Q)
    J = robot.jacob0(Q)
    F = robot.fkine_all(Q)
    assert T.shape == (7, 4, 4) and J.shape == (7, 6, robot.n) and F.shape == (7, robot.n + 1, 4, 4)
    for k, q in enumerate(Q):
        np.testing.assert_allclose(T[k], robot.fkine(q), atol=1e-14)
        np.testing.assert_allclose(J[k], robot.jacob0(q), atol=1e-14)
        # frame n of fkine_all composed with the tool is the end-effector pose
        np.testing.assert_allclose(F[k, -1] @ robot.tool, T[k], atol=1e-14)
        np.testing.assert_allclose(F[k, 0], robot.base, atol=0)


def test_fkine_all_composes_link_transforms():
    robot = with_base_tool(models.stanford())
    q = robot.qr
    F = robot.fkine_all(q)
    T = robot.base.copy()
    for i, link in enumerate(robot.links):
        T = T @ link.A(q[i])
        np.testing.assert_allclose(F[i + 1], T, atol=1e-14)


@pytest.mark.parametrize("pose", ["qz", "qr", "qn", "qs"])
def test_puma560_matches_toolbox_kinematics(puma_ref, pose):
    ref = puma_ref["poses"][pose]
    p = models.puma560()
    np.testing.assert_allclose(p.fkine(ref["q"]), ref["fkine"], atol=1e-12)
    np.testing.assert_allclose(p.jacob0(ref["q"]), ref["jacob0"], atol=1e-12)
    np.testing.assert_allclose(getattr(p, pose), ref["q"])
    np.testing.assert_allclose(p.poses[pose], ref["q"])


def test_puma560_published_zero_pose():
    """Corke, Robotics, Vision and Control (2nd ed.), sec. 7.2: p560.fkine(qz) has the tool
    at (0.4521, -0.1500, 0.4318) m above the shoulder, which is 0.67183 m up the pedestal."""
    p = models.puma560()
    np.testing.assert_allclose(p.fkine(p.qz)[:3, 3], [0.4521, -0.15005, 0.4318 + 0.67183], atol=1e-9)


def test_manipulability_is_zero_at_a_singularity_and_positive_elsewhere():
    p = models.puma560()
    assert p.manipulability(p.qz) < 1e-12  # wrist singular: q5 = 0
    assert p.manipulability(p.qn) > 1e-3
    two = models.planar(2)
    q = np.array([0.3, 0.9])
    # closed form for a 2-link planar arm: |a1 a2 sin(q2)|
    assert two.manipulability(q, axes="trans") == pytest.approx(0.0)  # z row is zero
    J = two.jacob0(q)[:2]
    assert np.sqrt(np.linalg.det(J @ J.T)) == pytest.approx(abs(np.sin(0.9)))


def test_contract_attributes_and_repr():
    p = models.puma560()
    assert p.n == 6 and len(p.links) == 6 and p.qlim.shape == (2, 6)
    assert "0.67183" in repr(p) and "0.15005" in repr(p) and "Puma 560" in repr(p)
    for make in (models.puma560, models.stanford, models.pa10, models.ur5, models.rrr, models.scara):
        r = make()
        assert {"qz", "qr"} <= set(r.poses)
        assert r.reach > 0.3
        assert r.link_lengths().shape == (r.n, 2)
    assert models.pa10().n == 7
    # the reach bounds every reachable point (from the first joint axis)
    p = models.puma560()
    pts = p.fkine(random_q(p, np.random.default_rng(0), 500))[:, :3, 3]
    assert np.linalg.norm(pts, axis=1).max() <= p.reach


def test_link_edit_is_seen_by_the_robot():
    r = Robot([Link(a=1.0), Link(a=1.0)])
    assert r.fkine([0, 0])[0, 3] == pytest.approx(2.0)
    r.links[1].a = 0.5
    assert r.fkine([0, 0])[0, 3] == pytest.approx(1.5)
    with pytest.raises(ValueError, match="expected 2 joint values"):
        r.fkine([0, 0, 0])
