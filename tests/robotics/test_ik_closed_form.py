"""Closed-form inverse kinematics: ``ikine_a`` answers with Robotics Toolbox's
configuration labels (fixture recorded from RTB 1.5), checks its own residual, and
``ikine`` meets its accuracy, joint-limit and singularity targets on the arms that have a
closed form (Puma 560, UR5, PA-10) as well as rejecting unreachable poses honestly."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ejsrl.robotics import models
from ejsrl.robotics.ik import ikine_a_all, pose_error
from ejsrl.robotics.transforms import transl

from testkit.robotics import FIXTURES, random_q, with_base_tool

RTB = json.loads((FIXTURES / "puma560_rtb_ik_friction.json").read_text())
CONFIGS = ["lun", "ldn", "luf", "ldf", "run", "rdn", "ruf", "rdf"]


def _angle_diff(a, b):
    return np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))))


def _reached(robot, T, q, tol=1e-10):
    e = pose_error(T, robot.fkine(q))
    return np.linalg.norm(e[:3]) < tol and np.linalg.norm(e[3:]) < tol


@pytest.mark.parametrize("config", CONFIGS)
def test_ikine_a_labels_are_the_toolbox_labels(config):
    p = models.puma560()
    for case in RTB["ikine_a"]:
        T = np.array(case["T"])
        sol = p.ikine_a(T, config)
        assert sol.success, sol.reason
        assert _angle_diff(sol.q, case["solutions"][config]).max() < 1e-8, (config, sol.q, case["solutions"][config])
        assert _reached(p, T, sol.q)


def test_ikine_a_defaults_missing_letters_as_the_toolbox():
    p = models.puma560()
    T = np.array(RTB["ikine_a"][0]["T"])
    sols = RTB["ikine_a"][0]["solutions"]
    assert _angle_diff(p.ikine_a(T).q, sols["lun"]).max() < 1e-8
    assert _angle_diff(p.ikine_a(T, "r").q, sols["run"]).max() < 1e-8
    assert _angle_diff(p.ikine_a(T, "fd").q, sols["ldf"]).max() < 1e-8
    with pytest.raises(ValueError, match="unknown configuration letter"):
        p.ikine_a(T, "rux")


def test_ikine_a_all_labels_match_ikine_a():
    p = with_base_tool(models.puma560())
    T = p.fkine([0.3, 0.4, -0.2, 0.5, -0.7, 1.0])
    sols, confs = ikine_a_all(p, T)
    assert sorted(confs) == sorted(CONFIGS)
    for q, c in zip(sols, confs):
        np.testing.assert_allclose(p.ikine_a(T, c).q, q, atol=1e-12)


def test_ikine_a_reports_a_solution_that_misses_the_pose():
    """Just beyond the reach the elbow's arccos is clipped (round-off); the solution then
    misses by ~1e-10 m and must say so rather than succeed."""
    p = models.puma560()
    T = p.fkine([0.3, 0.4, -0.2, 0.5, -0.7, 1.0])
    shoulder = np.array([0.0, 0.0, 0.0])  # the Puma's shoulder is at the base origin (d1 = 0)

    def at(scale):
        Ts = T.copy()
        Ts[:3, 3] = shoulder + scale * (T[:3, 3] - shoulder)
        return Ts

    lo, hi = 1.0, 3.0  # reachable at lo, not at hi
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if np.isfinite(p.ikine_a(at(mid), "run").q).all() else (lo, mid)
    sol = p.ikine_a(at(lo), "run")
    assert not sol.success
    assert "misses the pose" in sol.reason
    assert 1e-10 < sol.pos_error < 1e-6
    assert p.ikine_a(at(lo), "run", tol=1e-6).success
    far = p.ikine_a(at(hi * 1.01), "rdn")
    assert not far.success and "out of reach" in far.reason


# ---------------------------------------------------------------------------- ikine targets
ARMS = [models.puma560, models.ur5, models.pa10]


@pytest.mark.parametrize("make", ARMS)
def test_ikine_reaches_1000_random_targets_to_1e_10_within_the_limits(make):
    robot = with_base_tool(make())
    rng = np.random.default_rng(14)
    targets = robot.fkine(random_q(robot, rng, 1000))
    lim = robot.qlim
    ok = 0
    for T in targets:
        sol = robot.ikine(T)
        assert np.all(sol.q >= lim[0]) and np.all(sol.q <= lim[1]), sol.q
        if sol.success:
            assert _reached(robot, T, sol.q), pose_error(T, robot.fkine(sol.q))
            ok += 1
    assert ok >= 999, f"{robot.name}: {ok}/1000"


@pytest.mark.parametrize("make", ARMS)
@pytest.mark.parametrize("q5", [0.0, 1e-7, 1e-4])
def test_ikine_is_robust_at_and_near_the_wrist_singularity(make, q5):
    robot = make()
    rng = np.random.default_rng(15)
    Q = random_q(robot, rng, 200)
    wrist = [4] if robot.n == 6 else [4, 5]  # PA-10: joint 5 as stated, and its wrist pitch, joint 6
    lim = robot.qlim
    for j in wrist:
        Qs = Q.copy()
        Qs[:, j] = q5
        for T in robot.fkine(Qs):
            sol = robot.ikine(T)
            assert sol.success, sol.reason
            assert _reached(robot, T, sol.q)
            assert np.all(sol.q >= lim[0]) and np.all(sol.q <= lim[1])


@pytest.mark.parametrize("make", ARMS + [models.stanford])
def test_ikine_rejects_an_out_of_reach_pose_at_once(make):
    robot = make()
    sol = robot.ikine(transl(3.0, 1.0, 0.5))
    assert not sol.success
    assert "out of reach" in sol.reason
    assert sol.searches <= 1  # no random restarts
    assert sol.pos_error > 1.0


def test_ikine_takes_the_closed_form_solution_nearest_q0():
    p = models.puma560()
    T = p.fkine([0.3, 0.4, -0.2, 0.5, -0.7, 1.0])
    sols, _ = ikine_a_all(p, T)
    lim = p.qlim
    inside = [q for q in sols if np.all(q >= lim[0]) and np.all(q <= lim[1])]
    assert len(inside) >= 4
    for q0 in inside:
        sol = p.ikine(T, q0=q0 + 0.01)
        assert sol.success
        assert _angle_diff(sol.q, q0).max() < 1e-8


def test_ikine_on_a_7r_arm_finds_a_solution_when_q0s_joint_3_cannot_reach():
    arm = models.pa10()
    q = np.array([0.4, 1.2, 2.5, 1.0, 0.3, -0.8, 0.2])  # q3 far from q0's
    T = arm.fkine(q)
    sol = arm.ikine(T, q0=np.zeros(7))
    assert sol.success, sol.reason
    assert _reached(arm, T, sol.q)
    lim = arm.qlim
    assert np.all(sol.q >= lim[0]) and np.all(sol.q <= lim[1])


def test_ikine_without_closed_form_still_solves():
    p = models.puma560()
    rng = np.random.default_rng(16)
    targets = p.fkine(random_q(p, rng, 100))
    ok = sum(p.ikine(T, closed_form=False).success for T in targets)
    assert ok >= 99


@pytest.mark.parametrize(("make", "joint"), [(models.puma560, 1), (models.ur5, 2), (models.pa10, 3)])
def test_ikine_with_joint_offsets_on_a_moved_base_and_tool(make, joint):
    robot = with_base_tool(make())
    robot.links[joint].offset = 0.3
    robot.links[0].offset = -0.2
    rng = np.random.default_rng(17)
    for T in robot.fkine(random_q(robot, rng, 100)):
        sol = robot.ikine(T)
        assert sol.success, sol.reason
        assert _reached(robot, T, sol.q)


@pytest.mark.parametrize(("make", "joint", "straight"), [(models.puma560, 2, -1.5238183), (models.ur5, 2, 0.0),
                                                         (models.pa10, 3, 0.0)])
@pytest.mark.parametrize("dq", [0.0, 1e-7, 1e-4])
def test_ikine_is_robust_at_and_near_a_straight_elbow(make, joint, straight, dq):
    robot = make()
    rng = np.random.default_rng(18)
    Q = random_q(robot, rng, 50)
    Q[:, joint] = straight + dq
    for T in robot.fkine(Q):
        sol = robot.ikine(T)
        assert sol.success, sol.reason
        assert _reached(robot, T, sol.q)


def test_ikine_says_when_a_reachable_pose_has_no_solution_within_the_limits():
    p = models.puma560()
    p.links[1].qlim = np.array([0.0, 0.1])
    p.links[2].qlim = np.array([-0.1, 0.0])
    T = models.puma560().fkine([0, -1.2, 0.8, 0, 0.5, 0])
    sol = p.ikine(T)
    assert not sol.success
    assert "no solution within the joint limits" in sol.reason
    lim = p.qlim
    assert np.all(sol.q >= lim[0]) and np.all(sol.q <= lim[1])


def test_ikine_searches_on_when_closed_form_seeds_do_not_polish(monkeypatch):
    """The safety net: should no seed within the limits polish to tol, the LM search takes
    over (simulated by a polish that always gives up)."""
    from ejsrl.robotics import ik

    def give_up(self, q, ilimit):
        e = [1.0] * 6
        return q, e, 3.0, 0, False

    monkeypatch.setattr(ik._Problem, "polish", give_up)
    p = models.puma560()
    T = p.fkine([0.3, 0.4, -0.2, 0.5, -0.7, 1.0])
    sol = p.ikine(T)
    assert sol.success and _reached(p, T, sol.q)


def _dh_arm(a, d, alpha, qlim, name):
    from ejsrl.robotics import Robot, RevoluteDH

    return Robot([RevoluteDH(a=a[j], d=d[j], alpha=alpha[j], qlim=qlim[j]) for j in range(len(a))], name=name)


def test_ikine_closed_form_covers_other_arms_of_the_families():
    """UR10 and KUKA LWR-IV (alpha signs other than the PA-10's, one-sided elbow and wrist
    limits), with the DH tables of Robotics Toolbox's ``models.DH.UR10`` and ``LWR4``."""
    h = np.pi / 2
    ur10 = _dh_arm([0, -0.612, -0.5723, 0, 0, 0], [0.1273, 0, 0, 0.163941, 0.1157, 0.0922],
                   [h, 0, 0, h, -h, 0], [[-2 * np.pi, 2 * np.pi]] * 6, "UR10")
    lwr = _dh_arm([0] * 7, [0, 0, 0.40, 0, 0.39, 0, 0], [h, -h, -h, h, h, -h, 0],
                  [[-2.8973, 2.8973], [-1.7628, 1.7628], [-2.8973, 2.8973], [-3.0718, -0.0698],
                   [-2.8973, 2.8973], [-0.0175, 3.7525], [-2.8973, 2.8973]], "LWR-IV")
    for arm in (ur10, lwr):
        arm.tool = transl(0, 0, 0.103)
        rng = np.random.default_rng(19)
        lim = arm.qlim
        for T in arm.fkine(random_q(arm, rng, 200)):
            sol = arm.ikine(T)
            assert sol.success, (arm.name, sol.reason)
            assert _reached(arm, T, sol.q)
            assert np.all(sol.q >= lim[0]) and np.all(sol.q <= lim[1])
