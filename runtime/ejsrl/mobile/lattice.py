"""A lattice planner, as the Toolbox's :class:`LatticePlanner`: a graph of poses reached
from a root by three motion primitives, searched for the cheapest path between two of
them.

The primitives, in the frame of the pose they start from (world units, m and rad):
``S`` one unit straight ahead, ``L`` a quarter circle of unit radius to the left (ending
at (1, 1) turned +pi/2) and ``R`` its mirror to the right, costing ``costs = (1, pi/2,
pi/2)`` by default. :meth:`LatticePlanner.plan` grows the lattice breadth first from
``root`` (``iterations`` levels, or until no new pose is free when there is a grid): a
pose whose position is an obstacle (or off the grid) is left out, as in the Toolbox only
the end of a move is checked. :meth:`LatticePlanner.query` finds the cheapest sequence of
moves (A* with an admissible heuristic: the straight-line distance times the least cost
per unit of distance a move achieves), and returns the poses (k, 3) and the moves
(``"SLR..."``). :meth:`LatticePlanner.curve` samples the path's arcs to draw it.

Poses are kept as integer lattice coordinates ``(i, j, k)`` in the root's frame (``k``:
heading in quarter turns), so that a pose reached two ways is one vertex exactly.
"""

from __future__ import annotations

import heapq
import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ._util import Array, vector
from .grid import BinaryOccupancyGrid
from .planners import NoPathError, _pt

__all__ = ["LatticePlanner", "LatticeStatus"]

#: move -> (di, dj, dk) in the frame of the pose it starts from
_MOVES = {"S": (1, 0, 0), "L": (1, 1, 1), "R": (1, -1, -1)}
#: the unit rotations by k quarter turns: (cos, sin)
_QUARTER = ((1, 0), (0, 1), (-1, 0), (0, -1))


class LatticeStatus(NamedTuple):
    """What a query found: ``cost`` of the path, ``segments`` the moves ("S", "L", "R")."""

    cost: float
    segments: list[str]


class LatticePlanner:
    """Lattice planner over an optional :class:`BinaryOccupancyGrid` (see the module text).

    ``costs``: of the straight, left and right moves; ``root``: the pose ``(x, y, theta)``
    the lattice grows from. After :meth:`plan`, ``vertices`` (m, 3) are the lattice's
    poses and ``edges`` the ``(from, to, move)`` of every move between them.
    """

    def __init__(self, occgrid: BinaryOccupancyGrid | None = None, *, costs: ArrayLike | None = None,
                 root: ArrayLike = (0.0, 0.0, 0.0)) -> None:
        if occgrid is not None and not isinstance(occgrid, BinaryOccupancyGrid):
            raise TypeError("a lattice planner's map is a BinaryOccupancyGrid (ejsrl.mobile.BinaryOccupancyGrid)")
        self.occgrid = occgrid
        c = vector((1.0, math.pi / 2, math.pi / 2) if costs is None else costs, 3, "costs")
        if not np.all(c > 0):
            raise ValueError(f"the moves' costs must be positive, got {c.tolist()}")
        self.costs = {"S": float(c[0]), "L": float(c[1]), "R": float(c[2])}
        self.root = vector(root, 3, "root")
        # least cost per unit of straight-line distance of a move: S goes 1, L and R sqrt 2
        self._rate = min(self.costs["S"], self.costs["L"] / math.sqrt(2.0), self.costs["R"] / math.sqrt(2.0))
        self._index: dict[tuple[int, int, int], int] = {}
        self._keys: list[tuple[int, int, int]] = []
        self._adj: list[list[tuple[int, str]]] = []
        self.edges: list[tuple[int, int, str]] = []

    # -- poses ---------------------------------------------------------------------------------
    def _world(self, key: tuple[int, int, int]) -> Array:
        """The world pose (3,) of lattice coordinates ``(i, j, k)``."""
        x0, y0, t0 = self.root
        i, j, k = key
        c, s = math.cos(t0), math.sin(t0)
        th = math.remainder(t0 + k * math.pi / 2, 2 * math.pi)
        return np.array([x0 + c * i - s * j, y0 + s * i + c * j, th])

    def _key(self, pose: ArrayLike, what: str) -> tuple[int, int, int]:
        """The lattice coordinates of a world pose; ValueError if it is not a lattice pose."""
        x, y, th = (float(v) for v in vector(pose, 3, what))
        x0, y0, t0 = self.root
        c, s = math.cos(t0), math.sin(t0)
        i, j = c * (x - x0) + s * (y - y0), -s * (x - x0) + c * (y - y0)
        k = math.remainder(th - t0, 2 * math.pi) / (math.pi / 2)
        key = (int(round(i)), int(round(j)), int(round(k)) % 4)
        if abs(i - key[0]) > 1e-3 or abs(j - key[1]) > 1e-3 or abs(k - round(k)) > 1e-3 or key not in self._index:
            raise ValueError(f"the {what} {_pt(pose)} is not a pose of the lattice")
        return key

    def _free(self, key: tuple[int, int, int]) -> bool:
        return self.occgrid is None or not self.occgrid.isoccupied(self._world(key)[:2])

    @property
    def vertices(self) -> Array:
        """The lattice's poses (m, 3) in the world, in the order they were added."""
        return np.array([self._world(k) for k in self._keys]).reshape(-1, 3)

    # -- planning ------------------------------------------------------------------------------
    def plan(self, iterations: int | None = None) -> None:
        """Grow the lattice from the root: ``iterations`` levels of moves (every one when
        None, which needs a grid to stop it)."""
        if iterations is None and self.occgrid is None:
            raise ValueError("iterations must be given when there is no occupancy grid to fill")
        root = (0, 0, 0)
        self._index = {root: 0}
        self._keys = [root]
        self._adj = [[]]
        self.edges = []
        frontier = [root]
        level = 0
        while frontier and (iterations is None or level < iterations):
            new: list[tuple[int, int, int]] = []
            for u in frontier:
                i, j, k = u
                c, s = _QUARTER[k]
                iu = self._index[u]
                for move, (di, dj, dk) in _MOVES.items():
                    v = (i + c * di - s * dj, j + s * di + c * dj, (k + dk) % 4)
                    iv = self._index.get(v)
                    if iv is None:
                        if not self._free(v):
                            continue
                        iv = len(self._keys)
                        self._index[v] = iv
                        self._keys.append(v)
                        self._adj.append([])
                        new.append(v)
                    self._adj[iu].append((iv, move))
                    self.edges.append((iu, iv, move))
            frontier = new
            level += 1
        self.iterations = level

    def query(self, start: ArrayLike, goal: ArrayLike) -> tuple[Array, LatticeStatus]:
        """The cheapest path from ``start`` to ``goal`` (poses of the lattice): its poses
        (k, 3) from start to goal and a :class:`LatticeStatus`. ``NoPathError`` if the goal
        cannot be reached (moves go forwards only), ``ValueError`` if an end is not a pose
        of the lattice."""
        if not self._keys:
            raise RuntimeError("no lattice: call plan() first")
        s = self._index[self._key(start, "start")]
        t = self._index[self._key(goal, "goal")]
        tx = self._world(self._keys[t])[:2]
        pos = [self._world(k)[:2] for k in self._keys]

        def h(v: int) -> float:
            return self._rate * float(math.hypot(*(pos[v] - tx)))

        cost = {s: 0.0}
        parent: dict[int, tuple[int, str]] = {}
        heap = [(h(s), 0.0, s)]
        done: set[int] = set()
        while heap:
            _, g, u = heapq.heappop(heap)
            if u in done:
                continue
            done.add(u)
            if u == t:
                break
            for v, move in self._adj[u]:
                ng = g + self.costs[move]
                if ng < cost.get(v, math.inf) - 1e-12:
                    cost[v] = ng
                    parent[v] = (u, move)
                    heapq.heappush(heap, (ng + h(v), ng, v))
        if t not in done:
            raise NoPathError(f"the goal {_pt(goal)} cannot be reached through the lattice from {_pt(start)}")
        seq, moves = [t], []
        while seq[-1] != s:
            u, move = parent[seq[-1]]
            seq.append(u)
            moves.append(move)
        seq.reverse()
        moves.reverse()
        return np.array([self._world(self._keys[v]) for v in seq]), LatticeStatus(cost[t], moves)

    def curve(self, path: ArrayLike, npoints: int = 10) -> Array:
        """Points (m, 2) along a path of lattice poses (k, 3) as the vehicle drives it: the
        straight moves' ends and each turn's quarter circle sampled at ``npoints``."""
        P = np.asarray(path, dtype=float).reshape(-1, 3)
        out = [P[0, :2]] if len(P) else []
        a = np.linspace(0.0, math.pi / 2, max(2, int(npoints)))[1:]
        for p, q in zip(P[:-1], P[1:]):
            turn = math.remainder(q[2] - p[2], 2 * math.pi)
            c, s = math.cos(p[2]), math.sin(p[2])
            if abs(turn) < 1e-6:
                out.append(q[:2])
                continue
            side = 1.0 if turn > 0 else -1.0
            local = np.column_stack((np.sin(a), side * (1.0 - np.cos(a))))
            out.extend(local @ np.array([[c, s], [-s, c]]) + p[:2])
        return np.array(out).reshape(-1, 2)
