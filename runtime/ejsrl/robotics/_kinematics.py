"""Batched forward kinematics and geometric Jacobians on plain arrays (private).

The reference implementation: ``Robot`` runs the generated code of :mod:`._kernels` by
default, and the tests check it against these functions (``Robot._fast = False``).

Every function accepts joint values with any leading batch shape ``(..., n)`` and works
on all configurations at once with NumPy (no Python loop over configurations; the only
loop is over the n links of the chain).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def dh_transforms(
    q: Array,
    a: Array,
    alpha: Array,
    d: Array,
    theta: Array,
    offset: Array,
    prismatic: Array,
    mdh: bool,
    *,
    ca: Array | None = None,
    sa: Array | None = None,
) -> Array:
    """Link transforms ``T_{i-1}_i`` (..., n, 4, 4) for joint values ``q`` (..., n)."""
    q = np.asarray(q, dtype=float)
    qo = q + offset
    if prismatic.any():
        th = np.where(prismatic, theta, qo)
        dd = np.where(prismatic, qo, d)
    else:
        th = qo
        dd = np.broadcast_to(d, q.shape)
    ct = np.cos(th)
    st = np.sin(th)
    if ca is None:
        ca = np.cos(alpha)
        sa = np.sin(alpha)
    A = np.zeros(q.shape + (4, 4))
    if not mdh:
        A[..., 0, 0] = ct
        A[..., 0, 1] = -st * ca
        A[..., 0, 2] = st * sa
        A[..., 0, 3] = a * ct
        A[..., 1, 0] = st
        A[..., 1, 1] = ct * ca
        A[..., 1, 2] = -ct * sa
        A[..., 1, 3] = a * st
        A[..., 2, 1] = sa
        A[..., 2, 2] = ca
        A[..., 2, 3] = dd
    else:
        A[..., 0, 0] = ct
        A[..., 0, 1] = -st
        A[..., 0, 3] = a
        A[..., 1, 0] = st * ca
        A[..., 1, 1] = ct * ca
        A[..., 1, 2] = -sa
        A[..., 1, 3] = -sa * dd
        A[..., 2, 0] = st * sa
        A[..., 2, 1] = ct * sa
        A[..., 2, 2] = ca
        A[..., 2, 3] = ca * dd
    A[..., 3, 3] = 1.0
    return A


def chain(A: Array, base: Array | None, tool: Array | None) -> Array:
    """Product ``base @ A_1 @ ... @ A_n @ tool`` (..., 4, 4) of link transforms (..., n, 4, 4)."""
    n = A.shape[-3]
    T = A[..., 0, :, :] if base is None else base @ A[..., 0, :, :]
    for i in range(1, n):
        T = T @ A[..., i, :, :]
    if tool is not None:
        T = T @ tool
    return T


def chain_all(A: Array, base: Array) -> Array:
    """Frames (..., n+1, 4, 4) in the world: the base, then each link frame (no tool)."""
    n = A.shape[-3]
    F = np.empty(A.shape[:-3] + (n + 1, 4, 4))
    F[..., 0, :, :] = base
    T = base
    for i in range(n):
        T = T @ A[..., i, :, :]
        F[..., i + 1, :, :] = T
    return F


def cross(u: Array, v: Array) -> Array:
    """Cross product over the last axis (faster than ``np.cross`` for small arrays)."""
    u0, u1, u2 = u[..., 0], u[..., 1], u[..., 2]
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    return np.stack((u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0), axis=-1)


def jacobian_from_frames(F: Array, T_end: Array, prismatic: Array, mdh: bool) -> Array:
    """Geometric Jacobian in the world frame (..., 6, n), rows ``vx vy vz wx wy wz``.

    ``F`` (..., n+1, 4, 4) are the world frames from :func:`chain_all`; ``T_end`` (..., 4, 4)
    is the end-effector pose (tool included) whose origin is the velocity reference point.
    Joint i moves about/along ``z_{i-1}`` (standard DH) or ``z_i`` (modified DH).
    """
    Fj = F[..., :-1, :, :] if not mdh else F[..., 1:, :, :]
    z = Fj[..., :3, 2]  # (..., n, 3)
    o = Fj[..., :3, 3]
    pe = T_end[..., None, :3, 3]
    v = cross(z, pe - o)
    w = z
    if prismatic.any():
        v = np.where(prismatic[:, None], z, v)
        w = np.where(prismatic[:, None], 0.0, z)
    J = np.concatenate((v, w), axis=-1)  # (..., n, 6)
    return np.swapaxes(J, -1, -2)
