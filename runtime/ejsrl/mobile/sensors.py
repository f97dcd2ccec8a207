"""Sensors of a mobile robot, as the Toolbox's: a :class:`LandmarkMap`, the
:class:`RangeBearingSensor` (range and bearing to one visible landmark per reading, with
noise) and a :class:`LaserScanner` that ray-casts an occupancy grid.

Ranges in m, bearings in rad measured from the vehicle's heading (counter-clockwise).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._util import Array, angdiff, vector
from .grid import BinaryOccupancyGrid

__all__ = ["LandmarkMap", "RangeBearingSensor", "LaserScanner"]


class LandmarkMap:
    """Point landmarks: ``landmarks`` (2, N) coordinates, or a number N of landmarks drawn
    uniformly in ``workspace`` (a half-width A: [-A, A]^2, or ``[xmin, xmax, ymin, ymax]``)
    from ``np.random.default_rng(seed)`` (the Toolbox's map for the same N and seed)."""

    def __init__(self, landmarks: ArrayLike | int, workspace: float | ArrayLike = 10.0, seed: int | None = 0) -> None:
        ws = np.atleast_1d(np.asarray(workspace, dtype=float))
        self.workspace = np.array([-ws[0], ws[0], -ws[0], ws[0]]) if ws.size == 1 else vector(ws, 4, "workspace")
        if isinstance(landmarks, (int, np.integer)) and not isinstance(landmarks, bool):
            rng = np.random.default_rng(seed)
            x = rng.uniform(self.workspace[0], self.workspace[1], int(landmarks))
            y = rng.uniform(self.workspace[2], self.workspace[3], int(landmarks))
            self.landmarks = np.vstack((x, y))
        else:
            lm = np.array(landmarks, dtype=float)
            if lm.ndim != 2 or lm.shape[0] != 2:
                raise ValueError(f"landmarks must be a (2, N) array of coordinates or a count, got shape {lm.shape}")
            self.landmarks = lm

    def __len__(self) -> int:
        return self.landmarks.shape[1]

    def __getitem__(self, k: int) -> Array:
        return self.landmarks[:, k]

    @property
    def points(self) -> Array:
        """(N, 2) coordinates, to draw."""
        return self.landmarks.T.copy()


class RangeBearingSensor:
    """Range and bearing to the landmarks of ``map`` seen from ``robot`` (a vehicle).

    ``reading()`` picks one visible landmark at random (as the Toolbox: ``integers``
    then ``multivariate_normal`` from ``np.random.default_rng(seed)``) and returns ``(z,
    id)``, ``z = (range, bearing)`` plus noise of covariance ``covar``; ``(None, None)``
    when none is visible. ``range``: max range or ``[min, max]`` (m); ``angle``: half-width
    or ``[min, max]`` of the field of view (rad). ``h``, ``Hx``, ``Hp``, ``Hw``, ``g``,
    ``Gx``, ``Gz`` are the observation model, its Jacobians and its inverse for an EKF.
    """

    def __init__(self, robot: Any, map: LandmarkMap, *, covar: ArrayLike | None = None,
                 range: float | ArrayLike | None = None, angle: float | ArrayLike | None = None,
                 every: int = 1, seed: int | None = 0) -> None:
        self.robot = robot
        self.map = map
        c = np.zeros((2, 2)) if covar is None else np.asarray(covar, dtype=float)
        self.W = np.diag(c) if c.shape == (2,) else c.reshape(2, 2)
        self.r_range = None if range is None else (
            [0.0, float(range)] if np.ndim(range) == 0 else vector(range, 2, "range").tolist())
        self.theta_range = None if angle is None else (
            [-float(angle), float(angle)] if np.ndim(angle) == 0 else vector(angle, 2, "angle").tolist())
        self.every = max(1, int(every))
        self.seed = seed
        self.init()

    def init(self) -> None:
        self.random = np.random.default_rng(self.seed)
        self.count = 0

    def h(self, x: ArrayLike, landmark: int | ArrayLike | None = None) -> Array:
        """Range and bearing (2,) from pose x (3,) to one landmark (its id or its
        coordinates), or (N, 2) to every landmark when None; from (m, 3) poses to one
        landmark, (m, 2)."""
        X = np.asarray(x, dtype=float)
        if X.ndim == 2:
            if landmark is None:
                raise ValueError("h: for many poses give one landmark")
            p = self._lm(landmark)
            dx, dy = p[0] - X[:, 0], p[1] - X[:, 1]
            return np.column_stack((np.hypot(dx, dy), angdiff(np.arctan2(dy, dx), X[:, 2])))
        xp, yp, th = (float(v) for v in vector(x, 3, "x"))
        if landmark is None:
            dx, dy = self.map.landmarks[0] - xp, self.map.landmarks[1] - yp
            return np.column_stack((np.hypot(dx, dy), angdiff(np.arctan2(dy, dx), th)))
        p = self.map[landmark] if isinstance(landmark, (int, np.integer)) else vector(landmark, 2, "landmark")
        dx, dy = p[0] - xp, p[1] - yp
        return np.array([math.hypot(dx, dy), angdiff(math.atan2(dy, dx), th)])

    def _lm(self, landmark: int | ArrayLike) -> Array:
        return self.map[landmark] if isinstance(landmark, (int, np.integer)) else vector(landmark, 2, "landmark")

    def Hx(self, x: ArrayLike, landmark: int | ArrayLike) -> Array:
        """Jacobian (2, 3) of ``h`` with respect to the pose."""
        d = self._lm(landmark) - np.asarray(x, dtype=float)[:2]
        r = math.hypot(d[0], d[1])
        return np.array([[-d[0] / r, -d[1] / r, 0.0], [d[1] / r**2, -d[0] / r**2, -1.0]])

    def Hp(self, x: ArrayLike, landmark: int | ArrayLike) -> Array:
        """Jacobian (2, 2) of ``h`` with respect to the landmark's position."""
        d = self._lm(landmark) - np.asarray(x, dtype=float)[:2]
        r = math.hypot(d[0], d[1])
        return np.array([[d[0] / r, d[1] / r], [-d[1] / r**2, d[0] / r**2]])

    def Hw(self, x: ArrayLike, landmark: Any = None) -> Array:
        """Jacobian (2, 2) of ``h`` with respect to the sensor noise."""
        return np.eye(2)

    def g(self, x: ArrayLike, z: ArrayLike) -> Array:
        """The landmark position (2,) seen at ``z`` from pose x (the inverse of ``h``)."""
        x = np.asarray(x, dtype=float)
        b = float(z[1]) + x[2]
        return np.array([x[0] + z[0] * math.cos(b), x[1] + z[0] * math.sin(b)])

    def Gx(self, x: ArrayLike, z: ArrayLike) -> Array:
        th = float(x[2])
        r, b = float(z[0]), float(z[1])
        return np.array([[1.0, 0.0, -r * math.sin(th + b)], [0.0, 1.0, r * math.cos(th + b)]])

    def Gz(self, x: ArrayLike, z: ArrayLike) -> Array:
        th = float(x[2])
        r, b = float(z[0]), float(z[1])
        return np.array([[math.cos(th + b), -r * math.sin(th + b)], [math.sin(th + b), r * math.cos(th + b)]])

    def visible(self) -> list[tuple[Array, int]]:
        """``(z, id)`` of every landmark within range and field of view (no noise)."""
        zs = self.h(self.robot.x)
        out = [(z, k) for k, z in enumerate(zs)]
        if self.r_range is not None:
            lo, hi = self.r_range
            out = [t for t in out if lo <= t[0][0] <= hi]
        if self.theta_range is not None:
            lo, hi = self.theta_range
            out = [t for t in out if lo <= t[0][1] <= hi]
        return out

    def reading(self) -> tuple[Array | None, int | None]:
        """One noisy observation ``(z, id)`` of a random visible landmark, or (None, None)."""
        self.count += 1
        if self.count % self.every != 0:
            return None, None
        zk = self.visible()
        if not zk:
            return None, None
        z, k = zk[int(self.random.integers(len(zk)))] if len(zk) > 1 else zk[0]
        return z + self.random.multivariate_normal((0.0, 0.0), self.W), int(k)


class LaserScanner:
    """A planar laser scanner: ``n`` beams evenly over ``[-fov/2, fov/2]`` (rad) about the
    heading, each the distance (m) to the first occupied cell of ``grid`` (up to
    ``max_range``), plus Gaussian noise of standard deviation ``sigma`` (m) from
    ``np.random.default_rng(seed)``."""

    def __init__(self, grid: BinaryOccupancyGrid, *, n: int = 61, fov: float = math.pi, max_range: float = 10.0,
                 sigma: float = 0.0, seed: int | None = 0) -> None:
        if n < 1:
            raise ValueError(f"a laser scanner needs at least one beam, got n = {n}")
        self.grid = grid
        self.angles = np.linspace(-fov / 2, fov / 2, n) if n > 1 else np.zeros(1)
        self.max_range = float(max_range)
        self.sigma = float(sigma)
        self.random = np.random.default_rng(seed)

    def scan(self, x: ArrayLike) -> Array:
        """Ranges (n,) from pose x (3,), clipped to [0, max_range]."""
        x = vector(x, 3, "x")
        r = np.array([self.grid.ray(x[:2], x[2] + a, self.max_range) for a in self.angles])
        if self.sigma > 0:
            r = np.clip(r + self.random.normal(0.0, self.sigma, r.shape), 0.0, self.max_range)
        return r

    def points(self, x: ArrayLike, ranges: ArrayLike | None = None) -> Array:
        """The world points (n, 2) the beams hit (those at max range included), to draw."""
        x = vector(x, 3, "x")
        r = self.scan(x) if ranges is None else np.asarray(ranges, dtype=float)
        a = x[2] + self.angles
        return np.column_stack((x[0] + r * np.cos(a), x[1] + r * np.sin(a)))
