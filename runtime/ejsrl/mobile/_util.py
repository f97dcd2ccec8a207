"""Small helpers shared by ejsrl.mobile (private)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


def wrap(a: ArrayLike) -> Array | float:
    """Angle(s) wrapped into [-pi, pi) (rad), as the Toolbox's ``wrap_mpi_pi``."""
    if np.ndim(a) == 0:
        return (float(a) + math.pi) % (2.0 * math.pi) - math.pi
    return (np.asarray(a, dtype=float) + np.pi) % (2.0 * np.pi) - np.pi


def angdiff(a: ArrayLike, b: ArrayLike = 0.0) -> Array | float:
    """``a - b`` wrapped into [-pi, pi) (rad), as the Toolbox's ``angdiff``."""
    if np.ndim(a) == 0 and np.ndim(b) == 0:
        return wrap(float(a) - float(b))
    return wrap(np.asarray(a, dtype=float) - np.asarray(b, dtype=float))


def vector(x: ArrayLike, n: int, what: str) -> Array:
    """``x`` as a float array of shape (n,), or a ValueError naming ``what``."""
    v = np.asarray(x, dtype=float).reshape(-1)
    if v.shape != (n,):
        raise ValueError(f"{what} must have {n} values, got {np.shape(x)}")
    return v
