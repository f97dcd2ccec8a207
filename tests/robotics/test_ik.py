"""Inverse kinematics: success rate and accuracy on random reachable targets, honest
failure on unreachable ones, and the closed-form Puma solver."""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.robotics import models
from ejsrl.robotics.ik import ikine_a_all, pose_error
from ejsrl.robotics.transforms import transl

from testkit.robotics import random_q, with_base_tool


@pytest.mark.parametrize(("make", "count"), [(models.puma560, 1000), (models.stanford, 1000), (models.ur5, 1000),
                                             (models.pa10, 200)])
def test_ikine_solves_random_reachable_targets(make, count):
    robot = with_base_tool(make())
    rng = np.random.default_rng(2024)
    targets = robot.fkine(random_q(robot, rng, count))
    ok = 0
    lim = robot.qlim
    for T in targets:
        sol = robot.ikine(T)
        if sol.success:
            ok += 1
            e = pose_error(T, robot.fkine(sol.q))
            assert np.linalg.norm(e[:3]) < 1e-9 and np.linalg.norm(e[3:]) < 1e-9
            assert np.all(sol.q >= lim[0] - 1e-12) and np.all(sol.q <= lim[1] + 1e-12)
            assert sol.iterations >= 0 and sol.residual < 1e-9
    assert ok / count >= 0.995, f"{robot.name}: success {ok}/{count}"


def test_ikine_reports_unreachable_targets_honestly():
    p = models.puma560()
    sol = p.ikine(transl(2.0, 0.0, 0.5), slimit=20)
    assert not sol.success
    assert "reach" in sol.reason
    assert sol.residual > 0.5
    # reachable position but forbidden by the joint limits of q2 and q3: arm pointing down
    p.links[1].qlim = np.array([0.0, 0.1])
    p.links[2].qlim = np.array([-0.1, 0.0])
    T = models.puma560().fkine([0, -1.2, 0.8, 0, 0.5, 0])
    assert not p.ikine(T, slimit=10).success


def test_ikine_with_a_mask_for_a_planar_arm():
    arm = models.planar(3)
    goal_q = np.array([0.4, -0.7, 1.1])
    T = arm.fkine(goal_q)
    sol = arm.ikine(T, mask=[1, 1, 0, 0, 0, 1])
    assert sol.success
    e = pose_error(T, arm.fkine(sol.q))
    assert np.abs(e[[0, 1, 5]]).max() < 1e-9
    two = models.planar(2)
    T2 = two.fkine([0.3, 1.0]) @ np.diag([1.0, -1.0, -1.0, 1.0])  # orientation it cannot reach
    sol2 = two.ikine(T2, mask=[1, 1, 0, 0, 0, 0])
    assert sol2.success
    np.testing.assert_allclose(two.fkine(sol2.q)[:2, 3], T2[:2, 3], atol=1e-9)
    assert not two.ikine(T2, slimit=5).success  # unmasked: orientation is unreachable


def test_ikine_starts_from_q0_and_returns_the_nearby_solution():
    p = models.puma560()
    q = p.qn + 0.05
    sol = p.ikine(p.fkine(q), q0=p.qn)
    assert sol.success and sol.searches == 1
    np.testing.assert_allclose(sol.q, q, atol=1e-8)


def test_closed_form_puma_reproduces_the_pose_in_all_8_configurations():
    p = with_base_tool(models.puma560())
    rng = np.random.default_rng(5)
    for q in random_q(p, rng, 100):
        T = p.fkine(q)
        sols, confs = ikine_a_all(p, T)
        assert len(sols) == 8 and len(set(confs)) == 8
        for s in sols:
            np.testing.assert_allclose(p.fkine(s), T, atol=1e-9)
        # the 8 configurations are distinct joint vectors, one of them the original
        assert len({tuple(np.round(s, 6)) for s in sols}) == 8
        d = np.abs(np.angle(np.exp(1j * (sols - q)))).max(axis=1)
        assert d.min() < 1e-7
    sol = p.ikine_a(p.fkine(p.qn), "rdf")
    assert sol.success
    np.testing.assert_allclose(p.fkine(sol.q), p.fkine(p.qn), atol=1e-9)
    assert not p.ikine_a(transl(3.0, 0, 0)).success
    with pytest.raises(ValueError, match="Puma-type"):
        models.ur5().ikine_a(np.eye(4))
