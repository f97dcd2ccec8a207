"""How an ODE page packs its state variables (numbers and arrays) into one vector."""

from __future__ import annotations

from collections.abc import Callable
from operator import itemgetter
from typing import Any

import numpy as np

__all__ = ["StateLayout"]


def _shape(value: Any) -> tuple[int, ...]:
    shape = getattr(value, "shape", None)
    return tuple(shape) if shape is not None else np.shape(value)


class StateLayout:
    """Slices and shapes of each state variable in the packed state vector.

    Made from the variables' current values (so array sizes may come from ``expr`` initial
    values or change at run time); :meth:`of` reuses a layout while the shapes stay the same.

    ``unpack(y)`` gives the variables from a packed vector (floats for numbers, views of
    ``y`` for arrays); ``views(out)`` gives writable views of a packed output vector, one
    per variable, each of the variable's shape (length 1 for numbers), so a rate of the
    wrong shape fails to broadcast.
    """

    __slots__ = ("slices", "shapes", "size", "unpack", "views", "flat")

    def __init__(self, *values: Any) -> None:
        self.slices: list[slice] = []
        self.shapes: tuple[tuple[int, ...], ...] = tuple(_shape(v) for v in values)
        start = 0
        for shape in self.shapes:
            n = int(np.prod(shape)) if shape else 1
            self.slices.append(slice(start, start + n))
            start += n
        self.size = start
        self.unpack: Callable[[np.ndarray], tuple[Any, ...]]
        self.views: Callable[[np.ndarray], tuple[np.ndarray, ...]]
        self.flat = all(len(s) == 1 for s in self.shapes)  # every state a 1-D array
        if self.flat:
            # every state a 1-D array: slicing in C
            if len(self.slices) == 1:
                only = self.slices[0]
                self.unpack = self.views = lambda y: (y[only],)
            else:
                self.unpack = self.views = itemgetter(*self.slices)  # type: ignore[assignment]
        else:
            self.unpack = self._unpack
            self.views = self._views

    @classmethod
    def of(cls, previous: StateLayout | None, *values: Any) -> StateLayout:
        """``previous`` if the values still have its shapes, else a new layout."""
        if previous is not None and len(values) == len(previous.shapes):
            for v, shape in zip(values, previous.shapes):
                if _shape(v) != shape:
                    break
            else:
                return previous
        return cls(*values)

    def pack(self, values: tuple[Any, ...]) -> np.ndarray:
        """The packed float64 vector of ``values`` (which have this layout's shapes): a new array."""
        if self.flat:
            if len(values) == 1:
                return np.array(values[0], dtype=float)  # a copy, like concatenate's
            return np.concatenate(values).astype(float, copy=False)
        return np.concatenate([np.ravel(v) for v in values]).astype(float, copy=False)

    def _unpack(self, y: np.ndarray) -> tuple[Any, ...]:
        out = []
        for sl, shape in zip(self.slices, self.shapes):
            if not shape:
                out.append(float(y[sl.start]))
            elif len(shape) == 1:
                out.append(y[sl])
            else:
                out.append(y[sl].reshape(shape))
        return tuple(out)

    def _views(self, out: np.ndarray) -> tuple[np.ndarray, ...]:
        return tuple(out[sl] if len(shape) <= 1 else out[sl].reshape(shape) for sl, shape in zip(self.slices, self.shapes))

    def take(self, y: np.ndarray, j: int) -> Any:
        """Variable ``j`` alone (see ``unpack``)."""
        return self._unpack(y)[j]
