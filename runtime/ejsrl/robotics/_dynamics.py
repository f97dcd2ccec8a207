"""Batched recursive Newton-Euler on plain arrays (private).

The reference implementation: ``Robot`` runs the generated code of :mod:`._kernels` by
default, and the tests check it against these functions (``Robot._fast = False``).

Rigid-body part only (no motor armature, no friction: the Robot adds those). Works on
``(m, n)`` batches of configurations at once; the loops run over the n links only.
Quantities of link i are expressed in its frame i (Luh-Walker-Paul for standard DH,
Craig's formulation for modified DH).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._kinematics import cross

Array = NDArray[np.float64]


def _rt(R: Array, v: Array) -> Array:
    """``R.T @ v`` for batches R (m, 3, 3), v (m, 3)."""
    return (v[:, None, :] @ R)[:, 0, :]


def _r(R: Array, v: Array) -> Array:
    """``R @ v`` for batches R (m, 3, 3), v (m, 3)."""
    return (R @ v[:, :, None])[:, :, 0]


def rne_rigid(
    A: Array,
    qd: Array,
    qdd: Array,
    a0: Array,
    m: Array,
    r: Array,
    I: Array,
    prismatic: Array,
    mdh: bool,
) -> Array:
    """Joint forces (m, n) of the rigid links.

    Args:
        A: (m, n, 4, 4) link transforms ``T_{i-1}_i`` at the configurations.
        qd, qdd: (m, n) joint velocities and accelerations.
        a0: (3,) or (m, 3) acceleration imposed on the base, in the base frame
            (``-gravity`` to include gravity).
        m, r, I: (n,), (n, 3), (n, 3, 3) link masses, centres of mass and inertias in
            each link frame.
        prismatic: (n,) bool.
        mdh: modified DH convention.
    """
    M, n = qd.shape
    R = A[..., :3, :3]
    p = A[..., :3, 3]
    w = np.zeros((M, 3))
    wd = np.zeros((M, 3))
    acc = np.broadcast_to(np.asarray(a0, dtype=float), (M, 3)).copy()
    Fs: list[Array] = []
    Ns: list[Array] = []
    pss: list[Array] = []
    zs: list[Array] = []
    for i in range(n):
        Ri = R[:, i]
        qdi = qd[:, i, None]
        qddi = qdd[:, i, None]
        if not mdh:
            # Joint i moves about z_{i-1}; in frame i that axis is R^T z.
            z = Ri[:, 2, :]  # (m, 3): third row of R = R^T e_z
            ps = _rt(Ri, p[:, i])  # origin i-1 -> origin i, in frame i
            w_t = _rt(Ri, w)
            wd_t = _rt(Ri, wd)
            a_t = _rt(Ri, acc)
            if prismatic[i]:
                w = w_t
                wd = wd_t
                acc = a_t + z * qddi + cross(wd, ps) + 2.0 * cross(w, z * qdi) + cross(w, cross(w, ps))
            else:
                w = w_t + z * qdi
                wd = wd_t + z * qddi + cross(w_t, z * qdi)
                acc = a_t + cross(wd, ps) + cross(w, cross(w, ps))
            pss.append(ps)
        else:
            z = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (M, 3))
            pi = p[:, i]
            a_prev = acc + cross(wd, pi) + cross(w, cross(w, pi))
            w_t = _rt(Ri, w)
            wd_t = _rt(Ri, wd)
            a_t = _rt(Ri, a_prev)
            if prismatic[i]:
                w = w_t
                wd = wd_t
                acc = a_t + 2.0 * cross(w, z * qdi) + z * qddi
            else:
                w = w_t + z * qdi
                wd = wd_t + cross(w_t, z * qdi) + z * qddi
                acc = a_t
        zs.append(z)
        ri = r[i]
        ac = acc + cross(wd, ri) + cross(w, cross(w, ri))
        Ii = I[i]
        Fs.append(m[i] * ac)
        Ns.append(wd @ Ii + cross(w, w @ Ii))
    tau = np.empty((M, n))
    f = np.zeros((M, 3))
    nn = np.zeros((M, 3))
    for i in range(n - 1, -1, -1):
        if i < n - 1:
            Rn = R[:, i + 1]
            fR = _r(Rn, f)
            nR = _r(Rn, nn)
        else:
            fR = f
            nR = nn
        if not mdh:
            ps = pss[i]
            nn = nR + cross(ps, fR) + cross(ps + r[i], Fs[i]) + Ns[i]
        else:
            if i < n - 1:
                nn = nR + cross(p[:, i + 1], fR) + cross(r[i], Fs[i]) + Ns[i]
            else:
                nn = cross(r[i], Fs[i]) + Ns[i]
        f = fR + Fs[i]
        z = zs[i]
        tau[:, i] = np.einsum("mk,mk->m", f if prismatic[i] else nn, z)
    return tau


def inertia_composite(F: Array, m: Array, r: Array, I: Array, prismatic: Array, mdh: bool) -> Array:
    """Joint-space inertia (M, n, n) of the rigid links from the world frames F (M, n+1, 4, 4).

    ``M = sum_i m_i Jv_i^T Jv_i + Jw_i^T (R_i I_i R_i^T) Jw_i`` with the centre-of-mass
    Jacobians of every link built at once (link i depends on joints 1..i only), then
    reduced with two batched matrix products; no loop over configurations or links.
    """
    Mb, N1 = F.shape[0], F.shape[1]
    n = N1 - 1
    Fj = F[:, 1:] if mdh else F[:, :-1]
    z = Fj[:, :, :3, 2]  # (M, n, 3) joint axes
    o = Fj[:, :, :3, 3]
    R = F[:, 1:, :3, :3]  # (M, n, 3, 3) link rotations
    com = (R @ r[None, :, :, None])[..., 0] + F[:, 1:, :3, 3]  # (M, n, 3)
    lower = np.tril(np.ones((n, n), dtype=bool))[None, :, :, None]  # link i, joint j <= i
    d = com[:, :, None, :] - o[:, None, :, :]  # (M, n_links, n_joints, 3)
    zz = np.broadcast_to(z[:, None, :, :], d.shape)
    Jv = cross(zz, d)
    Jw = zz
    if prismatic.any():
        pm = prismatic[None, None, :, None]
        Jv = np.where(pm, zz, Jv)
        Jw = np.where(pm, 0.0, zz)
    Jv = np.where(lower, Jv, 0.0) * np.sqrt(m)[None, :, None, None]
    Jw = np.where(lower, Jw, 0.0)
    Iw = R @ I[None] @ np.swapaxes(R, -1, -2)  # (M, n, 3, 3)
    JwI = Jw @ Iw  # (M, n_links, n_joints, 3)
    A = np.swapaxes(Jv, 1, 2).reshape(Mb, n, n * 3)
    B = np.swapaxes(Jw, 1, 2).reshape(Mb, n, n * 3)
    C = np.swapaxes(JwI, 1, 2).reshape(Mb, n, n * 3)
    return A @ np.swapaxes(A, 1, 2) + C @ np.swapaxes(B, 1, 2)


def _cr(a: list[float], b: list[float]) -> list[float]:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _mt(R: list[list[float]], v: list[float]) -> list[float]:
    """R^T v."""
    return [R[0][0] * v[0] + R[1][0] * v[1] + R[2][0] * v[2],
            R[0][1] * v[0] + R[1][1] * v[1] + R[2][1] * v[2],
            R[0][2] * v[0] + R[1][2] * v[1] + R[2][2] * v[2]]


def _mv(R: list[list[float]], v: list[float]) -> list[float]:
    """R v."""
    return [R[0][0] * v[0] + R[0][1] * v[1] + R[0][2] * v[2],
            R[1][0] * v[0] + R[1][1] * v[1] + R[1][2] * v[2],
            R[2][0] * v[0] + R[2][1] * v[1] + R[2][2] * v[2]]


def rne_rigid_single(A: Array, qd: Array, qdd: Array, a0: Array, m: list[float], r: list[list[float]],
                     I: list[list[list[float]]], prismatic: list[bool], mdh: bool) -> Array:
    """:func:`rne_rigid` for one configuration with plain Python floats.

    For a single arm state, NumPy's per-call overhead on 3-vectors costs far more than the
    arithmetic, so the same recursion runs here on lists (about 10x faster)."""
    n = len(m)
    Al = A.tolist()
    qdl = qd.tolist()
    qddl = qdd.tolist()
    w = [0.0, 0.0, 0.0]
    wd = [0.0, 0.0, 0.0]
    acc = [float(x) for x in a0]
    Rs = [[row[:3] for row in Ai[:3]] for Ai in Al]
    ps = [[Ai[0][3], Ai[1][3], Ai[2][3]] for Ai in Al]
    F: list[list[float]] = []
    N: list[list[float]] = []
    pst: list[list[float]] = []
    zs: list[list[float]] = []
    for i in range(n):
        R = Rs[i]
        q1, q2 = qdl[i], qddl[i]
        if not mdh:
            z = R[2]
            p = _mt(R, ps[i])
            w_t = _mt(R, w)
            wd_t = _mt(R, wd)
            a_t = _mt(R, acc)
            if prismatic[i]:
                w, wd = w_t, wd_t
                c1 = _cr(wd, p)
                c2 = _cr(w, [z[0] * q1, z[1] * q1, z[2] * q1])
                c3 = _cr(w, _cr(w, p))
                acc = [a_t[k] + z[k] * q2 + c1[k] + 2.0 * c2[k] + c3[k] for k in range(3)]
            else:
                w = [w_t[k] + z[k] * q1 for k in range(3)]
                c = _cr(w_t, [z[0] * q1, z[1] * q1, z[2] * q1])
                wd = [wd_t[k] + z[k] * q2 + c[k] for k in range(3)]
                c1 = _cr(wd, p)
                c3 = _cr(w, _cr(w, p))
                acc = [a_t[k] + c1[k] + c3[k] for k in range(3)]
            pst.append(p)
        else:
            z = [0.0, 0.0, 1.0]
            p = ps[i]
            c1 = _cr(wd, p)
            c3 = _cr(w, _cr(w, p))
            a_t = _mt(R, [acc[k] + c1[k] + c3[k] for k in range(3)])
            w_t = _mt(R, w)
            wd_t = _mt(R, wd)
            if prismatic[i]:
                w, wd = w_t, wd_t
                c2 = _cr(w, [0.0, 0.0, q1])
                acc = [a_t[0] + 2.0 * c2[0], a_t[1] + 2.0 * c2[1], a_t[2] + 2.0 * c2[2] + q2]
            else:
                w = [w_t[0], w_t[1], w_t[2] + q1]
                c = _cr(w_t, [0.0, 0.0, q1])
                wd = [wd_t[0] + c[0], wd_t[1] + c[1], wd_t[2] + c[2] + q2]
                acc = a_t
        zs.append(z)
        ri = r[i]
        c1 = _cr(wd, ri)
        c3 = _cr(w, _cr(w, ri))
        mi = m[i]
        F.append([mi * (acc[k] + c1[k] + c3[k]) for k in range(3)])
        Ii = I[i]
        Iw = _mv(Ii, w)
        Iwd = _mv(Ii, wd)
        c = _cr(w, Iw)
        N.append([Iwd[k] + c[k] for k in range(3)])
    tau = [0.0] * n
    f = [0.0, 0.0, 0.0]
    nn = [0.0, 0.0, 0.0]
    for i in range(n - 1, -1, -1):
        if i < n - 1:
            fR = _mv(Rs[i + 1], f)
            nR = _mv(Rs[i + 1], nn)
        else:
            fR, nR = f, nn
        Fi, Ni, ri = F[i], N[i], r[i]
        if not mdh:
            p = pst[i]
            c1 = _cr(p, fR)
            c2 = _cr([p[0] + ri[0], p[1] + ri[1], p[2] + ri[2]], Fi)
        else:
            c1 = _cr(ps[i + 1], fR) if i < n - 1 else [0.0, 0.0, 0.0]
            c2 = _cr(ri, Fi)
        nn = [nR[k] + c1[k] + c2[k] + Ni[k] for k in range(3)]
        f = [fR[k] + Fi[k] for k in range(3)]
        z = zs[i]
        v = f if prismatic[i] else nn
        tau[i] = v[0] * z[0] + v[1] * z[1] + v[2] * z[2]
    return np.array(tau)


# The largest ratio max(D) / min(D) of the L D L^T pivots of an inertia matrix that
# forward dynamics accepts: that ratio is a lower bound of the condition number, so past
# it qdd = M^-1 (tau - bias) has lost at least 12 of its 16 digits.
MAX_PIVOT_RATIO = 1e12


def ldl_pivots(M: Array) -> Array:
    """The diagonal of D in ``M = L D L^T`` (no pivoting), (..., n) for (..., n, n) M."""
    A = np.array(M, dtype=float)
    n = A.shape[-1]
    d = np.empty(A.shape[:-1])
    with np.errstate(divide="ignore", invalid="ignore"):
        for j in range(n):
            d[..., j] = A[..., j, j]
            if j + 1 < n:
                col = A[..., j + 1:, j]
                A[..., j + 1:, j + 1:] -= col[..., :, None] * col[..., None, :] / d[..., j, None, None]
    return d


def check_inertia(name: str, Q: Array, pivots: Array) -> None:
    """Raise ``LinAlgError`` naming the robot and the first configuration of ``Q`` (m, n)
    whose inertia pivots (m, n) are not all positive or spread more than
    :data:`MAX_PIVOT_RATIO` (a singular or ill-conditioned inertia matrix)."""
    pivots = np.atleast_2d(pivots)
    top = pivots.max(axis=-1)
    low = pivots.min(axis=-1)
    bad = ~(low > top / MAX_PIVOT_RATIO)  # nan pivots are refused too
    if not bad.any():
        return
    i = int(np.argmax(bad))
    q = np.atleast_2d(Q)[i]
    joint = int(np.nanargmin(pivots[i])) if np.isfinite(pivots[i]).any() else 0
    qs = np.array2string(q, precision=4, separator=", ", max_line_width=10_000)
    where = f" (configuration {i} of {len(pivots)})" if len(pivots) > 1 else ""
    raise np.linalg.LinAlgError(
        f"{name}: the inertia matrix at q = {qs}{where} is singular or ill-conditioned "
        f"(L D L^T pivot of joint {joint + 1}: {pivots[i, joint]:.3g}, largest {top[i]:.3g}: "
        + (f"condition number >= {top[i] / low[i]:.3g}), so " if low[i] > 0 else "not positive definite), so ")
        + "the joint accelerations are not defined: the links beyond that joint have no mass or inertia "
        "about its axis; give them mass and inertia, or the motors an armature (Jm, G)")
