"""Dynamics against Robotics Toolbox values, a second method and energy conservation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ejsrl.robotics import Robot, models

from testkit.robotics import ALL_MODELS, random_q, with_base_tool

DYN_MODELS = list(ALL_MODELS)


def com_points(robot: Robot, q: np.ndarray) -> np.ndarray:
    """World positions (n, 3) of the link centres of mass (payload folded in)."""
    robot._params()
    F = robot.fkine_all(q)
    return np.einsum("nij,nj->ni", F[1:, :3, :3], robot._r) + F[1:, :3, 3]


def potential(robot: Robot, q: np.ndarray) -> float:
    return float(-np.sum(robot._m * (com_points(robot, q) @ robot.gravity)))


def inertia_from_com_jacobians(robot: Robot, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """M = sum m Jv^T Jv + Jw^T R I R^T Jw + armature, with Jv by finite differences of
    the centres of mass and Jw from the joint axes: independent of Newton-Euler."""
    robot._params()
    n = robot.n
    F = robot.fkine_all(q)
    M = np.diag(robot._armature).astype(float)
    Jv = np.zeros((n, 3, n))
    for j in range(n):
        dq = np.zeros(n)
        dq[j] = h
        Jv[:, :, j] = (com_points(robot, q + dq) - com_points(robot, q - dq)) / (2 * h)
    axes = (F[1:] if robot.mdh else F[:-1])[:, :3, 2]
    for i in range(n):
        Jw = np.zeros((3, n))
        for j in range(i + 1):
            if not robot.links[j].isprismatic:
                Jw[:, j] = axes[j]
        R = F[i + 1, :3, :3]
        M += robot._m[i] * Jv[i].T @ Jv[i] + Jw.T @ R @ robot._I[i] @ R.T @ Jw
    return M


@pytest.mark.parametrize("k", range(5))
def test_puma560_rne_and_coriolis_match_toolbox(puma_ref, k):
    ref = puma_ref["random"][k]
    p = models.puma560()
    np.testing.assert_allclose(p.rne(ref["q"], ref["qd"], ref["qdd"]), ref["rne"], rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(p.coriolis(ref["q"], ref["qd"]), ref["coriolis"], atol=1e-12)


@pytest.mark.parametrize("pose", ["qz", "qr", "qn", "qs"])
def test_puma560_gravload_and_inertia_match_toolbox(puma_ref, pose):
    ref = puma_ref["poses"][pose]
    p = models.puma560()
    np.testing.assert_allclose(p.gravload(ref["q"]), ref["gravload"], atol=1e-10)
    np.testing.assert_allclose(p.inertia(ref["q"]), ref["inertia"], atol=1e-12)


def test_puma560_published_gravity_load():
    """Corke, RVC 2nd ed., sec. 9.2.2: puma.gravload(qn) = [0, 31.64, 6.035, 0, 0.02825, 0]."""
    p = models.puma560()
    np.testing.assert_allclose(p.gravload(p.qn), [0, 31.64, 6.035, 0, 0.02825, 0], atol=5e-3)


@pytest.mark.parametrize("name", DYN_MODELS)
def test_dynamics_are_mutually_consistent(name):
    robot = with_base_tool(ALL_MODELS[name]())
    robot.payload(0.7, [0.01, -0.02, 0.05], [0.002, 0.003, 0.001])
    rng = np.random.default_rng(11)
    Q = random_q(robot, rng, 4)
    Qd = rng.uniform(-1.5, 1.5, Q.shape)
    Qdd = rng.uniform(-2, 2, Q.shape)
    tau = robot.rne(Q, Qd, Qdd)
    M = robot.inertia(Q)
    C = robot.coriolis(Q, Qd)
    g = robot.gravload(Q)
    for k in range(len(Q)):
        lhs = M[k] @ Qdd[k] + C[k] @ Qd[k] + g[k] - robot.friction(Qd[k])
        np.testing.assert_allclose(tau[k], lhs, atol=1e-10 * (1 + np.abs(tau[k]).max()))
        np.testing.assert_allclose(M[k], M[k].T, atol=1e-12)
        assert np.linalg.eigvalsh(M[k]).min() > 0
        # independent method: kinetic-energy Hessian from centre-of-mass Jacobians
        np.testing.assert_allclose(M[k], inertia_from_com_jacobians(robot, Q[k]), atol=1e-7)
        # gravity is the gradient of the potential energy
        h = 1e-6
        grad = [(potential(robot, Q[k] + h * e) - potential(robot, Q[k] - h * e)) / (2 * h) for e in np.eye(robot.n)]
        np.testing.assert_allclose(g[k], grad, atol=1e-6)
        # dM/dt - 2C is skew-symmetric (passivity), with dM/dt by finite differences
        Mdot = (robot.inertia(Q[k] + h * Qd[k]) - robot.inertia(Q[k] - h * Qd[k])) / (2 * h)
        S = Mdot - 2 * C[k]
        np.testing.assert_allclose(S, -S.T, atol=1e-6)
    np.testing.assert_allclose(robot.accel(Q, Qd, tau), Qdd, atol=1e-8)
    np.testing.assert_allclose(robot.accel(Q[0], Qd[0], tau[0]), Qdd[0], atol=1e-8)
    for k in range(len(Q)):
        np.testing.assert_allclose(robot.rne(Q[k], Qd[k], Qdd[k]), tau[k], atol=1e-12)


def test_payload_equals_an_external_force_at_the_tool():
    """A point payload under gravity weighs on the arm exactly like the external wrench
    [0, 0, -m g] applied at the tool origin (checked through rne's fext path)."""
    p = with_base_tool(models.puma560())
    q = p.qn + 0.1
    bare = p.rne(q)
    w = np.array([0, 0, -2.5 * 9.81, 0, 0, 0])
    via_fext = p.rne(q, fext=w)
    p.payload(2.5)
    np.testing.assert_allclose(p.rne(q), via_fext, atol=1e-10)
    assert np.abs(via_fext - bare).max() > 1.0  # the payload matters
    # payload with inertia: same as adding its inertia to the last link by hand
    p.payload(1.2, [0.0, 0.0, 0.05], [0.01, 0.01, 0.02])
    M1 = p.inertia(q)
    p.payload(0)
    np.testing.assert_allclose(p.inertia(q), models.puma560().inertia(q), atol=1e-14)
    assert M1[5, 5] > p.inertia(q)[5, 5]


def test_friction_follows_the_toolbox_sign_convention():
    p = models.puma560()
    f = p.friction(np.array([1.0, -1.0, 0.0, 0.5, 0.0, 0.0]))
    L0 = p.links[0]
    assert f[0] == pytest.approx(-abs(L0.G) * (L0.B * abs(L0.G) + L0.Tc[0]))
    assert f[1] > 0 and f[2] == 0.0 and f[3] < 0
    assert f[0] == pytest.approx(L0.friction(1.0))


@pytest.mark.parametrize("name", ["rrr", "mdh5"])
def test_unforced_frictionless_arm_conserves_energy(name):
    robot = ALL_MODELS[name]().nofriction(viscous=True)
    robot._params()
    n = robot.n
    q0 = robot.qr if hasattr(robot, "qr") else np.full(n, 0.3)
    if name == "mdh5":
        q0 = np.array([0.2, 0.4, 0.3, -0.5, 0.7])
    qd0 = np.linspace(0.5, -0.5, n)

    def energy(x):
        q, qd = x[:n], x[n:]
        return 0.5 * qd @ robot.inertia(q) @ qd + potential(robot, q)

    def f(t, x):
        return np.concatenate((x[n:], robot.accel(x[:n], x[n:], np.zeros(n))))

    x0 = np.concatenate((q0, qd0))
    sol = solve_ivp(f, (0, 5.0), x0, method="DOP853", rtol=1e-11, atol=1e-12)
    assert sol.success
    E0 = energy(x0)
    E = np.array([energy(x) for x in sol.y.T[:: max(1, len(sol.t) // 50)]])
    scale = max(abs(E0), 0.5 * qd0 @ robot.inertia(q0) @ qd0)
    assert np.abs(E - E0).max() / scale < 1e-6
    assert np.ptp(sol.y[0]) > 0.1  # it really moved
