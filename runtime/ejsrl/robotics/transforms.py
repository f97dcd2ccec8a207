"""Spatial helpers: rotations, homogeneous transforms, roll-pitch-yaw, quaternions.

Conventions (as in Corke's Robotics Toolbox / spatialmath):

- Rotation matrices are (3, 3), homogeneous transforms (4, 4), angles in radians.
- Roll-pitch-yaw is the ZYX convention: ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``
  (rotate about the fixed x axis by roll, then fixed y by pitch, then fixed z by yaw).
- Quaternions are ``wxyz`` (scalar first), the viser convention, unit norm.
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
