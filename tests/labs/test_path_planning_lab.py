"""The path-planning lab (paper figures 8-9) run headless: the planned motion, integrated as
ODEs, reaches the goal under the velocity limits, and every synchronised profile ends all
joints together.

References are the lab's inputs and closed forms written here (the cubic's peak speed
1.5 D/T, the quintic's 1.875 D/T, LSPB minimum times D/v + v/a), not the planner's output.
"""

from __future__ import annotations

import numpy as np
import pytest
from testkit.labs import LABS, headless, vector

Q0 = np.radians([0, 45, -180, 0, 45, 0])
QF = np.radians([90, 10, -110, 60, -60, 90])
VMAX = np.radians([60, 60, 60, 120, 120, 120])
AMAX = np.radians([150, 150, 150, 300, 300, 300])
D = np.abs(QF - Q0)
SLOWEST = float(np.max(D / VMAX))  # the time the slowest joint needs at its full speed
DT = 0.02
VARS = "t,q,v,a,T_plan"


def lspb_min_time(D: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Minimum rest-to-rest time of a trapezoidal (or triangular) profile per joint."""
    return np.where(D > v**2 / a, D / v + v / a, 2 * np.sqrt(D / a))


def arrival_times(t: np.ndarray, q: np.ndarray, qf: np.ndarray, tol: float = 1e-7) -> np.ndarray:
    """For each joint, the first sample time after which it stays at its goal."""
    out = []
    for j in range(q.shape[1]):
        away = np.flatnonzero(np.abs(q[:, j] - qf[j]) > tol)
        out.append(t[away[-1] + 1] if len(away) else t[0])
    return np.array(out)


@pytest.fixture(scope="module")
def lab(built):
    return built(LABS["path"])


# expected duration of each synchronised profile, from its peak-speed formula
EXPECTED_T = {"cubic": 1.5 * SLOWEST, "quintic": 1.875 * SLOWEST, "trapezoidal": 1.5 * SLOWEST,
              "synchronous": float(np.max(lspb_min_time(D, VMAX, AMAX)))}


@pytest.mark.parametrize("profile", ["4-3-4", "cubic", "quintic", "trapezoidal", "synchronous"])
def test_synchronised_profiles_reach_the_goal_together_within_the_limits(lab, profile):
    d = headless(lab, 3.2, vars=VARS, sets={"profile": profile})
    t, q, v, a = d["t"], vector(d, "q", 6), vector(d, "v", 6), vector(d, "a", 6)
    T = d["T_plan"][0]
    if profile in EXPECTED_T:
        assert T == pytest.approx(EXPECTED_T[profile], rel=1e-9)
    # starts at the start, ends at the goal, at rest
    np.testing.assert_allclose(q[0], Q0, atol=1e-12)
    # (to 1e-5 rad: the adaptive solver meets LSPB's jumps in acceleration at the blends)
    np.testing.assert_allclose(q[-1], QF, atol=1e-5)
    np.testing.assert_allclose(v[-1], 0.0, atol=1e-5)
    # all joints end together: every one is still moving at the last sample before T and
    # every one rests from T on (each joint has its own distance to go)
    before = np.flatnonzero(t < T)[-1]
    assert np.all(np.abs(v[before]) > 1e-6), v[before]
    assert np.abs(v[t >= T]).max() < 1e-5
    assert np.all(np.abs(v[1]) > 1e-6)  # and they all started at once
    # no joint exceeds its velocity limit, and the limiting joint does use it
    ratio = np.max(np.abs(v), axis=0) / VMAX
    assert ratio.max() <= 1.0 + 1e-6
    assert ratio.max() >= 0.98
    # the integrated states are consistent: v is the time derivative of q; a is zero at rest
    assert np.max(np.abs(np.gradient(q, t, axis=0) - v)) < 0.03 * VMAX.max()
    assert np.abs(a[t > T + DT]).max() == 0.0
    if profile != "synchronous":
        # synchronised in shape too: each joint's normalised progress is one common curve
        progress = (q - Q0) / (QF - Q0)
        assert np.ptp(progress, axis=1).max() < 1e-6


def test_434_starts_and_ends_without_an_acceleration_jump_unlike_the_cubic(lab):
    d434 = headless(lab, 2.0, vars=VARS, sets={"profile": "4-3-4"})
    dcub = headless(lab, 2.5, vars=VARS, sets={"profile": "cubic"})
    a434, acub = vector(d434, "a", 6), vector(dcub, "a", 6)
    # the 4-3-4 blends start from rest with zero acceleration; the cubic jumps to 6 D / T^2 at once
    assert np.abs(a434[0]).max() < 1e-9
    T = dcub["T_plan"][0]
    t1 = dcub["t"][1]  # the cubic's acceleration 6 D / T^2 (1 - 2 t / T) is not zero right after the start
    np.testing.assert_allclose(np.abs(acub[1]), 6 * D / T**2 * (1 - 2 * t1 / T), rtol=1e-9)
    assert np.all(np.abs(acub[1]) > 0.5)


def test_asynchronous_joints_each_finish_in_their_own_minimum_time(lab):
    d = headless(lab, 3.0, vars=VARS, sets={"profile": "asynchronous"})
    t, q, v, a = d["t"], vector(d, "q", 6), vector(d, "v", 6), vector(d, "a", 6)
    expected = lspb_min_time(D, VMAX, AMAX)
    arrive = arrival_times(t, q, QF, tol=1e-5)
    assert np.all(np.abs(arrive - expected) <= DT + 1e-9), (arrive, expected)
    assert np.ptp(expected) > 0.5  # they really do end at different times
    assert np.all(np.max(np.abs(v), axis=0) <= VMAX * (1 + 1e-6))
    assert np.all(np.max(np.abs(a), axis=0) <= AMAX * (1 + 1e-6))
    np.testing.assert_allclose(q[-1], QF, atol=1e-5)


def test_a_lower_velocity_limit_slows_every_joint_to_stay_in_step(lab):
    vmax = VMAX.copy()
    vmax[4] = np.radians(30)  # joint 5 (105 degrees to go) becomes the slowest: 3.5 s at full speed
    d = headless(lab, 0.1, vars=VARS, sets={"profile": "cubic", "v_max_deg": str([round(float(x), 9) for x in np.degrees(vmax)])})
    assert d["T_plan"][0] == pytest.approx(1.5 * np.max(D / vmax), rel=1e-9)
    assert d["T_plan"][0] > 1.5 * SLOWEST * 2
