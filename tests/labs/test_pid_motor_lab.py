"""The PID + DC-motor lab (paper figure 13) run headless: each joint settles within 2 % of
its step target (π/2, π/3, −π/4), the overshoot orders as control theory says when the
gains change, and at rest the motors hold exactly the arm's weight.

References: the targets themselves; the gravity torques as the gradient of the arm's
potential energy (centres of mass from standard DH written out here, finite
differences), not the runtime's dynamics; the armature equation at rest (V = R i).
"""

from __future__ import annotations

import numpy as np
import pytest
from testkit.labs import LABS, dh_frames, headless, settle_time, vector

TARGETS = np.array([np.pi / 2, np.pi / 3, -np.pi / 4])
VARS = "t,q,qd,i,V,tau,saturated"
# models.rrr(): (d, a, alpha, offset) and link masses and centres of mass (link frames)
RRR = [(0.4, 0.0, np.pi / 2, 0.0), (0.0, 0.4, 0.0, 0.0), (0.0, 0.3, 0.0, 0.0)]
MASS = [3.0, 2.0, 1.0]
COM = [np.array([0, -0.2, 0]), np.array([-0.2, 0, 0]), np.array([-0.15, 0, 0])]
G = np.array([100.0, 100.0, 50.0])
KT, R = 0.02, 1.0


def potential(q: np.ndarray) -> float:
    frames = dh_frames(q, RRR)
    return sum(m * 9.81 * (frames[j + 1] @ np.append(c, 1.0))[2] for j, (m, c) in enumerate(zip(MASS, COM)))


def gravity_torque(q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """dV/dq: the torques that hold the arm still against gravity."""
    return np.array([(potential(q + h * e) - potential(q - h * e)) / (2 * h) for e in np.eye(3)])


def overshoot(d: dict[str, np.ndarray]) -> np.ndarray:
    """Per joint, how far past its target it went, as a fraction of the step."""
    q = vector(d, "q", 3)
    return np.max(q / TARGETS, axis=0) - 1.0


@pytest.fixture(scope="module")
def runs(built):
    lab = built(LABS["pid"])
    cases = {"default": {}, "no_d": {"Kd": "0"}, "low_i": {"Ki": "5"}, "high_i": {"Ki": "20"}}
    return {name: headless(lab, 3.0, vars=VARS, every=5, sets=sets) for name, sets in cases.items()}


def test_every_joint_settles_within_two_percent_of_its_target(runs):
    d = runs["default"]
    t, q = d["t"], vector(d, "q", 3)
    for j in range(3):
        ts = settle_time(t, q[:, j], TARGETS[j])
        assert ts < 1.5, f"joint {j + 1} settles at {ts} s"
    np.testing.assert_allclose(q[-1], TARGETS, rtol=0.01)
    assert np.all(overshoot(d) > 0.005)  # a real step response, with some overshoot


def test_at_rest_the_motors_hold_the_arms_weight(runs):
    d = runs["default"]
    q, qd = vector(d, "q", 3)[-1], vector(d, "qd", 3)[-1]
    i, V, tau = vector(d, "i", 3)[-1], vector(d, "V", 3)[-1], vector(d, "tau", 3)[-1]
    assert np.abs(qd).max() < 1e-2
    np.testing.assert_allclose(tau, G * KT * i, rtol=1e-12)  # the gearbox
    np.testing.assert_allclose(tau, gravity_torque(q), rtol=0.02, atol=0.02)  # holding the weight
    assert abs(tau[1]) > 1.0  # the shoulder does hold something
    np.testing.assert_allclose(V, R * i, atol=0.05)  # no back-EMF when the motor stands still


def test_overshoot_orders_with_the_gains(runs):
    base, no_d, low_i, high_i = (overshoot(runs[k]) for k in ("default", "no_d", "low_i", "high_i"))
    # the derivative term is the damping: without it every joint overshoots more
    assert np.all(no_d > base + 0.03), (no_d, base)
    # the integral keeps pushing until the error changes sign: more Ki, more overshoot
    assert np.all(low_i < base) and np.all(base < high_i), (low_i, base, high_i)
    # and the arm still gets there
    for d in runs.values():
        np.testing.assert_allclose(vector(d, "q", 3)[-1], TARGETS, rtol=0.03)


def test_without_integral_action_gravity_leaves_a_steady_error(built):
    """P and D only: at rest the motor torque G Kt Ka Kp e / R must equal the weight's torque."""
    d = headless(built(LABS["pid"]), 4.0, vars=VARS, every=50, sets={"Ki": "0"})
    q = vector(d, "q", 3)[-1]
    error = TARGETS - q
    Ka, Kp = 10.0, 12.0
    np.testing.assert_allclose(G * KT * Ka * Kp * error / R, gravity_torque(q), rtol=0.02, atol=1e-3)
    assert abs(error[0]) < 1e-4  # the waist carries no weight
    assert abs(np.degrees(error[1])) > 0.5  # the shoulder visibly falls short
