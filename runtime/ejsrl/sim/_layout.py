"""How an ODE page packs its state variables (numbers and arrays) into one vector."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["StateLayout"]


class StateLayout:
    """Slices and shapes of each state variable in the packed state vector.

    Built from the variables' current values when the evolution pages are built (at
    start and on reset), so array sizes may come from ``expr`` initial values.
    """

    __slots__ = ("slices", "shapes", "size")

    def __init__(self, *values: Any) -> None:
        self.slices: list[slice] = []
        self.shapes: list[tuple[int, ...]] = []
        start = 0
        for v in values:
            shape = np.shape(v)
            n = int(np.prod(shape)) if shape else 1
            self.slices.append(slice(start, start + n))
            self.shapes.append(shape)
            start += n
        self.size = start

    def take(self, y: np.ndarray, j: int) -> Any:
        """Variable ``j`` from the packed vector: a float, or an array view of its shape."""
        shape = self.shapes[j]
        if not shape:
            return float(y[self.slices[j].start])
        part = y[self.slices[j]]
        return part if len(shape) == 1 else part.reshape(shape)
