"""The Toolbox's Jacobian and dynamics extras: against Robotics Toolbox for Python on its
Puma 560 (recorded in fixtures/dynamics_extras_rtb.json by fixtures/make_dynamics_extras_rtb.py),
finite differences, and second methods (energy, static balance, SVD)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ejsrl.robotics import Robot, load_urdf, models
from ejsrl.world.collision import CollisionShape
from testkit.robotics import FIXTURES

REF = json.loads((FIXTURES / "dynamics_extras_rtb.json").read_text())
TLIM = [97.6, 186.4, 89.4, 24.2, 20.1, 21.3]


def _arms() -> list[Robot]:
    return [models.puma560(), models.stanford(), load_urdf(FIXTURES / "urdf_test_arm.urdf")]


def test_extras_match_the_toolbox_on_the_puma560() -> None:
    puma = models.puma560()
    for row in REF["rows"]:
        q, qd, qdd = (np.array(row[k]) for k in ("q", "qd", "qdd"))
        np.testing.assert_allclose(puma.hessian0(q), row["hessian0"], atol=1e-13)
        np.testing.assert_allclose(puma.jacob0_dot(q, qd), row["jacob0_dot"], atol=1e-13)
        np.testing.assert_allclose(puma.jacobm(q), row["jacobm"], atol=1e-13)
        np.testing.assert_allclose(puma.jacobm(q, axes="trans"), row["jacobm_trans"], atol=1e-13)
        np.testing.assert_allclose(puma.itorque(q, qdd), row["itorque"], atol=1e-12)
        ref = np.array(row["payload_capacity"], dtype=float)
        np.testing.assert_allclose(puma.payload_capacity(q, TLIM, [0, 0, -1, 0, 0, 0]), ref, rtol=1e-10)


def test_fdyn_matches_the_toolboxs_integration() -> None:
    f = REF["fdyn"]
    puma = models.puma560()
    for link in puma.links:  # as RTB's nofriction(coulomb=True): no Coulomb friction, viscous kept
        link.Tc = np.zeros(2)
    tr = puma.fdyn(f["T"], f["q0"], dt=f["dt"])
    np.testing.assert_allclose(tr.t, f["t"], atol=1e-15)
    np.testing.assert_allclose(tr.q, f["q"], atol=1e-9)
    np.testing.assert_allclose(tr.qd, f["qd"], atol=1e-8)


@pytest.mark.parametrize("arm", range(3))
def test_hessian_and_jacobian_rate_against_finite_differences(arm: int) -> None:
    robot = _arms()[arm]
    rng = np.random.default_rng(arm)
    q = rng.uniform(-1, 1, robot.n)
    q = np.clip(q, robot.qlim[0] + 0.05, robot.qlim[1] - 0.05)
    qd = rng.uniform(-1, 1, robot.n)
    H = robot.hessian0(q)
    eps = 1e-6
    for j in range(robot.n):
        dq = np.zeros(robot.n)
        dq[j] = eps
        np.testing.assert_allclose(H[j], (robot.jacob0(q + dq) - robot.jacob0(q - dq)) / (2 * eps), atol=1e-8)
    Jdot = (robot.jacob0(q + eps * qd) - robot.jacob0(q - eps * qd)) / (2 * eps)
    np.testing.assert_allclose(robot.jacob0_dot(q, qd), Jdot, atol=1e-8)
    np.testing.assert_allclose(robot.hessian0(np.array([q, q]))[1], H, atol=0)  # batches too
    axes = "all" if robot.n == 6 else "trans"  # a 5-joint arm has no 6-D manipulability
    m = lambda x: robot.manipulability(x, axes=axes)  # noqa: E731
    grad = [(m(q + eps * e) - m(q - eps * e)) / (2 * eps) for e in np.eye(robot.n)]
    np.testing.assert_allclose(robot.jacobm(q, axes=axes)[:, 0], grad, atol=1e-8)
    assert np.max(np.abs(grad)) > 1e-4


def test_fdyn_conserves_the_energy_of_an_unforced_frictionless_arm() -> None:
    robot = models.planar(2, vertical=True)  # uniform rods under gravity, no friction

    def energy(q: np.ndarray, qd: np.ndarray) -> float:
        F = robot.fkine_all(q)
        pot = sum(-robot.links[i].m * robot.gravity @ (F[i + 1][:3, :3] @ robot.links[i].r + F[i + 1][:3, 3])
                  for i in range(robot.n))
        return 0.5 * qd @ robot.inertia(q) @ qd + pot

    tr = robot.fdyn(2.0, [0.6, -0.4], solver="DOP853", solver_args={"rtol": 1e-11, "atol": 1e-12})
    E = [energy(q, qd) for q, qd in zip(tr.q, tr.qd)]
    assert np.ptp(E) < 1e-7 * abs(E[0]) + 1e-8
    assert np.ptp(tr.q[:, 0]) > 0.5  # it really swung
    # a torque function holds it still: gravity compensation
    hold = robot.fdyn(0.5, [0.6, -0.4], Q=lambda r, t, q, qd: r.gravload(q))
    np.testing.assert_allclose(hold.q[-1], [0.6, -0.4], atol=1e-9)


def test_cinertia_gives_the_same_kinetic_energy_in_task_space() -> None:
    for robot in (models.puma560(), models.ur5_urdf()):
        q = np.array([0.3, -0.8, 1.1, -0.4, 0.7, 0.2])
        qd = np.array([0.5, -0.2, 0.4, 1.0, -0.6, 0.3])
        nu = robot.jacob0(q) @ qd
        Mx = robot.cinertia(q)
        np.testing.assert_allclose(0.5 * nu @ Mx @ nu, 0.5 * qd @ robot.inertia(q) @ qd, rtol=1e-10)
        np.testing.assert_allclose(Mx, Mx.T, atol=1e-9)
    with pytest.raises(ValueError, match="needs a 6-joint arm"):
        models.planar(2).cinertia([0.1, 0.2])


def test_gravjac_is_a_second_way_to_the_gravity_load() -> None:
    for robot in _arms():
        robot.payload(1.5, [0.0, 0.02, 0.05])
        q = np.clip(np.linspace(-0.7, 0.9, robot.n), robot.qlim[0] + 0.01, robot.qlim[1] - 0.01)
        tau, J = robot.gravjac(q)
        np.testing.assert_allclose(tau, robot.gravload(q), atol=1e-12)
        np.testing.assert_allclose(J, robot.jacob0(q), atol=0)


def test_paycap_holds_exactly_the_limit_load() -> None:
    puma = models.puma560()
    q = np.array([0.0, -0.5, 0.3, 0.0, 0.4, 0.0])
    w = np.array([0.0, 0.0, -1.0, 0.0, 0.0, 0.0])  # a weight pulling down on the tool
    wmax, joint = puma.paycap(q, w, TLIM)
    assert wmax > 0 and 0 <= joint < 6
    # holding wmax * w: the motors give gravload + the torque against the payload
    tau = puma.rne(q, friction=False, fext=wmax * w)
    assert abs(abs(tau[joint]) - TLIM[joint]) < 1e-9
    assert np.all(np.abs(tau) <= np.array(TLIM) + 1e-9)
    tau_more = puma.rne(q, friction=False, fext=1.01 * wmax * w)
    assert abs(tau_more[joint]) > TLIM[joint]


def test_velocity_and_force_ellipsoids() -> None:
    robot = models.puma560()
    q = np.array([0.2, -0.6, 0.9, 0.1, 0.5, 0.0])
    Jt = robot.jacob0(q)[:3]
    ve = robot.vellipse(q)
    fe = robot.fellipse(q)
    np.testing.assert_allclose(ve.centre, robot.fkine(q)[:3, 3])
    np.testing.assert_allclose(np.sort(ve.radii), np.sort(np.sqrt(np.linalg.eigvalsh(Jt @ Jt.T))), rtol=1e-12)
    np.testing.assert_allclose(np.sort(fe.radii), np.sort(1 / np.sqrt(np.linalg.eigvalsh(Jt @ Jt.T))), rtol=1e-12)
    rng = np.random.default_rng(0)
    for _ in range(200):  # unit joint speeds move the tool inside the velocity ellipsoid
        u = rng.normal(size=6)
        u /= np.linalg.norm(u)
        assert ve.contains(ve.centre + Jt @ u)
    far = ve.centre + ve.axes[:, 0] * ve.radii[0] * 1.01
    assert not ve.contains(far) and ve.contains(ve.centre + ve.axes[:, 0] * ve.radii[0])
    assert ve.points(8).shape == (64, 3)


def test_robot_object_collisions() -> None:
    ur5 = models.ur5_urdf()
    q = ur5.qr
    T_tool = ur5.fkine(q)
    box = CollisionShape.box([0.05, 0.05, 0.05])
    assert ur5.iscollided(q, box, T_tool)  # at the flange: touches the last links
    hits = ur5.collided(q, box, T_tool)
    assert 6 in hits and 0 not in hits
    far = T_tool.copy()
    far[:3, 3] += [2.0, 0.0, 0.0]
    assert not ur5.iscollided(q, box, far)
    assert ur5.iscollided(q, box, far, margin=2.5)
    # a DH arm uses its automatic link geometry: a floor at the base touches the base, not the hand
    puma = models.puma560()
    floor = CollisionShape.box([4.0, 4.0, 0.02])
    hits = puma.collided(puma.qz, floor, np.eye(4))
    assert 0 in hits and 6 not in hits
    assert 0 not in puma.collided(puma.qz, floor, np.eye(4), skip_base=True)
    below = np.eye(4)
    below[2, 3] = -1.0
    assert not puma.iscollided(puma.qz, floor, below)
    with pytest.raises(TypeError, match="CollisionShape"):
        puma.iscollided(puma.qz, "box")
