"""``accel`` and ``fdyn`` refuse an inertia matrix that is singular or ill-conditioned
(issue #27): the AL5D's URDF has a wrist roll whose link has no inertia about its axis,
and the Toolbox returns 1e17 rad/s^2 there. A well-conditioned arm is still solved, and
its answer equals ``M^-1 (tau - bias)`` from NumPy."""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.robotics import Robot, RevoluteDH, models


def _arm(last_inertia: float) -> Robot:
    """A 3R arm plus a wrist roll (alpha = pi/2 then a roll about the forearm) whose last
    link has no mass and the inertia ``last_inertia`` (kg m^2) about every axis."""
    rod = dict(m=1.0, r=[-0.15, 0, 0], I=[0.001, 0.0075, 0.0075])
    links = [
        RevoluteDH(d=0.3, alpha=np.pi / 2, m=2.0, r=[0, -0.1, 0], I=[0.01, 0.01, 0.01]),
        RevoluteDH(a=0.3, **rod),
        RevoluteDH(alpha=np.pi / 2, **rod),
        RevoluteDH(d=0.2, m=0.0, r=[0, 0, 0], I=[last_inertia] * 3),
    ]
    return Robot(links, name="wristy")


Q = np.array([0.3, 0.5, -0.4, 0.2])


@pytest.mark.parametrize("fast", [True, False])
@pytest.mark.parametrize("inertia", [0.0, 1e-16])
def test_accel_refuses_a_singular_or_ill_conditioned_inertia(fast: bool, inertia: float) -> None:
    robot = _arm(inertia)
    robot._fast = fast
    M = robot.inertia(Q)
    assert np.linalg.cond(M) > 1e12  # the reference: NumPy's condition number
    with pytest.raises(np.linalg.LinAlgError) as err:
        robot.accel(Q, np.zeros(4), np.zeros(4))
    msg = str(err.value)
    assert "wristy" in msg and "[ 0.3,  0.5, -0.4,  0.2]" in msg and "joint 4" in msg
    assert "singular or ill-conditioned" in msg and "armature" in msg
    # a batch names the configuration that fails
    with pytest.raises(np.linalg.LinAlgError, match=r"configuration 0 of 2"):
        robot.accel(np.array([Q, Q]), np.zeros(4), np.zeros(4))


@pytest.mark.parametrize("fast", [True, False])
def test_accel_accepts_the_same_arm_with_inertia_and_equals_numpy(fast: bool) -> None:
    robot = _arm(1e-4)
    robot._fast = fast
    qd = np.array([0.1, -0.2, 0.3, 0.4])
    tau = np.array([1.0, 2.0, -0.5, 0.01])
    bias = robot.rne(Q, qd, np.zeros(4))
    ref = np.linalg.solve(robot.inertia(Q), tau - bias)
    np.testing.assert_allclose(robot.accel(Q, qd, tau), ref, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(robot.accel(np.array([Q, Q]), qd, tau), [ref, ref], rtol=1e-10, atol=1e-10)


def test_accel_of_the_puma_over_many_configurations_is_unchanged() -> None:
    p = models.puma560()
    rng = np.random.default_rng(3)
    Qs = rng.uniform(-np.pi, np.pi, (50, 6))
    qd = rng.uniform(-1, 1, (50, 6))
    tau = rng.uniform(-5, 5, (50, 6))
    bias = p.rne(Qs, qd, np.zeros((50, 6)))
    ref = np.linalg.solve(p.inertia(Qs), (tau - bias)[..., None])[..., 0]
    np.testing.assert_allclose(p.accel(Qs, qd, tau), ref, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(p.accel(Qs[7], qd[7], tau[7]), ref[7], rtol=1e-9, atol=1e-9)


def test_fdyn_names_the_time_robot_and_configuration() -> None:
    robot = _arm(0.0)
    with pytest.raises(np.linalg.LinAlgError, match=r"fdyn at t = 0 s: wristy: the inertia matrix at q = "):
        robot.fdyn(0.1, Q)
