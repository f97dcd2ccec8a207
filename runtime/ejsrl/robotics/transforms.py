"""Spatial helpers: rotations, homogeneous transforms, roll-pitch-yaw, quaternions.

Conventions (as in Corke's Robotics Toolbox / spatialmath):

- Rotation matrices are (3, 3), homogeneous transforms (4, 4), angles in radians.
- Roll-pitch-yaw is the ZYX convention: ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``
  (rotate about the fixed x axis by roll, then fixed y by pitch, then fixed z by yaw).
- Quaternions are ``wxyz`` (scalar first), the viser convention, unit norm.
- Euler angles are ZYZ: ``R = Rz(phi) @ Ry(theta) @ Rz(psi)``.
- Angle-axis: rotation by ``theta`` about the unit vector ``v``; a rotation vector is
  ``theta * v``.
- ``T_a_b`` names the pose of frame b expressed in frame a.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "rotx",
    "roty",
    "rotz",
    "trotx",
    "troty",
    "trotz",
    "transl",
    "rpy2r",
    "rpy2tr",
    "tr2rpy",
    "r2q",
    "q2r",
    "r2t",
    "t2r",
    "trinv",
    "eul2r",
    "eul2tr",
    "tr2eul",
    "angvec2r",
    "angvec2tr",
    "tr2angvec",
    "tr2angvec_vec",
    "skew",
    "vex",
    "q2tr",
    "qmul",
    "qconj",
    "qslerp",
    "trinterp",
]

Array = NDArray[np.float64]


def rotx(theta: float) -> Array:
    """Rotation about x by ``theta`` rad: (3, 3)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def roty(theta: float) -> Array:
    """Rotation about y by ``theta`` rad: (3, 3)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rotz(theta: float) -> Array:
    """Rotation about z by ``theta`` rad: (3, 3)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def r2t(R: ArrayLike, p: ArrayLike | None = None) -> Array:
    """Homogeneous transform (4, 4) from rotation ``R`` (3, 3) and optional translation ``p`` (3,)."""
    T = np.eye(4)
    T[:3, :3] = R
    if p is not None:
        T[:3, 3] = p
    return T


def t2r(T: ArrayLike) -> Array:
    """Rotation part (3, 3) of a homogeneous transform."""
    return np.array(T, dtype=float)[:3, :3]


def trotx(theta: float) -> Array:
    """Homogeneous rotation about x: (4, 4)."""
    return r2t(rotx(theta))


def troty(theta: float) -> Array:
    """Homogeneous rotation about y: (4, 4)."""
    return r2t(roty(theta))


def trotz(theta: float) -> Array:
    """Homogeneous rotation about z: (4, 4)."""
    return r2t(rotz(theta))


def transl(x: float | ArrayLike, y: float | None = None, z: float | None = None) -> Array:
    """Pure translation (4, 4); ``transl([x, y, z])`` or ``transl(x, y, z)``."""
    T = np.eye(4)
    if y is None:
        T[:3, 3] = np.asarray(x, dtype=float).reshape(3)
    else:
        T[:3, 3] = (float(x), float(y), float(z if z is not None else 0.0))  # type: ignore[arg-type]
    return T


def rpy2r(roll: float | ArrayLike, pitch: float | None = None, yaw: float | None = None) -> Array:
    """Rotation (3, 3) from roll-pitch-yaw (ZYX): ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``.

    Accepts ``rpy2r(roll, pitch, yaw)`` or ``rpy2r([roll, pitch, yaw])``.
    """
    if pitch is None:
        roll, pitch, yaw = np.asarray(roll, dtype=float).reshape(3)
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def rpy2tr(roll: float | ArrayLike, pitch: float | None = None, yaw: float | None = None) -> Array:
    """Homogeneous transform (4, 4) from roll-pitch-yaw (ZYX), no translation."""
    return r2t(rpy2r(roll, pitch, yaw))


def tr2rpy(T: ArrayLike) -> Array:
    """Roll-pitch-yaw (ZYX) angles ``[roll, pitch, yaw]`` of a (3, 3) or (4, 4) matrix.

    At the singularity (pitch = ±pi/2) roll is set to 0 and yaw takes the whole rotation.
    """
    R = np.asarray(T, dtype=float)[:3, :3]
    sp = -R[2, 0]
    if abs(abs(sp) - 1.0) < 1e-12:
        pitch = np.copysign(np.pi / 2, sp)
        roll = 0.0
        yaw = np.arctan2(-R[0, 1], R[1, 1])
    else:
        pitch = np.arcsin(np.clip(sp, -1.0, 1.0))
        roll = np.arctan2(R[2, 1], R[2, 2])
        yaw = np.arctan2(R[1, 0], R[0, 0])
    return np.array([roll, pitch, yaw])


def r2q(R: ArrayLike) -> Array:
    """Unit quaternion ``wxyz`` (w >= 0) of a rotation (3, 3) or the rotation part of a (4, 4)."""
    M = np.asarray(R, dtype=float)[:3, :3]
    tr = M[0, 0] + M[1, 1] + M[2, 2]
    if tr > 0:
        s = 2.0 * np.sqrt(tr + 1.0)
        q = np.array([0.25 * s, (M[2, 1] - M[1, 2]) / s, (M[0, 2] - M[2, 0]) / s, (M[1, 0] - M[0, 1]) / s])
    elif M[0, 0] > M[1, 1] and M[0, 0] > M[2, 2]:
        s = 2.0 * np.sqrt(1.0 + M[0, 0] - M[1, 1] - M[2, 2])
        q = np.array([(M[2, 1] - M[1, 2]) / s, 0.25 * s, (M[0, 1] + M[1, 0]) / s, (M[0, 2] + M[2, 0]) / s])
    elif M[1, 1] > M[2, 2]:
        s = 2.0 * np.sqrt(1.0 + M[1, 1] - M[0, 0] - M[2, 2])
        q = np.array([(M[0, 2] - M[2, 0]) / s, (M[0, 1] + M[1, 0]) / s, 0.25 * s, (M[1, 2] + M[2, 1]) / s])
    else:
        s = 2.0 * np.sqrt(1.0 + M[2, 2] - M[0, 0] - M[1, 1])
        q = np.array([(M[1, 0] - M[0, 1]) / s, (M[0, 2] + M[2, 0]) / s, (M[1, 2] + M[2, 1]) / s, 0.25 * s])
    if q[0] < 0:
        q = -q
    return q / np.linalg.norm(q)


def q2r(q: ArrayLike) -> Array:
    """Rotation (3, 3) of a quaternion ``wxyz`` (normalised first)."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def trinv(T: ArrayLike) -> Array:
    """Inverse of a homogeneous transform (4, 4), using the rotation's transpose."""
    T = np.asarray(T, dtype=float)
    Ti = np.eye(4)
    Rt = T[:3, :3].T
    Ti[:3, :3] = Rt
    Ti[:3, 3] = -Rt @ T[:3, 3]
    return Ti


def skew(v: ArrayLike) -> Array:
    """Skew-symmetric matrix (3, 3) of a 3-vector: ``skew(a) @ b == cross(a, b)``."""
    x, y, z = np.asarray(v, dtype=float).reshape(3)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def vex(S: ArrayLike) -> Array:
    """The 3-vector of a skew-symmetric matrix (inverse of :func:`skew`)."""
    S = np.asarray(S, dtype=float)
    return 0.5 * np.array([S[2, 1] - S[1, 2], S[0, 2] - S[2, 0], S[1, 0] - S[0, 1]])


def eul2r(phi: float | ArrayLike, theta: float | None = None, psi: float | None = None) -> Array:
    """Rotation (3, 3) from ZYZ Euler angles: ``Rz(phi) @ Ry(theta) @ Rz(psi)``.

    Accepts ``eul2r(phi, theta, psi)`` or ``eul2r([phi, theta, psi])``."""
    if theta is None:
        phi, theta, psi = np.asarray(phi, dtype=float).reshape(3)
    return rotz(phi) @ roty(theta) @ rotz(psi)  # type: ignore[arg-type]


def eul2tr(phi: float | ArrayLike, theta: float | None = None, psi: float | None = None) -> Array:
    """Homogeneous transform (4, 4) from ZYZ Euler angles, no translation."""
    return r2t(eul2r(phi, theta, psi))


def tr2eul(T: ArrayLike, *, flip: bool = False) -> Array:
    """ZYZ Euler angles ``[phi, theta, psi]`` of a (3, 3) or (4, 4) matrix, ``theta`` in
    [0, pi] (or [-pi, 0] with ``flip``). At theta = 0 or pi, phi is 0 and psi takes the
    whole rotation about z."""
    R = np.asarray(T, dtype=float)[:3, :3]
    st = np.hypot(R[0, 2], R[1, 2])
    if st < 1e-12:
        phi = 0.0
        if R[2, 2] > 0:
            theta, psi = 0.0, np.arctan2(R[1, 0], R[0, 0])
        else:
            # R = Ry(pi) @ Rz(psi) = [[-c, s, 0], [s, c, 0], [0, 0, -1]]
            theta, psi = np.pi, np.arctan2(R[1, 0], -R[0, 0])
        return np.array([phi, theta if not flip else -theta, psi])
    sgn = -1.0 if flip else 1.0
    phi = np.arctan2(sgn * R[1, 2], sgn * R[0, 2])
    theta = np.arctan2(sgn * st, R[2, 2])
    psi = np.arctan2(sgn * R[2, 1], -sgn * R[2, 0])
    return np.array([phi, theta, psi])


def angvec2r(theta: float, v: ArrayLike) -> Array:
    """Rotation (3, 3) by ``theta`` rad about the axis ``v`` (normalised; Rodrigues)."""
    v = np.asarray(v, dtype=float).reshape(3)
    nv = np.linalg.norm(v)
    if nv == 0 or theta == 0:
        return np.eye(3)
    K = skew(v / nv)
    return np.eye(3) + np.sin(theta) * K + (1.0 - np.cos(theta)) * (K @ K)


def angvec2tr(theta: float, v: ArrayLike) -> Array:
    """Homogeneous transform (4, 4) of :func:`angvec2r`."""
    return r2t(angvec2r(theta, v))


def tr2angvec_vec(T: ArrayLike) -> Array:
    """Rotation vector ``theta * v`` (3,) of a (3, 3) or (4, 4) matrix, theta in [0, pi];
    the matrix logarithm, robust near 0 and pi."""
    R = np.asarray(T, dtype=float)[:3, :3]
    v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    s = 0.5 * np.sqrt(v @ v)
    theta = np.arctan2(s, c)
    if s > 1e-6:
        return v * (theta / (2.0 * s))
    if c > 0:  # small angle: log(R) ~ vee(R - R^T) / 2
        return 0.5 * v
    # theta ~ pi: R ~ 2 u u^T - I, so u from the symmetric part (largest diagonal first)
    B = 0.5 * (R + R.T)
    k = int(np.argmax(np.diag(B)))
    axis = np.empty(3)
    axis[k] = np.sqrt(max(0.5 * (B[k, k] + 1.0), 0.0))
    for j in range(3):
        if j != k:
            axis[j] = B[j, k] / (2.0 * axis[k])
    axis /= np.linalg.norm(axis)
    if axis @ v < 0:
        axis = -axis
    return axis * theta


def tr2angvec(T: ArrayLike) -> tuple[float, Array]:
    """Angle (rad, in [0, pi]) and unit axis (3,) of a rotation; axis ``[0, 0, 0]`` when
    the angle is zero."""
    w = tr2angvec_vec(T)
    theta = float(np.linalg.norm(w))
    return theta, (w / theta if theta > 0 else np.zeros(3))


def q2tr(q: ArrayLike) -> Array:
    """Homogeneous transform (4, 4) of a quaternion ``wxyz``."""
    return r2t(q2r(q))


def qmul(q1: ArrayLike, q2: ArrayLike) -> Array:
    """Hamilton product ``q1 * q2`` of quaternions ``wxyz`` (rotation q2 then q1 in the fixed
    frame: ``q2r(qmul(a, b)) == q2r(a) @ q2r(b)``)."""
    w1, x1, y1, z1 = np.asarray(q1, dtype=float)
    w2, x2, y2, z2 = np.asarray(q2, dtype=float)
    return np.array([
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
        w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
    ])


def qconj(q: ArrayLike) -> Array:
    """Conjugate of a quaternion ``wxyz`` (the inverse rotation for a unit quaternion)."""
    w, x, y, z = np.asarray(q, dtype=float)
    return np.array([w, -x, -y, -z])


def qslerp(q0: ArrayLike, q1: ArrayLike, s: float) -> Array:
    """Spherical linear interpolation of unit quaternions ``wxyz`` at ``s`` in [0, 1],
    along the shorter arc (constant angular speed)."""
    a = np.asarray(q0, dtype=float) / np.linalg.norm(q0)
    b = np.asarray(q1, dtype=float) / np.linalg.norm(q1)
    d = float(a @ b)
    if d < 0:
        b, d = -b, -d
    if d > 1.0 - 1e-12:
        out = a + s * (b - a)
        return out / np.linalg.norm(out)
    th = np.arccos(min(d, 1.0))
    out = (np.sin((1 - s) * th) * a + np.sin(s * th) * b) / np.sin(th)
    return out / np.linalg.norm(out)


def trinterp(T0: ArrayLike, T1: ArrayLike, s: float) -> Array:
    """Pose (4, 4) interpolated at ``s`` in [0, 1]: translation linearly, rotation by SLERP."""
    T0 = np.asarray(T0, dtype=float)
    T1 = np.asarray(T1, dtype=float)
    out = np.eye(4)
    out[:3, 3] = (1 - s) * T0[:3, 3] + s * T1[:3, 3]
    out[:3, :3] = q2r(qslerp(r2q(T0), r2q(T1), s))
    return out
