"""The inverse-dynamics lab (paper figure 10) run headless: the torques in the CSV are
Newton-Euler's along the integrated path, and they change with the payload as physics says.

References: ``rne`` recomputed here from the CSV's q, v, a on a freshly built arm; the
payload's static share J_c(q)^T m g with the Jacobian of its centre of mass taken by
finite differences of the forward kinematics; and the work-energy balance over a
rest-to-rest move (the payload's share of the joint work is m g times the rise of its
centre of mass), which needs no dynamics code at all.
"""

from __future__ import annotations

import numpy as np
import pytest
from testkit.labs import LABS, headless, vector

from ejsrl.robotics import models
from ejsrl.robotics.transforms import transl

R_PAYLOAD = np.array([0.0, 0.0, 0.15])  # the lab's payload centre of mass in the tool frame
SIDE = 0.3
G = 9.81
VARS = "t,q,v,a,tau,tau_payload,m_payload,moves,T_plan"


@pytest.fixture(scope="module")
def runs(built):
    lab = built(LABS["dynamics"])
    # one move (1.95 s) and part of the 0.5 s rest at its end
    return {m: headless(lab, 2.3, vars=VARS, sets={"m_payload": str(m)}) for m in (0.0, 2.5, 5.0)}


def arm_with_payload(m: float):
    robot = models.puma560()
    I = m * SIDE**2 / 6
    robot.payload(m, R_PAYLOAD, [I, I, I])
    return robot


def payload_point(robot, q: np.ndarray) -> np.ndarray:
    return (robot.fkine(q) @ transl(*R_PAYLOAD))[:3, 3]


def com_jacobian(robot, q: np.ndarray, h: float = 1e-7) -> np.ndarray:
    """d(payload centre)/dq (3, 6) by central differences of the forward kinematics."""
    J = np.zeros((3, len(q)))
    for j in range(len(q)):
        dq = np.zeros(len(q))
        dq[j] = h
        J[:, j] = (payload_point(robot, q + dq) - payload_point(robot, q - dq)) / (2 * h)
    return J


def test_torques_are_newton_euler_along_the_path(runs):
    for m, d in runs.items():
        q, v, a, tau = (vector(d, k, 6) for k in ("q", "v", "a", "tau"))
        assert np.all(d["m_payload"] == m)
        expected = arm_with_payload(m).rne(q, v, a)  # batched: every CSV row at once
        np.testing.assert_allclose(tau, expected, rtol=1e-9, atol=1e-9)
        bare = models.puma560().rne(q, v, a)
        np.testing.assert_allclose(vector(d, "tau_payload", 6), expected - bare, rtol=1e-9, atol=1e-9)
        assert np.abs(v).max() > 0.5  # the arm really moved
        assert d["moves"][-1] == 0 and d["t"][-1] > d["T_plan"][0]  # one complete move


def test_the_payload_changes_the_torques_as_physics_says(runs):
    d0, d1, d2 = runs[0.0], runs[2.5], runs[5.0]
    q = vector(d0, "q", 6)
    np.testing.assert_array_equal(q, vector(d2, "q", 6))  # the payload does not change the plan
    tau0, tau1, tau2 = (vector(d, "tau", 6) for d in (d0, d1, d2))
    # visibly: the shoulder needs newtons-metres more with 5 kg
    assert np.abs(tau2 - tau0)[:, 1].max() > 10.0
    # the payload's share is linear in its mass (its inertia is m side^2 / 6)
    np.testing.assert_allclose(tau2 - tau0, 2 * (tau1 - tau0), rtol=1e-7, atol=1e-8)
    # at rest (start, and the dwell after the move) the share is J_c^T m g: holding the weight up
    robot = models.puma560()
    t, v = d0["t"], vector(d0, "v", 6)
    rest = [0, int(np.flatnonzero((t > d0["T_plan"][0] + 0.05) & (np.abs(v).max(axis=1) == 0))[0])]
    for i in rest:
        static = com_jacobian(robot, q[i]).T @ np.array([0.0, 0.0, 5.0 * G])
        np.testing.assert_allclose(tau2[i] - tau0[i], static, rtol=1e-6, atol=1e-6)
    # while it moves the share is not just the weight: the accelerations add to it
    moving = np.flatnonzero(np.abs(v).max(axis=1) > 0.3)
    static_moving = np.array([com_jacobian(robot, q[i]).T @ [0, 0, 5.0 * G] for i in moving])
    assert np.abs((tau2 - tau0)[moving] - static_moving).max() > 0.5


def test_the_payloads_share_of_the_work_lifts_its_weight(runs):
    """Rest to rest, the extra joint work is the payload's potential energy gain m g dz."""
    d0, d2 = runs[0.0], runs[5.0]
    t, q, v = d0["t"], vector(d0, "q", 6), vector(d0, "v", 6)
    power = np.sum((vector(d2, "tau", 6) - vector(d0, "tau", 6)) * v, axis=1)
    work = float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(t)))
    robot = models.puma560()
    dz = payload_point(robot, q[-1])[2] - payload_point(robot, q[0])[2]
    assert abs(dz) > 0.1
    assert work == pytest.approx(5.0 * G * dz, rel=2e-3)
