"""Sampling planners on an occupancy grid: :class:`PRMPlanner` (probabilistic roadmap) and
:class:`RRTPlanner` (a rapidly-exploring random tree of car-like motions, with the
vehicle's turning radius), as the Toolbox names them. Random numbers come from
``np.random.default_rng(seed)``; world units (m, rad).
"""

from __future__ import annotations

import heapq
import math


import numpy as np
from numpy.typing import ArrayLike

from ._util import Array, angdiff, vector
from .grid import BinaryOccupancyGrid
from .planners import NoPathError, _pt

__all__ = ["PRMPlanner", "RRTPlanner"]


def _segment_free(grid: BinaryOccupancyGrid, a: Array, b: Array) -> bool:
    """Is the straight segment a-b clear of occupied cells (checked every quarter cell)?"""
    d = float(np.hypot(*(b - a)))
    n = max(2, int(math.ceil(d / (0.25 * grid.cellsize))) + 1)
    pts = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
    cells = grid.w2g(pts)
    c, r = cells[:, 0], cells[:, 1]
    rows, cols = grid.shape
    if (c < 0).any() or (r < 0).any() or (c >= cols).any() or (r >= rows).any():
        return False
    return not grid.grid[r, c].any()


class PRMPlanner:
    """``plan()`` samples ``npoints`` free points and joins every pair closer than
    ``dist_thresh`` (m) whose segment is free; ``query(start, goal)`` joins the two ends to
    their nearest reachable roadmap points and returns the shortest roadmap path (k, 2)
    (``cost``: its length, m)."""

    def __init__(self, occgrid: BinaryOccupancyGrid, *, npoints: int = 100, dist_thresh: float | None = None,
                 seed: int | None = 0) -> None:
        self.occgrid = occgrid
        self.npoints = int(npoints)
        ws = occgrid.extent
        self.dist_thresh = float(dist_thresh) if dist_thresh is not None else 0.3 * max(ws[1] - ws[0], ws[3] - ws[2])
        self.seed = seed
        self.points: Array = np.zeros((0, 2))
        self.edges: list[tuple[int, int]] = []

    def plan(self) -> None:
        g = self.occgrid
        rng = np.random.default_rng(self.seed)
        ws = g.extent
        pts: list[Array] = []
        tries = 0
        while len(pts) < self.npoints:
            tries += 1
            if tries > 1000 * self.npoints:
                raise RuntimeError("PRM: hardly any free space to sample in this grid")
            p = np.array([rng.uniform(ws[0], ws[1]), rng.uniform(ws[2], ws[3])])
            if not g.isoccupied(p):
                pts.append(p)
        self.points = np.array(pts)
        self.adj: list[list[tuple[int, float]]] = [[] for _ in pts]
        self.edges = []
        P = self.points
        for i in range(len(P)):
            d = np.hypot(*(P[i + 1:] - P[i]).T)
            for k in np.flatnonzero(d < self.dist_thresh):
                j = i + 1 + int(k)
                if _segment_free(g, P[i], P[j]):
                    self.adj[i].append((j, float(d[k])))
                    self.adj[j].append((i, float(d[k])))
                    self.edges.append((i, j))

    def _attach(self, p: Array, what: str) -> list[tuple[int, float]]:
        if self.occgrid.isoccupied(p):
            raise ValueError(f"the {what} {_pt(p)} is in an obstacle or off the grid")
        d = np.hypot(*(self.points - p).T)
        out = [(int(k), float(d[k])) for k in np.argsort(d) if _segment_free(self.occgrid, p, self.points[k])]
        if not out:
            raise NoPathError(f"the {what} {_pt(p)} sees no roadmap point")
        return out[:5]

    def query(self, start: ArrayLike, goal: ArrayLike) -> Array:
        if not len(self.points):
            raise RuntimeError("no roadmap: call plan() first")
        s, t = vector(start, 2, "start"), vector(goal, 2, "goal")
        if _segment_free(self.occgrid, s, t):
            self.cost = float(np.hypot(*(t - s)))
            return np.array([s, t])
        n = len(self.points)
        S, T = n, n + 1  # the two ends as extra nodes
        extra: dict[int, list[tuple[int, float]]] = {S: self._attach(s, "start"), T: []}
        for k, d in self._attach(t, "goal"):
            extra.setdefault(k, []).append((T, d))
        dist = {S: 0.0}
        parent: dict[int, int] = {}
        heap = [(0.0, S)]
        done = set()
        while heap:
            du, u = heapq.heappop(heap)
            if u in done:
                continue
            done.add(u)
            if u == T:
                break
            nbrs = (self.adj[u] if u < n else []) + extra.get(u, [])
            for v, w in nbrs:
                if du + w < dist.get(v, math.inf):
                    dist[v] = du + w
                    parent[v] = u
                    heapq.heappush(heap, (du + w, v))
        if T not in done:
            raise NoPathError(f"the roadmap joins no path from {_pt(s)} to {_pt(t)}: plan with more points")
        order = [T]
        while order[-1] != S:
            order.append(parent[order[-1]])
        pts = {S: s, T: t}
        self.cost = dist[T]
        return np.array([pts[k] if k in pts else self.points[k] for k in order[::-1]])


class RRTPlanner:
    """A tree of car-like motions from the start pose (a kinematic bicycle of wheel base
    ``L`` and steering limit ``steer_max``, so turns no tighter than ``L / tan(steer_max)``):
    each iteration draws a random pose, takes the nearest tree node (distance plus
    ``heading_weight`` times the heading difference) and drives from it for ``step`` m
    with the steering (of ``nsteer`` values over the limits, forwards or in reverse) that
    ends nearest the drawn pose, keeping the motion if it stays clear of obstacles (one
    draw in ten is the goal itself, towards which the motions from its ten nearest nodes
    compete). ``query(start, goal)`` grows the tree until a pose
    along a motion is within ``tol`` (m) and ``heading_tol`` (rad) of the goal, or
    ``iterations`` pass; the path is the poses (k, 3), every ``ds`` m along exact arcs."""

    def __init__(self, occgrid: BinaryOccupancyGrid, *, L: float = 1.0, steer_max: float = 0.6, step: float = 1.0,
                 nsteer: int = 7, tol: float = 0.5, heading_tol: float = 0.5, heading_weight: float = 0.3,
                 iterations: int = 5000, reverse: bool = True, ds: float = 0.1, seed: int | None = 0) -> None:
        self.occgrid = occgrid
        self.L, self.steer_max = float(L), float(steer_max)
        self.step, self.ds = float(step), float(ds)
        self.steers = np.linspace(-steer_max, steer_max, max(1, int(nsteer)))
        self.tol, self.heading_tol, self.heading_weight = float(tol), float(heading_tol), float(heading_weight)
        self.iterations = int(iterations)
        self.reverse = reverse
        self.seed = seed

    @property
    def radius_min(self) -> float:
        return self.L / math.tan(self.steer_max)

    def _drive(self, x: Array, v: float, gamma: float) -> Array:
        """The poses (n, 3) of a bicycle driven ``step`` m from x at steering gamma (exact arcs)."""
        n = max(2, int(math.ceil(self.step / self.ds)))
        s = np.linspace(self.ds, self.step, n) * v
        k = math.tan(gamma) / self.L
        th = x[2] + k * s
        if abs(k) < 1e-12:
            return np.column_stack((x[0] + s * math.cos(x[2]), x[1] + s * math.sin(x[2]), th))
        return np.column_stack((x[0] + (np.sin(th) - math.sin(x[2])) / k, x[1] - (np.cos(th) - math.cos(x[2])) / k, th))

    def _free(self, poses: Array) -> bool:
        g = self.occgrid
        cells = g.w2g(poses[:, :2])
        c, r = cells[:, 0], cells[:, 1]
        rows, cols = g.shape
        if (c < 0).any() or (r < 0).any() or (c >= cols).any() or (r >= rows).any():
            return False
        return not g.grid[r, c].any()

    def _dist(self, nodes: Array, x: Array) -> Array:
        return np.hypot(nodes[:, 0] - x[0], nodes[:, 1] - x[1]) + self.heading_weight * np.abs(angdiff(nodes[:, 2], x[2]))

    def query(self, start: ArrayLike, goal: ArrayLike) -> Array:
        s, t = vector(start, 3, "start"), vector(goal, 3, "goal")
        for p, what in ((s, "start"), (t, "goal")):
            if self.occgrid.isoccupied(p[:2]):
                raise ValueError(f"the {what} {_pt(p[:2])} is in an obstacle or off the grid")
        rng = np.random.default_rng(self.seed)
        ws = self.occgrid.extent
        nodes = [s]
        parent = [-1]
        motions: list[Array] = [s[None, :]]
        dirs = (1.0, -1.0) if self.reverse else (1.0,)
        for it in range(self.iterations):
            to_goal = rng.uniform() < 0.1
            target = t if to_goal else np.array([rng.uniform(ws[0], ws[1]), rng.uniform(ws[2], ws[3]),
                                                 rng.uniform(-math.pi, math.pi)])
            N = np.array(nodes)
            dist = self._dist(N, target)
            # towards the goal, the motions from its 10 nearest nodes compete (aligning the heading)
            near = np.argsort(dist)[:10] if to_goal else [int(np.argmin(dist))]
            best = None
            for i in near:
                for v in dirs:
                    for gmm in self.steers:
                        m = self._drive(N[i], v, float(gmm))
                        d = float(self._dist(m[-1:], target)[0])
                        if best is None or d < best[0]:
                            best = (d, m, int(i))
            m, i = best[1], best[2]
            if not self._free(m):
                continue
            # a pose along the motion within the goal's tolerances ends the search there
            hit = np.flatnonzero((np.hypot(m[:, 0] - t[0], m[:, 1] - t[1]) < self.tol)
                                 & (np.abs(angdiff(m[:, 2], t[2])) < self.heading_tol))
            if len(hit):
                m = m[:hit[0] + 1]
            nodes.append(m[-1])
            parent.append(i)
            motions.append(m)
            if len(hit):
                self.iterations_used = it + 1
                chain = [len(nodes) - 1]
                while parent[chain[-1]] >= 0:
                    chain.append(parent[chain[-1]])
                path = np.vstack([motions[k] for k in chain[::-1]])
                self.tree = np.array(nodes)
                self.parents = np.array(parent)
                return path
        self.tree = np.array(nodes)
        self.parents = np.array(parent)
        raise NoPathError(f"RRT: no motion reached {_pt(t)} within {self.iterations} iterations")

