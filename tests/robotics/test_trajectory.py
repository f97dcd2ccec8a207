"""Trajectories meet their boundary conditions and limits, checked numerically."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ejsrl.robotics import trajectory as tj
from ejsrl.robotics.transforms import q2r, r2q, rpy2tr, tr2angvec, transl

Q0 = np.array([0.0, 0.5, -1.0, 2.0])
QF = np.array([1.2, -0.7, -1.0, 0.1])


def dense(traj, k=4001):
    return traj.sample(np.linspace(0, traj.T, k))


def assert_derivatives_consistent(traj):
    """qd and qdd are the derivatives of q (central differences of the sampler)."""
    t = np.linspace(0.013, traj.T - 0.013, 37)
    h = 1e-6
    qp, qm = traj.sample(t + h)[0], traj.sample(t - h)[0]
    q, qd, qdd = traj.sample(t)
    np.testing.assert_allclose((qp - qm) / (2 * h), qd, atol=1e-6)
    vp, vm = traj.sample(t + h)[1], traj.sample(t - h)[1]
    np.testing.assert_allclose((vp - vm) / (2 * h), qdd, atol=1e-5)


@pytest.mark.parametrize("kind", ["cubic", "quintic"])
def test_polynomials_meet_boundary_conditions(kind):
    v0, vf = np.array([0.1, 0, 0, -0.2]), np.array([0, 0.3, 0, 0])
    traj = getattr(tj, kind)(Q0, QF, 2.0, qd0=v0, qdf=vf)
    q, qd, qdd = traj.sample(0.0 + 1e-15)
    np.testing.assert_allclose(q, Q0, atol=1e-12)
    np.testing.assert_allclose(qd, v0, atol=1e-12)
    q, qd, qdd = traj.sample(2.0 - 1e-15)
    np.testing.assert_allclose(q, QF, atol=1e-12)
    np.testing.assert_allclose(qd, vf, atol=1e-12)
    if kind == "quintic":
        np.testing.assert_allclose(traj.sample(1e-15)[2], 0, atol=1e-12)
        np.testing.assert_allclose(traj.sample(2 - 1e-15)[2], 0, atol=1e-12)
    assert traj.q.shape == (101, 4) and traj.t.shape == (101,) and traj.T == 2.0
    assert_derivatives_consistent(traj)


def test_sample_clamps_outside_the_time_range():
    traj = tj.quintic(Q0, QF, 1.5)
    for t, q in ((-1.0, Q0), (7.0, QF)):
        qs, qd, qdd = traj.sample(t)
        np.testing.assert_allclose(qs, q, atol=1e-12)
        assert not qd.any() and not qdd.any()
    q, qd, _ = traj.sample(np.array([-1.0, 0.75, 9.0]))
    np.testing.assert_allclose(q[[0, 2]], [Q0, QF], atol=1e-12)
    assert not qd[[0, 2]].any()


def test_lspb_with_a_time_has_the_toolbox_cruise_speed():
    traj = tj.lspb(Q0, QF, 2.0)
    _, qd, qdd = dense(traj)
    np.testing.assert_allclose(np.abs(qd).max(axis=0), 1.5 * np.abs(QF - Q0) / 2.0, rtol=1e-9)
    np.testing.assert_allclose(traj.sample(2.0 - 1e-15)[0], QF, atol=1e-12)
    assert_derivatives_consistent(traj)
    with pytest.raises(ValueError, match="cruise speed"):
        tj.lspb(0.0, 1.0, 1.0, V=3.0)


@pytest.mark.parametrize("planner", ["synchronous", "asynchronous", "lspb"])
def test_multi_axis_trapezoids_respect_limits(planner):
    vmax = np.array([1.0, 0.5, 2.0, 3.0])
    amax = np.array([2.0, 4.0, 1.0, 10.0])
    traj = getattr(tj, planner)(Q0, QF, vmax=vmax, amax=amax)
    t = np.linspace(0, traj.T, 20001)
    q, qd, qdd = traj.sample(t)
    assert np.all(np.abs(qd) <= vmax * (1 + 1e-9))
    assert np.all(np.abs(qdd) <= amax * (1 + 1e-9))
    np.testing.assert_allclose(q[-1], QF, atol=1e-12)
    np.testing.assert_allclose(q[0], Q0, atol=1e-12)
    moving = Q0 != QF
    # time at which each joint arrives (within 1e-9 of its goal from then on)
    done = np.array([t[np.nonzero(np.abs(q[:, j] - QF[j]) > 1e-9)[0].max() + 1] if moving[j] else 0.0
                     for j in range(4)])
    tmin = np.where(np.abs(QF - Q0) <= vmax**2 / amax, 2 * np.sqrt(np.abs(QF - Q0) / amax),
                    np.abs(QF - Q0) / vmax + vmax / amax)
    if planner == "asynchronous":
        np.testing.assert_allclose(done[moving], tmin[moving], atol=2 * traj.T / 20000)
    else:  # synchronous: every moving joint ends together, at the slowest joint's time
        np.testing.assert_allclose(done[moving], tmin.max(), atol=2 * traj.T / 20000)
        assert traj.T == pytest.approx(tmin.max())
    assert_derivatives_consistent(traj)


def test_spline_passes_through_via_points_with_continuous_acceleration():
    tv = np.array([0.0, 1.0, 2.5, 3.0])
    qv = np.array([[0, 0], [1, 2], [0.5, 1], [0, 0.3]])
    traj = tj.spline(tv, qv, qd0=[0.1, 0.0], qdf=[0.0, -0.2])
    for t, q in zip(tv, qv):
        np.testing.assert_allclose(traj.sample(min(t, traj.T - 1e-15))[0], q, atol=1e-12)
    np.testing.assert_allclose(traj.sample(1e-15)[1], [0.1, 0.0], atol=1e-12)
    for tk in tv[1:-1]:
        np.testing.assert_allclose(traj.sample(tk - 1e-12)[2], traj.sample(tk + 1e-12)[2], atol=1e-9)
    assert_derivatives_consistent(traj)


def test_poly434_meets_its_knots_and_is_smooth():
    q1, q2 = Q0 + 0.1, QF - 0.1
    traj = tj.poly434(Q0, q1, q2, QF, 0.3, 1.0, 0.4)
    b = traj.breaks
    np.testing.assert_allclose(b, [0, 0.3, 1.3, 1.7])
    np.testing.assert_allclose(traj.sample(0.3)[0], q1, atol=1e-12)
    np.testing.assert_allclose(traj.sample(1.3)[0], q2, atol=1e-12)
    for tk in b[1:3]:
        for k in range(3):
            np.testing.assert_allclose(traj.sample(tk - 1e-10)[k], traj.sample(tk + 1e-10)[k], atol=1e-7)
    for t, q in ((1e-15, Q0), (1.7 - 1e-15, QF)):
        s = traj.sample(t)
        np.testing.assert_allclose(s[0], q, atol=1e-12)
        np.testing.assert_allclose(s[1], 0, atol=1e-12)
        np.testing.assert_allclose(s[2], 0, atol=1e-11)
    assert_derivatives_consistent(traj)


def test_path434_is_synchronised_within_limits_and_drives_an_ode():
    """The paper's lab: v = synchro(qi, qf, vmax), APlan = the 4-3-4 acceleration, and an
    ODE q' = v, v' = APlan(t) must land on qf at rest."""
    qi = np.radians([10, -20, 30, 0, 45, -60])
    qf = np.radians([60, 15, -40, 90, 0, 30])
    vmax = np.array([1.0, 1.0, 1.2, 2.0, 2.0, 2.0])
    v = tj.synchro(qi, qf, vmax)
    Tm = np.max(np.abs(qf - qi) / vmax)
    np.testing.assert_allclose(v * Tm, qf - qi)
    assert np.all(np.abs(v) <= vmax + 1e-12)
    traj = tj.path434(qi, qf, vmax, tacc=0.1, tdec=0.2)
    q, qd, qdd = dense(traj, 20001)
    assert np.all(np.abs(qd) <= vmax * (1 + 1e-9))
    slowest = np.argmax(np.abs(qf - qi) / vmax)
    assert np.abs(qd[:, slowest]).max() > 0.9 * vmax[slowest]  # it uses its velocity budget
    sol = solve_ivp(lambda t, x: np.concatenate((x[6:], traj.sample(t)[2])), (0, traj.T + 0.5),
                    np.concatenate((qi, np.zeros(6))), rtol=1e-10, atol=1e-12, max_step=0.05)
    np.testing.assert_allclose(sol.y[:6, -1], qf, atol=1e-7)
    np.testing.assert_allclose(sol.y[6:, -1], 0, atol=1e-7)
    # every joint is in its lift-off phase, cruise and set-down at the same times
    assert len(traj.breaks) == 4
    with pytest.raises(ValueError, match="tacc"):
        tj.path434(qi, qf, vmax * 100, tacc=0.5, tdec=0.5)


def test_cartesian_line_is_straight_with_slerp_orientation():
    T0 = transl(0.4, -0.2, 0.3) @ rpy2tr(0.1, 0.2, 0.3)
    T1 = transl(0.1, 0.5, 0.6) @ rpy2tr(-0.4, 0.3, 1.9)
    ct = tj.ctraj(T0, T1, 2.0, num=51)
    np.testing.assert_allclose(ct.poses[0], T0, atol=1e-12)
    np.testing.assert_allclose(ct.poses[-1], T1, atol=1e-12)
    p = ct.poses[:, :3, 3]
    d = (T1[:3, 3] - T0[:3, 3]) / np.linalg.norm(T1[:3, 3] - T0[:3, 3])
    off = (p - T0[:3, 3]) - np.outer((p - T0[:3, 3]) @ d, d)
    assert np.abs(off).max() < 1e-12  # on the line
    # orientation: rotation from T0 grows about one fixed axis, proportionally to s
    theta, axis = tr2angvec(T1[:3, :3] @ T0[:3, :3].T)
    for s, T in zip(ct.s[1:-1], ct.poses[1:-1]):
        th, ax = tr2angvec(T[:3, :3] @ T0[:3, :3].T)
        assert th == pytest.approx(s * theta, abs=1e-9)
        np.testing.assert_allclose(ax, axis, atol=1e-8)
    # the twist is the derivative of the pose
    h = 1e-6
    Tp, v = ct.sample(0.7)
    Ta, _ = ct.sample(0.7 + h)
    Tb, _ = ct.sample(0.7 - h)
    np.testing.assert_allclose((Ta[:3, 3] - Tb[:3, 3]) / (2 * h), v[:3], atol=1e-7)
    W = (Ta[:3, :3] - Tb[:3, :3]) / (2 * h) @ Tp[:3, :3].T
    np.testing.assert_allclose([W[2, 1], W[0, 2], W[1, 0]], v[3:], atol=1e-7)
    assert np.allclose(q2r(r2q(ct.poses[10])), ct.poses[10][:3, :3])


def test_sample_at_the_ends_gives_the_polynomials_values() -> None:
    """A cubic from rest to rest: a(0) = 6 D / T^2 and a(T) = -6 D / T^2 (finite differences agree)."""
    import numpy as np

    from ejsrl.robotics import trajectory

    D, T = 1.2, 2.0
    tr = trajectory.cubic([0.0], [D], T)
    for t, expected in ((0.0, 6 * D / T**2), (T, -6 * D / T**2)):
        q, qd, qdd = tr.sample(t)
        assert np.allclose(qdd, expected)
        assert np.allclose(qd, 0.0, atol=1e-12)
        assert np.allclose(tr.sample(np.array([t]))[2][0], qdd)  # scalar and array paths agree
    h = 1e-5
    assert np.allclose(tr.sample(h)[1] / h, 6 * D / T**2, rtol=1e-3)
    assert np.allclose(tr.sample(-0.1)[2], 0.0) and np.allclose(tr.sample(T + 0.1)[2], 0.0)
