"""Occupancy grids: :class:`BinaryOccupancyGrid` (True = obstacle) and
:class:`OccupancyGrid` (floats: probability or cost), as the Toolbox's.

``grid[row, col]``: one row per y and one column per x; cell ``(col, row)`` is centred at
world ``origin + cellsize * (col, row)`` (m). :meth:`BinaryOccupancyGrid.from_image` reads
a picture (dark pixels are obstacles; the image's top row is the largest y).
"""

from __future__ import annotations

import math
import os

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._util import Array, vector

__all__ = ["BinaryOccupancyGrid", "OccupancyGrid"]


class _Grid:
    def __init__(self, grid: ArrayLike, *, cellsize: float = 1.0, origin: ArrayLike = (0.0, 0.0),
                 dtype: type = float) -> None:
        g = np.array(grid, dtype=dtype)
        if g.ndim != 2 or g.size == 0:
            raise ValueError(f"an occupancy grid is a 2-D array (rows = y, columns = x), got shape {g.shape}")
        if not cellsize > 0:
            raise ValueError(f"cellsize must be positive, got {cellsize!r}")
        self.grid = g
        self.cellsize = float(cellsize)
        self.origin = vector(origin, 2, "origin")

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, columns) = (cells along y, cells along x)."""
        return self.grid.shape  # type: ignore[return-value]

    @property
    def workspace(self) -> Array:
        """``[xmin, xmax, ymin, ymax]`` (m) of the cells' centres."""
        r, c = self.shape
        o, s = self.origin, self.cellsize
        return np.array([o[0], o[0] + (c - 1) * s, o[1], o[1] + (r - 1) * s])

    @property
    def extent(self) -> Array:
        """``[xmin, xmax, ymin, ymax]`` (m) of the cells' outer edges (for drawing)."""
        w = self.workspace
        h = 0.5 * self.cellsize
        return np.array([w[0] - h, w[1] + h, w[2] - h, w[3] + h])

    def w2g(self, p: ArrayLike) -> NDArray[np.int64]:
        """World point(s) (2,) or (m, 2) (m) -> cell(s) ``(col, row)``, rounded."""
        P = np.asarray(p, dtype=float)
        return np.round((P - self.origin) / self.cellsize).astype(int)

    def g2w(self, c: ArrayLike) -> Array:
        """Cell(s) ``(col, row)`` -> the world point(s) of their centres (m)."""
        return np.asarray(c, dtype=float) * self.cellsize + self.origin

    def inside(self, cell: ArrayLike) -> bool:
        c, r = (int(v) for v in cell)
        return 0 <= r < self.shape[0] and 0 <= c < self.shape[1]

    def copy(self):  # type: ignore[no-untyped-def]
        out = object.__new__(type(self))
        out.__dict__.update(self.__dict__)
        out.grid = self.grid.copy()
        return out


class BinaryOccupancyGrid(_Grid):
    """Obstacles as True cells. ``isoccupied(p)`` is True outside the grid too."""

    def __init__(self, grid: ArrayLike, *, cellsize: float = 1.0, origin: ArrayLike = (0.0, 0.0)) -> None:
        super().__init__(np.asarray(grid) != 0, cellsize=cellsize, origin=origin, dtype=bool)

    @classmethod
    def from_image(cls, path: str | os.PathLike[str] | ArrayLike, *, cellsize: float = 1.0,
                   origin: ArrayLike = (0.0, 0.0), threshold: float = 0.5) -> "BinaryOccupancyGrid":
        """A grid from a picture file (PNG, JPEG...) or an (H, W) / (H, W, 3) array: pixels
        darker than ``threshold`` (0-1 of white) are obstacles; the top row of the picture
        is the largest y, as the picture looks on screen."""
        if isinstance(path, (str, os.PathLike)):
            import cv2

            img = cv2.imread(os.fspath(path), cv2.IMREAD_GRAYSCALE)
            if img is None:
                raise FileNotFoundError(f"cannot read the image {os.fspath(path)!r} (missing, or not a picture)")
        else:
            img = np.asarray(path)
            if img.ndim == 3:
                img = img[..., :3].mean(axis=2)
        a = np.asarray(img, dtype=float)
        full = 255.0 if a.max() > 1.0 else 1.0
        return cls(np.flipud(a / full < threshold), cellsize=cellsize, origin=origin)

    def isoccupied(self, p: ArrayLike) -> bool:
        """Is the world point p (2,) (m) in an obstacle cell or off the grid?"""
        c, r = (int(v) for v in self.w2g(vector(p, 2, "p")))
        if c < 0 or r < 0 or r >= self.shape[0] or c >= self.shape[1]:
            return True
        return bool(self.grid[r, c])

    def set(self, region: ArrayLike, value: bool = True) -> None:
        """Set the cells whose centres lie in ``[xmin, xmax, ymin, ymax]`` (m) to value."""
        x0, x1, y0, y1 = (float(v) for v in vector(region, 4, "region"))
        c0, r0 = self.w2g([x0, y0])
        c1, r1 = self.w2g([x1, y1])
        r0, c0 = max(r0, 0), max(c0, 0)
        self.grid[r0:r1 + 1, c0:c1 + 1] = bool(value)

    def inflate(self, radius: float) -> None:
        """Grow the obstacles by ``radius`` (m): a dilation by a disc of ``round(radius /
        cellsize)`` cells, as the Toolbox's."""
        from scipy import ndimage

        r = int(round(radius / self.cellsize))
        Y, X = np.meshgrid(np.arange(-r, r + 1), np.arange(-r, r + 1))
        self.grid = ndimage.binary_dilation(self.grid, X**2 + Y**2 <= r**2)

    def cells(self) -> Array:
        """The occupied cells' centres (k, 2) in the world (m), to draw as points or squares."""
        r, c = np.nonzero(self.grid)
        return self.g2w(np.column_stack((c, r)))

    def ray(self, p: ArrayLike, angle: float, max_range: float) -> float:
        """Distance (m) from p (2,) along ``angle`` (rad, world) to the first occupied cell,
        ``max_range`` if none within it (steps of a quarter cell, the exact edge not sought
        below that)."""
        x, y = (float(v) for v in p)
        c, s = math.cos(angle), math.sin(angle)
        step = 0.25 * self.cellsize
        k = 0
        while True:
            d = k * step
            if d >= max_range:
                return float(max_range)
            if self.isoccupied((x + d * c, y + d * s)):
                return d
            k += 1


class OccupancyGrid(_Grid):
    """A grid of floats (occupancy probability or traversal cost)."""

    def __init__(self, grid: ArrayLike, *, cellsize: float = 1.0, origin: ArrayLike = (0.0, 0.0)) -> None:
        super().__init__(grid, cellsize=cellsize, origin=origin, dtype=float)
