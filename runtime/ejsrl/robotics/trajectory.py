"""Joint-space and Cartesian trajectories.

Every joint-space planner returns a :class:`Trajectory`: samples ``t`` (m,), ``q``,
``qd``, ``qdd`` (m, n) and ``sample(t)``, which evaluates the underlying piecewise
polynomials exactly at any time (so an ODE can integrate ``q' = v, v' = a(t)`` against
it). Times are in s, joint values in rad (or m for prismatic joints).

Planners: :func:`cubic`, :func:`quintic` (= :func:`jtraj`), :func:`lspb` (trapezoidal
velocity), :func:`synchronous`, :func:`asynchronous`, :func:`spline` (via points),
:func:`poly434` / :func:`path434` with :func:`synchro` (the EjsRL 4-3-4 planner), and
:func:`ctraj` (Cartesian straight line with SLERP orientation), and :func:`mstraj`
(multi-segment through via points with blends, as the Robotics Toolbox's).
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass
from math import comb

import numpy as np
import numpy.polynomial.polynomial as P
from numpy.typing import ArrayLike, NDArray

from .transforms import tr2angvec_vec, trinterp

__all__ = [
    "Trajectory",
    "CartesianTrajectory",
    "cubic",
    "quintic",
    "jtraj",
    "lspb",
    "synchronous",
    "asynchronous",
    "spline",
    "poly434",
    "synchro",
    "path434",
    "ctraj",
    "mstraj",
]

Array = NDArray[np.float64]


class Trajectory:
    """A piecewise-polynomial joint trajectory on ``[0, T]``.

    Attributes:
        t: (m,) sample times; q, qd, qdd: (m, n) samples at those times.
        T: duration (s); also ``duration``.
        breaks: (k+1,) segment boundaries; coef: (k, deg+1, n) coefficients in ascending
            powers of the local time ``t - breaks[i]``.
        kind: name of the planner.
    """

    def __init__(self, breaks: ArrayLike, coef: ArrayLike, *, num: int | ArrayLike = 101, kind: str = "") -> None:
        self.breaks = np.asarray(breaks, dtype=float)
        self.coef = np.asarray(coef, dtype=float)
        deg = self.coef.shape[1] - 1
        p = np.arange(1, deg + 1)
        self._dcoef = self.coef[:, 1:, :] * p[None, :, None]
        self._ddcoef = self._dcoef[:, 1:, :] * p[None, :-1, None]
        self._blist = self.breaks.tolist()
        self.kind = kind
        self.T = float(self.breaks[-1] - self.breaks[0])
        t = np.linspace(self.breaks[0], self.breaks[-1], num) if np.ndim(num) == 0 else np.asarray(num, float)
        self.t = t
        self.q, self.qd, self.qdd = self.sample(t)

    @property
    def duration(self) -> float:
        """Duration T (s)."""
        return self.T

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.coef.shape[2]

    @staticmethod
    def _horner(c: Array, tau: Array | float) -> Array:
        out = c[-1]
        for k in range(c.shape[0] - 2, -1, -1):
            out = out * tau + c[k]
        return out

    def sample(self, t: float | ArrayLike) -> tuple[Array, Array, Array]:
        """``(q, qd, qdd)`` at time(s) t: (n,) each for a scalar, (m, n) for an array.

        On ``[0, T]``, ends included, the polynomials themselves (so a cubic's acceleration
        at t = 0 is 6 D / T^2, not 0). Outside, the trajectory holds its end point: position
        clamped, velocity and acceleration zero."""
        if np.ndim(t) == 0:
            t = float(t)
            b = self._blist
            if t < b[0] or t > b[-1]:
                i = 0 if t < b[0] else len(b) - 2
                tau = 0.0 if t < b[0] else b[-1] - b[-2]
                z = np.zeros(self.n)
                return self._horner(self.coef[i], tau), z, z.copy()
            if t == b[-1]:
                i = len(b) - 2
                tau = b[-1] - b[-2]
                return (self._horner(self.coef[i], tau), self._horner(self._dcoef[i], tau),
                        self._horner(self._ddcoef[i], tau))
            i = bisect.bisect_right(b, t) - 1
            tau = t - b[i]
            return (self._horner(self.coef[i], tau), self._horner(self._dcoef[i], tau),
                    self._horner(self._ddcoef[i], tau))
        t = np.asarray(t, dtype=float)
        tc = np.clip(t, self.breaks[0], self.breaks[-1])
        i = np.clip(np.searchsorted(self.breaks, tc, side="right") - 1, 0, len(self.breaks) - 2)
        tau = (tc - self.breaks[i])[:, None]
        inside = ((t >= self.breaks[0]) & (t <= self.breaks[-1]))[:, None]
        q = self._horner(np.moveaxis(self.coef[i], 1, 0), tau)
        qd = self._horner(np.moveaxis(self._dcoef[i], 1, 0), tau) * inside
        qdd = self._horner(np.moveaxis(self._ddcoef[i], 1, 0), tau) * inside
        return q, qd, qdd

    def __call__(self, t: float | ArrayLike) -> tuple[Array, Array, Array]:
        return self.sample(t)

    def __repr__(self) -> str:
        return f"Trajectory({self.kind}, n={self.n}, T={self.T:.4g} s, {len(self.breaks) - 1} segments)"


def _vec(x: ArrayLike, n: int | None = None) -> Array:
    a = np.atleast_1d(np.asarray(x, dtype=float))
    return a if n is None else np.broadcast_to(a, (n,)).astype(float)


def _shift(c: Array, h: float) -> Array:
    """Coefficients (deg+1, ...) of p(tau + h) given those of p(tau)."""
    deg = c.shape[0] - 1
    out = np.zeros_like(c)
    for k in range(deg + 1):
        for j in range(k, deg + 1):
            out[k] = out[k] + comb(j, k) * h ** (j - k) * c[j]
    return out


def _merge(pieces: list[tuple[Array, Array]], num: int | ArrayLike, kind: str) -> Trajectory:
    """Build one Trajectory from per-joint piecewise polynomials (breaks_j, coef_j (k_j, deg+1)).

    Joints that finish early hold their final position."""
    deg = max(c.shape[1] for _, c in pieces) - 1
    T = max(b[-1] for b, _ in pieces)
    allb = np.unique(np.concatenate([b for b, _ in pieces] + [[0.0, T]]))
    keep = np.concatenate(([True], np.diff(allb) > 1e-12 * max(T, 1.0)))
    allb = allb[keep]
    k = len(allb) - 1
    coef = np.zeros((k, deg + 1, len(pieces)))
    for j, (b, c) in enumerate(pieces):
        cj = np.zeros((c.shape[0], deg + 1))
        cj[:, : c.shape[1]] = c
        for s in range(k):
            mid = 0.5 * (allb[s] + allb[s + 1])
            if mid >= b[-1]:  # finished: hold the end position
                coef[s, 0, j] = Trajectory._horner(cj[-1], b[-1] - b[-2])
                continue
            i = min(max(int(np.searchsorted(b, mid, side="right")) - 1, 0), len(b) - 2)
            coef[s, :, j] = _shift(cj[i], allb[s] - b[i])
    return Trajectory(allb, coef, num=num, kind=kind)


# ---------------------------------------------------------------------------- polynomials
def cubic(q0: ArrayLike, qf: ArrayLike, T: float, *, qd0: ArrayLike = 0.0, qdf: ArrayLike = 0.0,
          num: int | ArrayLike = 101) -> Trajectory:
    """Cubic polynomial from ``q0`` to ``qf`` in time ``T`` with end velocities ``qd0``, ``qdf``."""
    q0 = _vec(q0)
    n = q0.size
    qf, v0, vf = _vec(qf, n), _vec(qd0, n), _vec(qdf, n)
    D = qf - q0
    c = np.stack((q0, v0, (3 * D - (2 * v0 + vf) * T) / T**2, (-2 * D + (v0 + vf) * T) / T**3))
    return Trajectory([0.0, T], c[None], num=num, kind="cubic")


def quintic(q0: ArrayLike, qf: ArrayLike, T: float, *, qd0: ArrayLike = 0.0, qdf: ArrayLike = 0.0,
            qdd0: ArrayLike = 0.0, qddf: ArrayLike = 0.0, num: int | ArrayLike = 101) -> Trajectory:
    """Quintic polynomial with given end positions, velocities and accelerations (``jtraj``)."""
    q0 = _vec(q0)
    n = q0.size
    qf, v0, vf, a0, af = _vec(qf, n), _vec(qd0, n), _vec(qdf, n), _vec(qdd0, n), _vec(qddf, n)
    M = np.array([[T**3, T**4, T**5], [3 * T**2, 4 * T**3, 5 * T**4], [6 * T, 12 * T**2, 20 * T**3]])
    rhs = np.stack((qf - q0 - v0 * T - 0.5 * a0 * T**2, vf - v0 - a0 * T, af - a0))
    c345 = np.linalg.solve(M, rhs)
    c = np.vstack((q0, v0, 0.5 * a0, c345))
    return Trajectory([0.0, T], c[None], num=num, kind="quintic")


jtraj = quintic


# ---------------------------------------------------------------------------- trapezoidal
def _trap_pieces(q0: float, qf: float, T: float, V: float) -> tuple[Array, Array]:
    """One joint's LSPB with cruise speed |V| over [0, T] (breaks, coef (3, 3))."""
    D = qf - q0
    if D == 0 or T == 0:
        return np.array([0.0, max(T, 1e-12)]), np.array([[q0, 0.0, 0.0]])
    V = abs(V) * np.sign(D)
    tb = (q0 - qf + V * T) / V
    a = V / tb
    qb = q0 + 0.5 * a * tb**2
    qc = qf - 0.5 * a * tb**2
    breaks = np.array([0.0, tb, T - tb, T])
    coef = np.array([[q0, 0.0, 0.5 * a], [qb, V, 0.0], [qc, V, -0.5 * a]])
    return breaks, coef


def _min_time(D: Array, vmax: Array, amax: Array) -> Array:
    """Minimum LSPB time per joint for distances |D| under limits vmax, amax."""
    D = np.abs(D)
    tri = D <= vmax**2 / amax
    return np.where(tri, 2 * np.sqrt(D / amax), D / vmax + vmax / amax)


def _speed_for_time(D: Array, T: float, amax: Array) -> Array:
    """Cruise speed of the LSPB covering |D| in time T accelerating at amax (T >= min time)."""
    D = np.abs(D)
    disc = np.maximum(amax**2 * T**2 - 4 * amax * D, 0.0)
    return 0.5 * (amax * T - np.sqrt(disc))


def lspb(q0: ArrayLike, qf: ArrayLike, T: float | None = None, *, V: ArrayLike | None = None,
         vmax: ArrayLike | None = None, amax: ArrayLike | None = None, num: int | ArrayLike = 101) -> Trajectory:
    """Linear segment with parabolic blends (trapezoidal velocity), rest to rest.

    Either give the time ``T`` (optionally the cruise speed ``V``, default
    ``1.5 |qf - q0| / T`` as in the Toolbox; it must lie in ``(|D|/T, 2|D|/T]``), or the
    limits ``vmax`` and ``amax`` for the minimum-time motion (for several joints this is
    :func:`synchronous`: the slowest joint sets the time).
    """
    q0 = _vec(q0)
    n = q0.size
    qf = _vec(qf, n)
    if T is None:
        if vmax is None or amax is None:
            raise ValueError("lspb needs either the time T or both vmax and amax")
        return synchronous(q0, qf, vmax=vmax, amax=amax, num=num)
    D = np.abs(qf - q0)
    Vv = 1.5 * D / T if V is None else np.abs(_vec(V, n))
    bad = (D > 0) & ((Vv <= D / T * (1 + 1e-12)) | (Vv > 2 * D / T * (1 + 1e-12)))
    if bad.any():
        j = int(np.argmax(bad))
        raise ValueError(f"lspb: cruise speed V[{j}] = {Vv[j]:.4g} must lie in ({D[j] / T:.4g}, {2 * D[j] / T:.4g}]")
    Vv = np.minimum(Vv, 2 * D / T)
    return _merge([_trap_pieces(q0[j], qf[j], T, Vv[j]) for j in range(n)], num, "lspb")


def synchronous(q0: ArrayLike, qf: ArrayLike, *, vmax: ArrayLike, amax: ArrayLike, T: float | None = None,
                num: int | ArrayLike = 101) -> Trajectory:
    """Synchronous multi-axis LSPB: all joints start and finish together.

    The slowest joint (the largest minimum time under its ``vmax``/``amax``) sets the time
    (or ``T`` if given and longer); every other joint covers its distance in that time
    accelerating at its own ``amax`` with a lower cruise speed, so no limit is exceeded.
    """
    q0 = _vec(q0)
    n = q0.size
    qf, vm, am = _vec(qf, n), np.abs(_vec(vmax, n)), np.abs(_vec(amax, n))
    D = qf - q0
    Tmin = float(np.max(_min_time(D, vm, am)))
    Tt = Tmin if T is None else max(float(T), Tmin)
    V = np.minimum(_speed_for_time(D, Tt, am), vm)
    return _merge([_trap_pieces(q0[j], qf[j], Tt, V[j]) for j in range(n)], num, "synchronous")


def asynchronous(q0: ArrayLike, qf: ArrayLike, *, vmax: ArrayLike, amax: ArrayLike,
                 num: int | ArrayLike = 101) -> Trajectory:
    """Asynchronous multi-axis LSPB: each joint moves in its own minimum time and then holds."""
    q0 = _vec(q0)
    n = q0.size
    qf, vm, am = _vec(qf, n), np.abs(_vec(vmax, n)), np.abs(_vec(amax, n))
    D = qf - q0
    Tj = _min_time(D, vm, am)
    V = np.minimum(_speed_for_time(D, Tj, am), vm)
    return _merge([_trap_pieces(q0[j], qf[j], float(Tj[j]), V[j]) for j in range(n)], num, "asynchronous")


# ---------------------------------------------------------------------------- via points
def spline(t_via: ArrayLike, q_via: ArrayLike, *, qd0: ArrayLike = 0.0, qdf: ArrayLike = 0.0,
           num: int | ArrayLike = 101) -> Trajectory:
    """Cubic spline through via points ``q_via`` (k, n) at times ``t_via`` (k,), with
    continuous acceleration and end velocities ``qd0``, ``qdf`` (clamped spline)."""
    from scipy.interpolate import CubicSpline

    tv = np.asarray(t_via, dtype=float)
    qv = np.asarray(q_via, dtype=float)
    if qv.ndim == 1:
        qv = qv[:, None]
    n = qv.shape[1]
    cs = CubicSpline(tv - tv[0], qv, bc_type=((1, _vec(qd0, n)), (1, _vec(qdf, n))))
    coef = cs.c[::-1].transpose(1, 0, 2)  # (k-1, 4, n), ascending powers
    return Trajectory(tv - tv[0], coef, num=num, kind="spline")


# ---------------------------------------------------------------------------- 4-3-4
def poly434(q0: ArrayLike, q_lift: ArrayLike, q_set: ArrayLike, qf: ArrayLike, t1: float, t2: float, t3: float,
            *, num: int | ArrayLike = 101) -> Trajectory:
    """The 4-3-4 trajectory: a quartic lift-off segment (duration t1) from rest at ``q0``
    to ``q_lift``, a cubic segment (t2) to the set-down point ``q_set`` and a quartic
    set-down segment (t3) to rest at ``qf``, with continuous position, velocity and
    acceleration (Fu, Gonzalez & Lee, *Robotics*, sec. 4.4)."""
    q0 = _vec(q0)
    n = q0.size
    q1, q2, qf = _vec(q_lift, n), _vec(q_set, n), _vec(qf, n)
    # unknowns: a0..a4 (seg 1), b0..b3 (seg 2), c0..c4 (seg 3)
    A = np.zeros((14, 14))
    rhs = np.zeros((14, n))
    r = 0
    A[r, 0] = 1; rhs[r] = q0; r += 1                                   # q(0)
    A[r, 1] = 1; r += 1                                                # qd(0) = 0
    A[r, 2] = 2; r += 1                                                # qdd(0) = 0
    A[r, 0:5] = [1, t1, t1**2, t1**3, t1**4]; rhs[r] = q1; r += 1     # lift-off position
    A[r, 5] = 1; rhs[r] = q1; r += 1                                   # seg 2 starts at lift-off
    A[r, 0:5] = [0, 1, 2 * t1, 3 * t1**2, 4 * t1**3]; A[r, 6] = -1; r += 1    # velocity continuity
    A[r, 0:5] = [0, 0, 2, 6 * t1, 12 * t1**2]; A[r, 7] = -2; r += 1           # acceleration continuity
    A[r, 5:9] = [1, t2, t2**2, t2**3]; rhs[r] = q2; r += 1            # set-down position
    A[r, 9] = 1; rhs[r] = q2; r += 1                                   # seg 3 starts at set-down
    A[r, 5:9] = [0, 1, 2 * t2, 3 * t2**2]; A[r, 10] = -1; r += 1
    A[r, 5:9] = [0, 0, 2, 6 * t2]; A[r, 11] = -2; r += 1
    A[r, 9:14] = [1, t3, t3**2, t3**3, t3**4]; rhs[r] = qf; r += 1    # final position
    A[r, 9:14] = [0, 1, 2 * t3, 3 * t3**2, 4 * t3**3]; r += 1          # qd(T) = 0
    A[r, 9:14] = [0, 0, 2, 6 * t3, 12 * t3**2]; r += 1                 # qdd(T) = 0
    x = np.linalg.solve(A, rhs)
    coef = np.zeros((3, 5, n))
    coef[0] = x[0:5]
    coef[1, :4] = x[5:9]
    coef[2] = x[9:14]
    return Trajectory(np.cumsum([0.0, t1, t2, t3]), coef, num=num, kind="4-3-4")


def synchro(q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike) -> Array:
    """Synchronised joint velocities (n,), signed: the slowest joint at its ``vmax`` sets the
    time ``Tm = max |qf - q0| / vmax``, every joint moves at ``(qf - q0) / Tm`` (the
    paper's ``robot.Synchro(qi, qf, vqMax)``)."""
    q0 = _vec(q0)
    n = q0.size
    D = _vec(qf, n) - q0
    Tm = float(np.max(np.abs(D) / np.abs(_vec(vmax, n))))
    return D / Tm if Tm > 0 else np.zeros(n)


def _peak(traj: Trajectory, which: int) -> Array:
    """Exact peak |qd| (which=1) or |qdd| (which=2) per joint: the maximum over segment
    ends and the real roots of the next derivative inside each segment."""
    c = traj._dcoef if which == 1 else traj._ddcoef
    peak = np.zeros(traj.n)
    for s in range(len(traj.breaks) - 1):
        h = traj.breaks[s + 1] - traj.breaks[s]
        for j in range(traj.n):
            cj = c[s, :, j]
            dc = np.trim_zeros(cj[1:] * np.arange(1, len(cj)), "b")
            cands = [0.0, h]
            if len(dc) > 1:
                roots = P.polyroots(dc)
                cands += [r.real for r in roots if abs(r.imag) < 1e-9 and 0 < r.real < h]
            peak[j] = max(peak[j], max(abs(P.polyval(tau, cj)) for tau in cands))
    return peak


def path434(q0: ArrayLike, qf: ArrayLike, vmax: ArrayLike, *, tacc: float = 0.1, tdec: float = 0.1,
            amax: ArrayLike | None = None, num: int | ArrayLike = 101) -> Trajectory:
    """EjsRL's 4-3-4 path (``Synchro`` + ``Coef434(tace, tdec, vSyncro)``), synchronised.

    The joints move together at the synchronised speeds of :func:`synchro`; lift-off is
    ``tacc`` s after the start at ``q0 + v tacc / 2`` and set-down ``tdec`` s before the end
    at ``qf - v tdec / 2`` (the points a linear ramp to speed v would reach). The quartic
    blends overshoot v slightly, so all durations are then stretched by the exact factor
    that keeps every joint within ``vmax`` (and ``amax`` if given). ``sample(t)[2]`` is the
    acceleration plan ``APlan`` for an ODE ``q' = v, v' = a(t)``.
    """
    q0 = _vec(q0)
    n = q0.size
    qf, vm = _vec(qf, n), np.abs(_vec(vmax, n))
    v = synchro(q0, qf, vm)
    D = qf - q0
    moving = np.abs(v) > 0
    if not moving.any():
        return poly434(q0, q0, qf, qf, tacc, 1e-3, tdec, num=num)
    Tm = float(np.max(np.abs(D[moving] / v[moving])))
    t2 = Tm - 0.5 * (tacc + tdec)
    if t2 <= 0:
        raise ValueError(
            f"path434: the motion takes {Tm:.4g} s at the synchronised speed, less than (tacc + tdec)/2 = "
            f"{0.5 * (tacc + tdec):.4g} s; shorten tacc/tdec or lower vmax"
        )
    q1 = q0 + 0.5 * v * tacc
    q2 = qf - 0.5 * v * tdec
    tr = poly434(q0, q1, q2, qf, tacc, t2, tdec, num=2)
    scale = float(np.max(_peak(tr, 1)[moving] / vm[moving]))
    if amax is not None:
        am = np.abs(_vec(amax, n))
        scale = max(scale, float(np.sqrt(np.max(_peak(tr, 2)[moving] / am[moving]))))
    scale = max(scale, 1.0)
    return poly434(q0, q1, q2, qf, tacc * scale, t2 * scale, tdec * scale, num=num)


# ---------------------------------------------------------------------------- Cartesian
@dataclass
class CartesianTrajectory:
    """Straight-line Cartesian motion: position along the segment, orientation by SLERP,
    both following the same scalar time profile ``s(t)`` in [0, 1].

    Attributes: ``t`` (m,), ``s`` (m,), ``poses`` (m, 4, 4) world poses, ``T`` duration.
    """

    T0: Array
    T1: Array
    profile: Trajectory
    t: Array
    s: Array
    poses: Array

    @property
    def T(self) -> float:
        """Duration (s)."""
        return self.profile.T

    def sample(self, t: float) -> tuple[Array, Array]:
        """Pose (4, 4) and world twist ``[vx vy vz wx wy wz]`` (6,) at time t."""
        s, sd, _ = self.profile.sample(t)
        T = _interp(self.T0, self.T1, float(s[0]))
        v = np.empty(6)
        v[:3] = (self.T1[:3, 3] - self.T0[:3, 3]) * sd[0]
        v[3:] = tr2angvec_vec(self.T1[:3, :3] @ self.T0[:3, :3].T) * sd[0]
        return T, v


_interp = trinterp


def ctraj(T0: ArrayLike, T1: ArrayLike, T: float = 1.0, *, profile: str = "quintic",
          num: int | ArrayLike = 101) -> CartesianTrajectory:
    """Cartesian straight line from pose ``T0`` to ``T1`` (4, 4) in ``T`` s.

    ``profile``: ``"quintic"`` (rest to rest, smooth acceleration), ``"lspb"``
    (trapezoidal speed) or ``"linear"`` (constant speed)."""
    T0 = np.asarray(T0, dtype=float)
    T1 = np.asarray(T1, dtype=float)
    if profile == "quintic":
        prof = quintic([0.0], [1.0], T, num=num)
    elif profile == "lspb":
        prof = lspb([0.0], [1.0], T, num=num)
    elif profile == "linear":
        prof = Trajectory([0.0, T], [[[0.0], [1.0 / T]]], num=num, kind="linear")
    else:
        raise ValueError(f"unknown profile {profile!r}; use 'quintic', 'lspb' or 'linear'")
    s = prof.q[:, 0]
    poses = np.array([_interp(T0, T1, float(si)) for si in s])
    return CartesianTrajectory(T0=T0, T1=T1, profile=prof, t=prof.t, s=s, poses=poses)


from ._mstraj import mstraj  # noqa: E402  (it builds a Trajectory)
