"""``UnitQuaternion``: a rotation as an immutable unit quaternion value, as spatialmath's.

Scalar first, ``q = s + v`` with ``vec = [s, vx, vy, vz]`` (wxyz, as viser and
:mod:`.transforms`). ``q`` and ``-q`` are the same rotation: ``==`` says so, and the
constructors keep ``s >= 0``. ``*`` composes (Hamilton product) or rotates vectors
(3,) or (3, N); ``inv()`` is the conjugate; ``interp(end, s)`` is SLERP along the shorter
arc; ``R``, ``SO3()``, ``SE3()``, ``rpy()``, ``angvec()``, ``angdist(other)``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from . import transforms as tf

Array = np.ndarray

__all__ = ["UnitQuaternion"]


def _canon(q: Array) -> Array:
    """Unit length, ``s >= 0`` (the first non-zero component positive when s = 0)."""
    n = float(np.linalg.norm(q))
    if not n > 0 or not math.isfinite(n):
        raise ValueError(f"a unit quaternion needs a non-zero finite [s, vx, vy, vz], got {q.tolist()}")
    q = q / n
    nz = np.flatnonzero(np.abs(q) > 1e-15)
    if len(nz) and q[nz[0]] < 0:
        q = -q
    return q


class UnitQuaternion:
    __slots__ = ("_q",)

    def __init__(self, s: ArrayLike | "UnitQuaternion" | float | None = None, v: ArrayLike | None = None, *,
                 norm: bool = True) -> None:
        """``UnitQuaternion()`` (identity), ``UnitQuaternion([s, vx, vy, vz])``,
        ``UnitQuaternion(s, [vx, vy, vz])``, or from a rotation matrix (3, 3) or pose (4, 4)."""
        if s is None:
            q = np.array([1.0, 0.0, 0.0, 0.0])
        elif isinstance(s, UnitQuaternion):
            q = s._q.copy()
        elif v is not None:
            q = np.r_[float(s), np.asarray(v, dtype=float).reshape(3)]
        else:
            a = np.asarray(s, dtype=float)
            if a.shape == (4,):
                q = a.copy()
            elif a.shape in ((3, 3), (4, 4)):
                R = a[:3, :3]
                if not np.allclose(R.T @ R, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
                    raise ValueError("UnitQuaternion from a matrix: it is not a rotation")
                q = np.asarray(tf.r2q(R), dtype=float)
            else:
                raise ValueError(f"UnitQuaternion takes [s, vx, vy, vz], (s, v) or a (3, 3)/(4, 4) matrix, got shape {a.shape}")
        self._q = _canon(q) if norm else q

    # ------------------------------------------------------------------ constructors
    @classmethod
    def Rx(cls, theta: float, unit: str = "rad") -> "UnitQuaternion":
        return cls.AngVec(theta, [1, 0, 0], unit=unit)

    @classmethod
    def Ry(cls, theta: float, unit: str = "rad") -> "UnitQuaternion":
        return cls.AngVec(theta, [0, 1, 0], unit=unit)

    @classmethod
    def Rz(cls, theta: float, unit: str = "rad") -> "UnitQuaternion":
        return cls.AngVec(theta, [0, 0, 1], unit=unit)

    @classmethod
    def AngVec(cls, theta: float, v: ArrayLike, unit: str = "rad") -> "UnitQuaternion":
        """Rotation by ``theta`` about the axis ``v`` (normalised)."""
        th = math.radians(theta) if unit == "deg" else float(theta)
        a = np.asarray(v, dtype=float).reshape(3)
        n = float(np.linalg.norm(a))
        if n == 0:
            raise ValueError("AngVec: the axis must not be zero")
        return cls(math.cos(th / 2), math.sin(th / 2) * a / n)

    @classmethod
    def EulerVec(cls, w: ArrayLike) -> "UnitQuaternion":
        """Rotation by the vector ``w`` (its norm is the angle, rad)."""
        w = np.asarray(w, dtype=float).reshape(3)
        th = float(np.linalg.norm(w))
        return cls() if th == 0 else cls.AngVec(th, w)

    @classmethod
    def RPY(cls, *angles: Any, unit: str = "rad") -> "UnitQuaternion":
        """From roll, pitch, yaw (ZYX, as :func:`.transforms.rpy2r`)."""
        a = np.asarray(angles[0] if len(angles) == 1 else angles, dtype=float).reshape(3)
        if unit == "deg":
            a = np.radians(a)
        return cls(tf.rpy2r(a))

    # ------------------------------------------------------------------ values
    @property
    def s(self) -> float:
        return float(self._q[0])

    @property
    def v(self) -> Array:
        return self._q[1:].copy()

    @property
    def vec(self) -> Array:
        """``[s, vx, vy, vz]`` (4,)."""
        return self._q.copy()

    @property
    def R(self) -> Array:
        """The rotation matrix (3, 3)."""
        return np.asarray(tf.q2r(self._q), dtype=float)

    def SO3(self) -> Any:
        from .pose import SO3

        return SO3(self.R)

    def SE3(self) -> Any:
        from .pose import SE3

        return SE3(tf.r2t(self.R))

    def rpy(self, unit: str = "rad") -> Array:
        a = np.asarray(tf.tr2rpy(tf.r2t(self.R)), dtype=float)
        return np.degrees(a) if unit == "deg" else a

    def angvec(self, unit: str = "rad") -> tuple[float, Array]:
        """``(theta, axis)``: the angle in [0, pi] and the unit axis."""
        n = float(np.linalg.norm(self._q[1:]))
        th = 2.0 * math.atan2(n, abs(self._q[0]))
        axis = self._q[1:] / n if n > 0 else np.array([1.0, 0.0, 0.0])
        if self._q[0] < 0:
            axis = -axis
        return (math.degrees(th) if unit == "deg" else th), axis

    def inv(self) -> "UnitQuaternion":
        return UnitQuaternion(np.asarray(tf.qconj(self._q), dtype=float))

    conj = inv

    def __mul__(self, other: Any) -> Any:
        if isinstance(other, UnitQuaternion):
            return UnitQuaternion(np.asarray(tf.qmul(self._q, other._q), dtype=float))
        p = np.asarray(other, dtype=float)
        if p.shape == (3,) or (p.ndim == 2 and p.shape[0] == 3):
            return self.R @ p
        return NotImplemented

    def __truediv__(self, other: "UnitQuaternion") -> "UnitQuaternion":
        return self * other.inv()

    def __pow__(self, k: int) -> "UnitQuaternion":
        out = UnitQuaternion()
        base = self if k >= 0 else self.inv()
        for _ in range(abs(int(k))):
            out = out * base
        return out

    def interp(self, end: "UnitQuaternion", s: float) -> "UnitQuaternion":
        """SLERP a fraction s (0-1) of the way to ``end``, along the shorter arc."""
        return UnitQuaternion(np.asarray(tf.qslerp(self._q, end._q, float(s)), dtype=float))

    def angdist(self, other: "UnitQuaternion") -> float:
        """The angle (rad) of the rotation from this one to ``other``, in [0, pi]."""
        d = min(1.0, abs(float(self._q @ other._q)))
        return 2.0 * math.acos(d)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, UnitQuaternion) and abs(abs(float(self._q @ other._q)) - 1.0) < 1e-12

    def __hash__(self) -> int:  # pragma: no cover - values are not keys
        return hash(tuple(np.round(self._q, 12)))

    def __array__(self, dtype: Any = None, copy: Any = None) -> Array:
        return self._q.copy() if dtype is None else self._q.astype(dtype)

    def __repr__(self) -> str:
        s, v = self._q[0], self._q[1:]
        return f"UnitQuaternion({s:.4f} << {v[0]:.4f}, {v[1]:.4f}, {v[2]:.4f} >>)"
