"""``SE3`` and ``SO3``: small value classes for poses and rotations, on the array functions.

They follow spatialmath (Corke's Robotics Toolbox) so course code reads the same::

    T = SE3(0.5, 0, 0.3) * SE3.RPY(0, 90, 0, unit="deg")   # composition with *
    T.t, T.R, T.A                                           # translation, rotation, (4, 4) array
    T.inv() * p                                             # acting on a point (3,) or points (3, N)
    T.rpy(unit="deg"), T.eul(), T.interp(T2, 0.5)
    print(T)                                                # the matrix; T.printline() one line

A value is immutable; every operation returns a new one. ``np.asarray(T)`` is the (4, 4)
(or (3, 3)) array, so a value goes wherever an array does (``robot.ikine(T)``...), and
an (4, 4) array composes with an ``SE3`` (``SE3(...) * robot.fkine(q)``). Angles are in
radians unless ``unit="deg"``; RPY is ZYX (``R = Rz(yaw) Ry(pitch) Rx(roll)``), Euler
angles ZYZ, as in :mod:`.transforms`.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import transforms as tf

__all__ = ["SO3", "SE3"]

Array = NDArray[np.float64]


def _rad(x: ArrayLike, unit: str) -> Array:
    if unit not in ("rad", "deg"):
        raise ValueError(f"unit must be 'rad' or 'deg', got {unit!r}")
    a = np.asarray(x, dtype=float)
    return np.radians(a) if unit == "deg" else a


def _out(x: Array, unit: str) -> Array:
    if unit not in ("rad", "deg"):
        raise ValueError(f"unit must be 'rad' or 'deg', got {unit!r}")
    return np.degrees(x) if unit == "deg" else x


def _angles(args: Sequence[Any], name: str) -> Array:
    if len(args) == 1:
        a = np.asarray(args[0], dtype=float).reshape(-1)
    else:
        a = np.asarray(args, dtype=float).reshape(-1)
    if a.size != 3:
        raise ValueError(f"{name} takes three angles, got {a.size}")
    return a


def _matrix_text(A: Array) -> str:
    cells = [[f"{0.0 if abs(v) < 5e-13 else v:.4g}" for v in row] for row in A]
    w = max(len(c) for row in cells for c in row)
    return "\n".join("  " + "  ".join(c.rjust(w) for c in row) for row in cells)


class SO3:
    """A rotation: ``SO3()`` (identity), ``SO3(R)`` for a (3, 3) rotation matrix (checked),
    or the constructors ``Rx``, ``Ry``, ``Rz``, ``RPY``, ``Eul``, ``AngVec``."""

    __slots__ = ("_A",)
    _N = 3

    def __init__(self, R: ArrayLike | "SO3" | None = None, *, check: bool = True) -> None:
        if R is None:
            A = np.eye(3)
        elif isinstance(R, SO3):
            A = R.R
        else:
            A = np.array(R, dtype=float)
            if A.shape == (4, 4):
                A = A[:3, :3].copy()
            if A.shape != (3, 3):
                raise ValueError(f"SO3 needs a (3, 3) rotation matrix, got shape {A.shape}")
            if check and (not np.allclose(A @ A.T, np.eye(3), atol=1e-8) or np.linalg.det(A) < 0):
                raise ValueError("SO3: the matrix is not a rotation (R R^T = I, det R = +1)")
        A.flags.writeable = False
        object.__setattr__(self, "_A", A)

    def __setattr__(self, key: str, value: Any) -> None:
        raise AttributeError(f"{type(self).__name__} values are immutable; make a new one")

    # -- constructors --------------------------------------------------------------------
    @classmethod
    def Rx(cls, theta: float, unit: str = "rad") -> "SO3":
        """Rotation by ``theta`` about x."""
        return cls(tf.rotx(float(_rad(theta, unit))), check=False)

    @classmethod
    def Ry(cls, theta: float, unit: str = "rad") -> "SO3":
        """Rotation by ``theta`` about y."""
        return cls(tf.roty(float(_rad(theta, unit))), check=False)

    @classmethod
    def Rz(cls, theta: float, unit: str = "rad") -> "SO3":
        """Rotation by ``theta`` about z."""
        return cls(tf.rotz(float(_rad(theta, unit))), check=False)

    @classmethod
    def RPY(cls, *angles: Any, unit: str = "rad") -> "SO3":
        """From roll, pitch, yaw (ZYX): ``RPY(r, p, y)`` or ``RPY([r, p, y])``."""
        return cls(tf.rpy2r(_rad(_angles(angles, "RPY"), unit)), check=False)

    @classmethod
    def Eul(cls, *angles: Any, unit: str = "rad") -> "SO3":
        """From ZYZ Euler angles: ``Eul(phi, theta, psi)`` or ``Eul([...])``."""
        return cls(tf.eul2r(_rad(_angles(angles, "Eul"), unit)), check=False)

    @classmethod
    def AngVec(cls, theta: float, v: ArrayLike, unit: str = "rad") -> "SO3":
        """Rotation by ``theta`` about the axis ``v``."""
        return cls(tf.angvec2r(float(_rad(theta, unit)), v), check=False)

    # -- values ---------------------------------------------------------------------------
    @property
    def R(self) -> Array:
        """The rotation matrix (3, 3) (read-only)."""
        return self._A[:3, :3]

    @property
    def A(self) -> Array:
        """The underlying array (read-only)."""
        return self._A

    def __array__(self, dtype: Any = None, copy: Any = None) -> Array:
        return np.array(self._A, dtype=dtype)

    def rpy(self, unit: str = "rad") -> Array:
        """``[roll, pitch, yaw]`` (ZYX)."""
        return _out(tf.tr2rpy(self.R), unit)

    def eul(self, unit: str = "rad", *, flip: bool = False) -> Array:
        """ZYZ Euler angles ``[phi, theta, psi]``."""
        return _out(tf.tr2eul(self.R, flip=flip), unit)

    def angvec(self, unit: str = "rad") -> tuple[float, Array]:
        """``(theta, v)``: angle and unit axis."""
        theta, v = tf.tr2angvec(self.R)
        return float(_out(np.asarray(theta), unit)), v

    def quat(self) -> Array:
        """The unit quaternion ``wxyz``."""
        return tf.r2q(self.R)

    # -- algebra ---------------------------------------------------------------------------
    def inv(self) -> "SO3":
        """The inverse rotation ``R^T``."""
        return type(self)(self.R.T, check=False)

    def _other(self, other: Any) -> Array | None:
        if type(other) is type(self):
            return other._A
        if isinstance(other, SO3):
            raise TypeError(f"cannot compose {type(self).__name__} with {type(other).__name__}; "
                            "convert one (SE3(R) or SE3.Rt(R, t))")
        if self._N == 4 and isinstance(other, np.ndarray) and other.shape == (4, 4):
            return type(self)(other)._A
        return None

    def __mul__(self, other: Any) -> Any:
        """Composition with another value of the same class (an ``SE3`` also with a (4, 4)
        array), or the action on points: (3,) -> (3,), (3, k) -> (3, k)."""
        A = self._other(other)
        if A is not None:
            return type(self)(self._A @ A, check=False)
        p = np.asarray(other, dtype=float)
        if p.shape[:1] == (3,) and p.ndim <= 2:
            return self._act(p)
        return NotImplemented

    __matmul__ = __mul__

    def __rmul__(self, other: Any) -> Any:
        A = self._other(other)
        if A is not None:
            return type(self)(A @ self._A, check=False)
        if np.isscalar(other):
            raise TypeError(f"cannot scale a {type(self).__name__}")
        return NotImplemented

    __rmatmul__ = __rmul__

    def _act(self, p: Array) -> Array:
        return self.R @ p

    def __truediv__(self, other: Any) -> Any:
        """``a / b`` = ``a * b.inv()``."""
        if type(other) is type(self):
            return self * other.inv()
        return NotImplemented

    def __pow__(self, k: int) -> Any:
        out = type(self)()
        base = self if k >= 0 else self.inv()
        for _ in range(abs(int(k))):
            out = out * base
        return out

    def __eq__(self, other: object) -> bool:
        if type(other) is type(self):
            return bool(np.allclose(self._A, other._A, atol=1e-10))
        if isinstance(other, np.ndarray) and other.shape == self._A.shape:
            return bool(np.allclose(self._A, other, atol=1e-10))
        return False

    __hash__ = None  # type: ignore[assignment]

    def interp(self, end: "SO3 | None" = None, s: float | ArrayLike = 0.5) -> Any:
        """Interpolation from this rotation (``s = 0``) to ``end`` (``s = 1``; identity
        start when ``end`` is None, as spatialmath), by SLERP: one value for a scalar
        ``s``, a list for an array of them."""
        a, b = (type(self)(), self) if end is None else (self, end)
        ss = np.asarray(s, dtype=float)
        out = [type(self)(tf.trinterp(tf.r2t(a.R), tf.r2t(b.R), float(x))[:3, :3], check=False) for x in ss.reshape(-1)]
        return out[0] if ss.ndim == 0 else out

    # -- printing ----------------------------------------------------------------------------
    def __str__(self) -> str:
        return _matrix_text(self._A)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(np.array({np.array2string(self._A, separator=', ', precision=6, suppress_small=True)}))"

    def strline(self, unit: str = "deg") -> str:
        """One line: ``rpy/zyx = r°, p°, y°`` (degrees unless ``unit="rad"``)."""
        sym = "°" if unit == "deg" else " rad"
        r = self.rpy(unit)
        return "rpy/zyx = " + ", ".join(f"{v + 0.0:.4g}{sym}" for v in r)

    def printline(self, unit: str = "deg") -> None:
        """Print :meth:`strline`."""
        print(self.strline(unit))


class SE3(SO3):
    """A rigid-body pose: ``SE3()`` (identity), ``SE3(x, y, z)`` or ``SE3([x, y, z])`` (a
    translation), ``SE3(T)`` for a (4, 4) transform (checked), or the constructors
    ``Trans``, ``Tx``/``Ty``/``Tz``, ``Rx``/``Ry``/``Rz``, ``RPY``, ``Eul``, ``AngVec``,
    ``Rt``. ``T * p`` maps points from the pose's frame to its parent's."""

    __slots__ = ()
    _N = 4

    def __init__(self, x: Any = None, y: float | None = None, z: float | None = None, *, check: bool = True) -> None:
        if x is None:
            A = np.eye(4)
        elif isinstance(x, SE3):
            A = x.A.copy()
        elif isinstance(x, SO3):
            A = tf.r2t(x.R)
        elif y is not None:
            A = tf.transl(float(x), float(y), float(z if z is not None else 0.0))
        else:
            a = np.array(x, dtype=float)
            if a.shape == (3,):
                A = tf.transl(a)
            elif a.shape == (4, 4):
                A = a
                if check:
                    R = A[:3, :3]
                    if not (np.allclose(R @ R.T, np.eye(3), atol=1e-8) and np.linalg.det(R) > 0
                            and np.allclose(A[3], [0, 0, 0, 1])):
                        raise ValueError("SE3: the matrix is not a rigid transform "
                                         "(rotation part orthonormal, last row [0 0 0 1])")
            else:
                raise ValueError(f"SE3 needs x, y, z, a 3-vector or a (4, 4) matrix, got shape {a.shape}")
        A = np.array(A, dtype=float)
        A.flags.writeable = False
        object.__setattr__(self, "_A", A)

    @classmethod
    def _rot(cls, R: Array) -> "SE3":
        return cls(tf.r2t(R), check=False)

    @classmethod
    def Rx(cls, theta: float, unit: str = "rad") -> "SE3":
        return cls._rot(SO3.Rx(theta, unit).R)

    @classmethod
    def Ry(cls, theta: float, unit: str = "rad") -> "SE3":
        return cls._rot(SO3.Ry(theta, unit).R)

    @classmethod
    def Rz(cls, theta: float, unit: str = "rad") -> "SE3":
        return cls._rot(SO3.Rz(theta, unit).R)

    @classmethod
    def RPY(cls, *angles: Any, unit: str = "rad") -> "SE3":
        return cls._rot(SO3.RPY(*angles, unit=unit).R)

    @classmethod
    def Eul(cls, *angles: Any, unit: str = "rad") -> "SE3":
        return cls._rot(SO3.Eul(*angles, unit=unit).R)

    @classmethod
    def AngVec(cls, theta: float, v: ArrayLike, unit: str = "rad") -> "SE3":
        return cls._rot(SO3.AngVec(theta, v, unit).R)

    @classmethod
    def Trans(cls, x: Any, y: float | None = None, z: float | None = None) -> "SE3":
        """A pure translation."""
        return cls(x, y, z) if y is not None else cls(np.asarray(x, dtype=float).reshape(3))

    @classmethod
    def Tx(cls, x: float) -> "SE3":
        return cls(x, 0.0, 0.0)

    @classmethod
    def Ty(cls, y: float) -> "SE3":
        return cls(0.0, y, 0.0)

    @classmethod
    def Tz(cls, z: float) -> "SE3":
        return cls(0.0, 0.0, z)

    @classmethod
    def Rt(cls, R: ArrayLike | SO3, t: ArrayLike | None = None) -> "SE3":
        """From a rotation and a translation."""
        Rm = R.R if isinstance(R, SO3) else SO3(R).R
        return cls(tf.r2t(Rm, None if t is None else np.asarray(t, dtype=float).reshape(3)), check=False)

    @property
    def t(self) -> Array:
        """The translation (3,) (read-only)."""
        return self._A[:3, 3]

    @property
    def x(self) -> float:
        return float(self._A[0, 3])

    @property
    def y(self) -> float:
        return float(self._A[1, 3])

    @property
    def z(self) -> float:
        return float(self._A[2, 3])

    def inv(self) -> "SE3":
        """The inverse pose ``[R^T, -R^T t]``."""
        return SE3(tf.trinv(self._A), check=False)

    def _act(self, p: Array) -> Array:
        return self.R @ p + (self.t if p.ndim == 1 else self.t[:, None])

    def interp(self, end: "SE3 | None" = None, s: float | ArrayLike = 0.5) -> Any:
        """Interpolation to ``end``: translation linearly, rotation by SLERP."""
        a, b = (SE3(), self) if end is None else (self, SE3(end))
        ss = np.asarray(s, dtype=float)
        out = [SE3(tf.trinterp(a.A, b.A, float(x)), check=False) for x in ss.reshape(-1)]
        return out[0] if ss.ndim == 0 else out

    def strline(self, unit: str = "deg") -> str:
        """One line: ``t = x, y, z; rpy/zyx = r°, p°, y°``."""
        return "t = " + ", ".join(f"{v + 0.0:.4g}" for v in self.t) + "; " + super().strline(unit)
