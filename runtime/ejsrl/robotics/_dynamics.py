"""Batched recursive Newton-Euler on plain arrays (private).

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
