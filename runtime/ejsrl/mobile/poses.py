"""``SE2``: a 2D pose (rigid motion of the plane) as an immutable value, as spatialmath's.

``SE2(x, y, theta)`` (m, m, rad), ``SE2(T)`` from a (3, 3) matrix, ``SE2.Rot(theta)``,
``SE2.Trans(x, y)``; ``*`` composes two poses or maps points (2,) or (2, N); ``inv()``,
``xyt()``, ``.t``, ``.theta``, ``.R``, ``.A``, ``interp(end, s)``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._util import Array, wrap

__all__ = ["SE2"]


class SE2:
    __slots__ = ("_A",)

    def __init__(self, x: ArrayLike | float | "SE2" = 0.0, y: float | None = None, theta: float = 0.0, *,
                 unit: str = "rad") -> None:
        if isinstance(x, SE2):
            self._A = x._A.copy()
            return
        if y is None and np.ndim(x) == 2:
            A = np.array(x, dtype=float)
            if A.shape != (3, 3) or not np.allclose(A[2], [0, 0, 1]):
                raise ValueError(f"SE2 from a matrix needs a (3, 3) homogeneous transform, got shape {A.shape}")
            R = A[:2, :2]
            if not np.allclose(R.T @ R, np.eye(2), atol=1e-9) or np.linalg.det(R) < 0:
                raise ValueError("SE2 from a matrix: its top-left (2, 2) is not a rotation")
            self._A = A
            return
        if y is None and np.ndim(x) == 1:
            v = np.asarray(x, dtype=float)
            if v.shape not in ((2,), (3,)):
                raise ValueError(f"SE2 from a vector needs (x, y) or (x, y, theta), got {v.shape}")
            x, y, theta = float(v[0]), float(v[1]), float(v[2]) if len(v) == 3 else 0.0
        th = math.radians(theta) if unit == "deg" else float(theta)
        c, s = math.cos(th), math.sin(th)
        self._A = np.array([[c, -s, float(x)], [s, c, float(0.0 if y is None else y)], [0.0, 0.0, 1.0]])

    @classmethod
    def Rot(cls, theta: float, unit: str = "rad") -> "SE2":
        return cls(0.0, 0.0, theta, unit=unit)

    @classmethod
    def Trans(cls, x: float, y: float) -> "SE2":
        return cls(x, y, 0.0)

    @property
    def A(self) -> Array:
        """The (3, 3) homogeneous matrix (a copy)."""
        return self._A.copy()

    @property
    def t(self) -> Array:
        return self._A[:2, 2].copy()

    @property
    def R(self) -> Array:
        return self._A[:2, :2].copy()

    @property
    def theta(self) -> float:
        return math.atan2(self._A[1, 0], self._A[0, 0])

    @property
    def x(self) -> float:
        return float(self._A[0, 2])

    @property
    def y(self) -> float:
        return float(self._A[1, 2])

    def xyt(self) -> Array:
        """``(x, y, theta)`` (3,)."""
        return np.array([self.x, self.y, self.theta])

    def inv(self) -> "SE2":
        R = self._A[:2, :2]
        A = np.eye(3)
        A[:2, :2] = R.T
        A[:2, 2] = -R.T @ self._A[:2, 2]
        return SE2(A)

    def __mul__(self, other: Any) -> Any:
        if isinstance(other, SE2):
            A = self._A @ other._A
            A[2] = (0.0, 0.0, 1.0)
            return SE2(A)
        p = np.asarray(other, dtype=float)
        if p.shape == (2,):
            return self._A[:2, :2] @ p + self._A[:2, 2]
        if p.ndim == 2 and p.shape[0] == 2:
            return self._A[:2, :2] @ p + self._A[:2, 2:3]
        return NotImplemented

    def interp(self, end: "SE2", s: float) -> "SE2":
        """The pose a fraction s (0-1) of the way to ``end`` (translation and angle linear)."""
        a, b = self.xyt(), end.xyt()
        return SE2(a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * wrap(b[2] - a[2]))

    def __array__(self, dtype: Any = None, copy: Any = None) -> Array:
        return self._A.copy() if dtype is None else self._A.astype(dtype)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, SE2) and bool(np.allclose(self._A, other._A, atol=1e-12))

    def __hash__(self) -> int:  # pragma: no cover - values are not keys
        return hash(tuple(np.round(self._A, 12).ravel()))

    def __repr__(self) -> str:
        return f"SE2({self.x:.4g}, {self.y:.4g}, {self.theta:.4g})"
