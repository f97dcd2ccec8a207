"""The reference plant's arm against independent references: the DH model of the same arm
(ejsrl.robotics) for its workspace check, and constant-deceleration kinematics for its brake."""

from __future__ import annotations

import numpy as np

from ejsrl.plant import Arm
from ejsrl.robotics import Link, Robot


def test_the_workspace_check_uses_the_arm_the_example_draws() -> None:
    arm = Arm(noise=0)
    dh = Robot([Link(d=0.35, alpha=np.pi / 2), Link(a=0.22), Link(a=0.22), Link(a=0.15), Link()])
    rng = np.random.default_rng(3)
    for _ in range(50):
        q = rng.uniform(arm.p.q_min, arm.p.q_max)
        np.testing.assert_allclose(arm.tool_position(q), dh.fkine(q)[:3, 3], atol=1e-12)


def test_braking_stops_within_the_constant_deceleration_distance() -> None:
    arm = Arm(noise=0)
    arm.qd[:] = np.radians([90, 60, 90, 120, 150])
    v0 = arm.qd.copy()
    arm.braking = True
    t, dt = 0.0, 1e-4
    while arm.moving():
        arm.step(dt)
        t += dt
    p = arm.p
    # full torque plus Coulomb friction at least (viscous friction only helps): v0^2 / (2 a)
    a_min = (p.u_max + p.coulomb) / p.inertia
    assert np.all(np.abs(arm.q) <= v0 ** 2 / (2 * a_min) + 1e-4)
    assert t <= float(np.max(v0 / a_min)) + 1e-3
    assert t < 0.05  # the e-stop's braking itself takes under 50 ms from these speeds


def test_the_servo_settles_on_a_set_point_at_the_speed_limit() -> None:
    arm = Arm(noise=0)
    target = np.radians([60, 30, -45, 20, 90])
    arm.q_set = target
    t, dt = 0.0, 1e-3
    while t < 3.0:
        arm.step(dt)
        t += dt
        assert np.all(np.abs(arm.qd) <= arm.p.qd_max * 1.1)  # no joint much faster than its limit
    np.testing.assert_allclose(arm.q, target, atol=np.radians(0.1))
