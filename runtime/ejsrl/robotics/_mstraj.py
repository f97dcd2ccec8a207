"""``mstraj``: a multi-segment, multi-axis path through via points (Corke's planner).

The same algorithm, step for step, as Robotics Toolbox for Python's ``mstraj`` (and
MATLAB's): each segment is a straight line at the speed of its slowest axis, and the
corners are rounded by quintic blends of duration ``tacc`` (so the via points themselves
are passed near, not through, when ``tacc > 0``). Times are quantised to ``dt`` as there,
and the samples are the Toolbox's: the first sample is one step ``dt`` after the start.

The result is a :class:`~ejsrl.robotics.trajectory.Trajectory` (``t``, ``q``, ``qd``,
``qdd``; ``sample(t)`` evaluates the same blends and lines between samples) with the
Toolbox's extras ``arrive`` (planned arrival time at each via point), ``info`` (per
segment: slowest axis, segment time, clock) and ``via``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from .trajectory import Trajectory  # imported below, when mstraj runs: trajectory imports this module

__all__ = ["mstraj", "MstrajInfo"]

Array = NDArray[np.float64]


class MstrajInfo(NamedTuple):
    """One segment of an ``mstraj`` plan: its slowest axis (None for the final blend, nan
    when segment times were given), its time (s) and the clock at its start (s)."""

    slowest: int | float | None
    segtime: float
    clock: float


def _mrange(start: float, stop: float, step: float) -> Array:
    """MATLAB's ``start:step:stop`` (the end included), on multiples of ``step``."""
    return np.arange(round(start / step), round(stop / step) + 1) * step


def _blend(q0: Array, q1: Array, tv: Array, qd0: Array, qd1: Array) -> tuple[Array, Array, Array, Array, float]:
    """The Toolbox's ``jtraj`` on the times ``tv`` (from 0): (q, qd, qdd) samples and the
    coefficients (6, n) of the quintic in ascending powers of local time, and its span."""
    tscal = float(np.max(tv))
    ts = tv / tscal
    A = 6 * (q1 - q0) - 3 * (qd1 + qd0) * tscal
    B = -15 * (q1 - q0) + (8 * qd0 + 7 * qd1) * tscal
    C = 10 * (q1 - q0) - (6 * qd0 + 4 * qd1) * tscal
    E = qd0 * tscal
    z = np.zeros_like(A)
    tt = np.array([ts**5, ts**4, ts**3, ts**2, ts, np.ones(ts.shape)]).T
    q = tt @ np.array([A, B, C, z, E, q0])
    qd = tt @ np.array([z, 5 * A, 4 * B, 3 * C, z, E]) / tscal
    qdd = tt @ np.array([z, z, 20 * A, 12 * B, 6 * C, z]) / tscal**2
    coef = np.array([q0, E / tscal, z, C / tscal**3, B / tscal**4, A / tscal**5])
    return q, qd, qdd, coef, tscal


def mstraj(
    viapoints: ArrayLike,
    dt: float,
    tacc: float | ArrayLike,
    qdmax: float | ArrayLike | None = None,
    tsegment: ArrayLike | None = None,
    q0: ArrayLike | None = None,
    qd0: ArrayLike | None = None,
    qdf: ArrayLike | None = None,
) -> Trajectory:
    """A path for N axes through via points: straight segments joined by smooth blends.

    Args:
        viapoints: (m, N) one via point per row; the first row is the start unless ``q0``
            is given.
        dt: sample time (s).
        tacc: blend (acceleration) time at each via point (s): a scalar, or one per segment.
        qdmax: maximum speed of each axis (scalar or (N,)), units/s; the segment time is
            that of its slowest axis (at least ``2 tacc``). Give this or ``tsegment``.
        tsegment: the time of each segment (s), instead of ``qdmax``.
        q0: start (N,) (default: the first via point).
        qd0, qdf: start and final velocities (N,) (default zero).

    Returns:
        a :class:`Trajectory` with ``t`` (K,), ``q``, ``qd``, ``qdd`` (K, N) exactly as the
        Toolbox's ``mstraj`` gives them, plus ``arrive`` (m,), ``info`` (list of
        :class:`MstrajInfo`) and ``via``.

    Works in joint space or on any coordinates (Cartesian x, y, z, RPY angles...).
    """
    via = np.atleast_2d(np.asarray(viapoints, dtype=float))
    if q0 is None:
        q_start = via[0].copy()
        via = via[1:]
    else:
        q_start = np.atleast_1d(np.asarray(q0, dtype=float)).ravel()
        if via.shape[1] != len(q_start):
            raise ValueError(f"mstraj: the via points have {via.shape[1]} columns but q0 has {len(q_start)} values")
    ns, nj = via.shape
    if ns == 0:
        raise ValueError("mstraj: give at least one via point after the start")
    if dt <= 0:
        raise ValueError(f"mstraj: dt must be positive, got {dt}")
    if qdmax is not None and tsegment is not None:
        raise ValueError("mstraj: give qdmax or tsegment, not both")
    tseg_given = None if tsegment is None else np.atleast_1d(np.asarray(tsegment, dtype=float)).ravel()
    if qdmax is None:
        if tseg_given is None:
            raise ValueError("mstraj: give qdmax (maximum axis speeds) or tsegment (segment times)")
        if len(tseg_given) != ns:
            raise ValueError(f"mstraj: tsegment has {len(tseg_given)} values for {ns} segments")
        vmax = None
    else:
        vmax = np.broadcast_to(np.asarray(qdmax, dtype=float), (nj,)).astype(float) if np.ndim(qdmax) == 0 \
            else np.asarray(qdmax, dtype=float).ravel()
        if len(vmax) != nj:
            raise ValueError(f"mstraj: qdmax has {len(vmax)} values for {nj} axes")
        if np.any(vmax <= 0):
            raise ValueError("mstraj: every qdmax must be positive")
    Tacc = np.full(ns, float(tacc)) if np.ndim(tacc) == 0 else np.asarray(tacc, dtype=float).ravel()
    if len(Tacc) != ns:
        raise ValueError(f"mstraj: tacc has {len(Tacc)} values for {ns} segments")
    qd_prev = np.zeros(nj) if qd0 is None else np.asarray(qd0, dtype=float).ravel()
    qd_end = np.zeros(nj) if qdf is None else np.asarray(qdf, dtype=float).ravel()
    if len(qd_prev) != nj or len(qd_end) != nj:
        raise ValueError(f"mstraj: qd0 and qdf need {nj} values")

    q_prev = q_start
    q_last = q_start  # the last sample so far (the next blend starts there)
    clock = 0.0
    arrive = np.zeros(ns)
    qs: list[Array] = []
    qds: list[Array] = []
    qdds: list[Array] = []
    info: list[MstrajInfo] = []
    spans: list[float] = []  # pieces for sample(): duration and coefficients (6, N)
    coefs: list[Array] = []
    tacc2 = 0.0
    tseg = 0.0
    q_next = q_start
    for seg in range(ns):
        q_next = via[seg]
        tacc_seg = math.ceil(Tacc[seg] / dt) * dt
        tacc2 = math.ceil(tacc_seg / 2 / dt) * dt
        taccx = tacc2 if seg == 0 else tacc_seg
        dq = q_next - q_prev
        slowest: int | float
        if vmax is not None:
            tl = np.ceil(np.abs(dq) / vmax / dt) * dt
            tt = taccx + tl
            slowest = int(np.argmax(tt))
            tseg = float(tt[slowest])
            if tseg <= 2 * tacc_seg:
                tseg = 2 * tacc_seg
        else:
            assert tseg_given is not None
            tseg = float(tseg_given[seg])
            slowest = math.nan
        info.append(MstrajInfo(slowest, tseg, clock))
        arrive[seg] = clock + tseg + (tacc2 if seg > 0 else 0.0)
        qd = dq / tseg
        if taccx > 0:
            q, v, a, coef, span = _blend(q_last, q_prev + tacc2 * qd, _mrange(0, taccx, dt), qd_prev, qd)
            qs.append(q[1:])
            qds.append(v[1:])
            qdds.append(a[1:])
            spans.append(span)
            coefs.append(coef)
        clock = clock + taccx
        times = _mrange(tacc2 + dt, tseg - tacc2, dt)
        if len(times):
            s = times / tseg
            lin = (1 - s)[:, None] * q_prev + s[:, None] * q_next
            qs.append(lin)
            qds.append(np.tile(qd, (len(times), 1)))
            qdds.append(np.zeros((len(times), nj)))
            q_last = lin[-1]
            t0 = times[0] - dt
            c = np.zeros((6, nj))
            c[0] = q_prev + (t0 / tseg) * dq
            c[1] = dq / tseg
            spans.append(times[-1] - t0)
            coefs.append(c)
            clock += len(times) * dt
        q_prev = q_next
        qd_prev = qd
    if tacc2 > 0:  # the final blend
        q, v, a, coef, span = _blend(q_last, q_next, _mrange(0, tacc2, dt), qd_prev, qd_end)
        qs.append(q[1:])
        qds.append(v[1:])
        qdds.append(a[1:])
        spans.append(span)
        coefs.append(coef)
    info.append(MstrajInfo(None, tseg, clock))
    Q = np.vstack(qs)
    t = dt * np.arange(len(Q))
    breaks = np.concatenate(([0.0], np.cumsum(spans))) - dt  # the first sample is dt after the start
    from .trajectory import Trajectory

    traj = Trajectory(breaks, np.array(coefs), num=t, kind="mstraj")
    traj.q, traj.qd, traj.qdd = Q, np.vstack(qds), np.vstack(qdds)
    traj.arrive = arrive  # type: ignore[attr-defined]
    traj.info = info  # type: ignore[attr-defined]
    traj.via = via  # type: ignore[attr-defined]
    return traj
