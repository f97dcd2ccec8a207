"""Path planners on an occupancy grid, as the Toolbox names them:
:class:`DistanceTransformPlanner`, :class:`AStarPlanner` and :class:`DstarPlanner` (D* Lite:
replans incrementally when cells change cost).

Cells are ``(col, row)`` = (x, y) indices of ``grid.grid[row, col]``; points in the world
(m) are converted with the grid's ``w2g``/``g2w``. Moves go to the 8 neighbours, costing
the distance between cell centres (1 or sqrt 2 cells) times the cell size, times the
cost of the cell entered for a :class:`DstarPlanner`. Paths are returned as (k, 2) world
points from the start to the goal, both included.
"""

from __future__ import annotations

import heapq
import math

import numpy as np
from numpy.typing import ArrayLike

from ._util import Array
from .grid import BinaryOccupancyGrid

__all__ = ["NoPathError", "DistanceTransformPlanner", "AStarPlanner", "DstarPlanner", "path_length"]

SQRT2 = math.sqrt(2.0)
# the Toolbox's order of the 8 neighbours as (drow, dcol): ties go to the first
_DIRS = ((-1, -1), (0, -1), (1, -1), (-1, 0), (-1, 1), (1, 0), (0, 1), (1, 1))


class NoPathError(RuntimeError):
    """The goal cannot be reached from the start."""


def path_length(path: ArrayLike) -> float:
    """Length (m) of a polyline (k, 2)."""
    P = np.asarray(path, dtype=float)
    return float(np.hypot(*np.diff(P, axis=0).T).sum()) if len(P) > 1 else 0.0


def _pt(p: ArrayLike) -> str:
    """A point as the user wrote it: ``(2, 2)``, ``(0.5, 1.25)``."""
    return "(" + ", ".join(f"{float(v):g}" for v in np.asarray(p, dtype=float).reshape(-1)) + ")"


def _cell(grid: BinaryOccupancyGrid, p: ArrayLike, what: str) -> tuple[int, int]:
    c, r = (int(v) for v in grid.w2g(np.asarray(p, dtype=float)))
    if not grid.inside((c, r)):
        raise ValueError(f"the {what} {_pt(p)} is outside the grid")
    if grid.grid[r, c]:
        raise ValueError(f"the {what} {_pt(p)} is in an obstacle")
    return c, r


def distancexform(occupied: ArrayLike, goal: tuple[int, int], metric: str = "euclidean") -> Array:
    """Distance (in cells) from every free cell to the goal cell ``(col, row)`` moving
    between 8 neighbours (``euclidean``: 1 or sqrt 2 a move) or 4 (``cityblock``); NaN on
    obstacles, inf where unreachable. The grassfire of the Toolbox's ``distancexform``,
    iterated until no distance changes (the Toolbox stops when no cell is newly reached,
    which can leave some distances above the shortest)."""
    occ = np.asarray(occupied, dtype=bool)
    if metric in ("euclidean",):
        D = np.array([[SQRT2, 1.0, SQRT2], [1.0, 0.0, 1.0], [SQRT2, 1.0, SQRT2]])
    elif metric in ("cityblock", "manhattan"):
        D = np.array([[np.inf, 1.0, np.inf], [1.0, 0.0, 1.0], [np.inf, 1.0, np.inf]])
    else:
        raise ValueError(f"unknown metric {metric!r}: 'euclidean' or 'cityblock'")
    rows, cols = occ.shape
    dist = np.full(occ.shape, np.inf)
    dist[goal[1], goal[0]] = 0.0
    H = np.full((rows + 2, cols + 2), np.inf)
    while True:
        H[1:-1, 1:-1] = dist
        new = dist.copy()
        for y in range(3):
            for x in range(3):
                if np.isfinite(D[y, x]) and D[y, x] > 0:
                    np.fmin(new, H[y:y + rows, x:x + cols] + D[y, x], out=new)
        new[occ] = np.inf
        if np.array_equal(new, dist):
            break
        dist = new
    dist[occ] = np.nan
    return dist


class _GridPlanner:
    def __init__(self, occgrid: BinaryOccupancyGrid) -> None:
        if not isinstance(occgrid, BinaryOccupancyGrid):
            raise TypeError("a planner needs a BinaryOccupancyGrid (ejsrl.mobile.BinaryOccupancyGrid)")
        self.occgrid = occgrid


class DistanceTransformPlanner(_GridPlanner):
    """``plan(goal)`` computes the distance transform from the goal; ``query(start)``
    descends it, to the neighbour of least distance (ties: the Toolbox's order)."""

    def __init__(self, occgrid: BinaryOccupancyGrid, *, metric: str = "euclidean") -> None:
        super().__init__(occgrid)
        self.metric = metric
        self.distancemap: Array | None = None
        self.goal: Array | None = None

    def plan(self, goal: ArrayLike) -> None:
        g = self.occgrid
        self.goal = np.asarray(goal, dtype=float)
        self._goal_cell = _cell(g, goal, "goal")
        self.distancemap = distancexform(g.grid, self._goal_cell, self.metric) * g.cellsize

    def query(self, start: ArrayLike) -> Array:
        if self.distancemap is None:
            raise RuntimeError("no plan: call plan(goal) first")
        g = self.occgrid
        c, r = _cell(g, start, "start")
        D = self.distancemap
        rows, cols = D.shape
        cells = [(c, r)]
        while (c, r) != self._goal_cell:
            best, step = D[r, c], None
            for dr, dc in _DIRS:
                rr, cc = r + dr, c + dc
                if 0 <= rr < rows and 0 <= cc < cols and D[rr, cc] < best:
                    best, step = D[rr, cc], (dr, dc)
            if step is None or not math.isfinite(best):
                raise NoPathError(f"the goal is not reachable from {_pt(start)}")
            r, c = r + step[0], c + step[1]
            cells.append((c, r))
        return g.g2w(np.array(cells))


class AStarPlanner(_GridPlanner):
    """A* from start to goal over the 8-connected grid (heuristic: the octile distance,
    admissible and consistent, so the path is a shortest one). ``query(start, goal)``."""

    def query(self, start: ArrayLike, goal: ArrayLike) -> Array:
        g = self.occgrid
        s, t = _cell(g, start, "start"), _cell(g, goal, "goal")
        occ = g.grid
        rows, cols = occ.shape

        def h(c: int, r: int) -> float:
            dx, dy = abs(c - t[0]), abs(r - t[1])
            return (dx + dy) + (SQRT2 - 2.0) * min(dx, dy)

        cost = {s: 0.0}
        parent: dict[tuple[int, int], tuple[int, int]] = {}
        heap = [(h(*s), 0.0, s)]
        closed = set()
        self.expanded = 0
        while heap:
            _, gc, u = heapq.heappop(heap)
            if u in closed:
                continue
            closed.add(u)
            self.expanded += 1
            if u == t:
                break
            c, r = u
            for dr, dc in _DIRS:
                rr, cc = r + dr, c + dc
                if not (0 <= rr < rows and 0 <= cc < cols) or occ[rr, cc] or (cc, rr) in closed:
                    continue
                ng = gc + (SQRT2 if dr and dc else 1.0)
                if ng < cost.get((cc, rr), math.inf):
                    cost[(cc, rr)] = ng
                    parent[(cc, rr)] = u
                    heapq.heappush(heap, (ng + h(cc, rr), ng, (cc, rr)))
        if t not in closed:
            raise NoPathError(f"the goal {_pt(goal)} is not reachable from the start")
        cells = [t]
        while cells[-1] != s:
            cells.append(parent[cells[-1]])
        self.cost = cost[t] * g.cellsize
        return g.g2w(np.array(cells[::-1]))


class DstarPlanner(_GridPlanner):
    """D* Lite (Koenig and Likhachev, 2002) towards a fixed goal: ``plan(goal)``, then
    ``query(start)`` for a path; after ``modify_cost(cell_or_point, cost)`` (a cost of inf
    or ``set_obstacle``: an obstacle) the next ``query`` repairs only what changed.

    Each cell has a traversal cost (1 for free cells; ``costmap`` may give others); a move
    costs the distance between cell centres times the cost of the cell entered.
    ``expanded`` counts the cells expanded by the last plan or query."""

    def __init__(self, occgrid: BinaryOccupancyGrid, *, costmap: ArrayLike | None = None) -> None:
        super().__init__(occgrid)
        cm = np.ones(occgrid.shape) if costmap is None else np.array(costmap, dtype=float)
        if cm.shape != occgrid.shape:
            raise ValueError(f"costmap shape {cm.shape} differs from the grid's {occgrid.shape}")
        cm[occgrid.grid] = np.inf
        self.costmap = cm
        self.expanded = 0

    # D* Lite searches backwards from the goal: g, rhs are distances to the goal
    def plan(self, goal: ArrayLike, start: ArrayLike | None = None) -> None:
        g = self.occgrid
        self.goal_cell = _cell(g, goal, "goal")
        rows, cols = g.shape
        self.g = np.full((rows, cols), np.inf)
        self.rhs = np.full((rows, cols), np.inf)
        self.rhs[self.goal_cell[1], self.goal_cell[0]] = 0.0
        self.km = 0.0
        self.U: list[tuple[tuple[float, float], tuple[int, int]]] = []
        self.in_queue: dict[tuple[int, int], tuple[float, float]] = {}
        self.start_cell = self.goal_cell if start is None else _cell(g, start, "start")
        self._push(self.goal_cell)
        self.expanded = 0
        self._compute()

    def _h(self, a: tuple[int, int], b: tuple[int, int]) -> float:
        dx, dy = abs(a[0] - b[0]), abs(a[1] - b[1])
        return (dx + dy) + (SQRT2 - 2.0) * min(dx, dy)

    def _key(self, u: tuple[int, int]) -> tuple[float, float]:
        m = min(self.g[u[1], u[0]], self.rhs[u[1], u[0]])
        return (m + self._h(self.start_cell, u) + self.km, m)

    def _push(self, u: tuple[int, int]) -> None:
        k = self._key(u)
        self.in_queue[u] = k
        heapq.heappush(self.U, (k, u))

    def _neighbours(self, u: tuple[int, int]) -> list[tuple[tuple[int, int], float]]:
        rows, cols = self.costmap.shape
        out = []
        c, r = u
        for dr, dc in _DIRS:
            rr, cc = r + dr, c + dc
            if 0 <= rr < rows and 0 <= cc < cols:
                out.append(((cc, rr), SQRT2 if dr and dc else 1.0))
        return out

    def _cost(self, u: tuple[int, int], v: tuple[int, int], d: float) -> float:
        """Moving from u to its neighbour v (distance d cells): d times v's cost (inf if
        either is an obstacle)."""
        cu, cv = self.costmap[u[1], u[0]], self.costmap[v[1], v[0]]
        return math.inf if math.isinf(cu) or math.isinf(cv) else d * cv

    def _update_vertex(self, u: tuple[int, int]) -> None:
        if u != self.goal_cell:
            best = math.inf
            for v, d in self._neighbours(u):
                best = min(best, self._cost(u, v, d) + self.g[v[1], v[0]])
            self.rhs[u[1], u[0]] = best
        self.in_queue.pop(u, None)  # stale heap entries are skipped when popped
        if self.g[u[1], u[0]] != self.rhs[u[1], u[0]]:
            self._push(u)

    def _top(self) -> tuple[tuple[float, float], tuple[int, int]] | None:
        while self.U:
            k, u = self.U[0]
            if self.in_queue.get(u) == k:
                return k, u
            heapq.heappop(self.U)
        return None

    def _compute(self) -> None:
        s = self.start_cell
        while True:
            top = self._top()
            if top is None:
                break
            k_old, u = top
            ks = self._key(s)
            # keys summed in another order differ in the last bits: a top key within
            # rounding of the start's is expanded too (more work, never a wrong path)
            if not (k_old[0] < ks[0] + 1e-9 * max(1.0, abs(ks[0])) or self.rhs[s[1], s[0]] != self.g[s[1], s[0]]):
                break
            self.expanded += 1
            k_new = self._key(u)
            if k_old < k_new:
                self._push(u)
                continue
            heapq.heappop(self.U)
            del self.in_queue[u]
            gu, ru = self.g[u[1], u[0]], self.rhs[u[1], u[0]]
            if gu > ru:
                self.g[u[1], u[0]] = ru
                for v, _ in self._neighbours(u):
                    self._update_vertex(v)
            else:
                self.g[u[1], u[0]] = math.inf
                self._update_vertex(u)
                for v, _ in self._neighbours(u):
                    self._update_vertex(v)

    def _as_cell(self, where: ArrayLike) -> tuple[int, int]:
        c, r = (int(v) for v in self.occgrid.w2g(np.asarray(where, dtype=float)))
        if not self.occgrid.inside((c, r)):
            raise ValueError(f"{_pt(where)} is outside the grid")
        return c, r

    def modify_cost(self, where: ArrayLike, cost: float) -> None:
        """Set the traversal cost of the cell holding the world point ``where`` (inf: an
        obstacle, and the grid cell is marked occupied; 1: free)."""
        u = self._as_cell(where)
        cost = float(cost)
        if not cost > 0:
            raise ValueError(f"a cell's cost must be positive (inf for an obstacle), got {cost!r}")
        if self.costmap[u[1], u[0]] == cost:
            return
        self.costmap[u[1], u[0]] = cost
        self.occgrid.grid[u[1], u[0]] = math.isinf(cost)
        if not hasattr(self, "g"):
            return
        self._update_vertex(u)
        for v, _ in self._neighbours(u):
            self._update_vertex(v)

    def set_obstacle(self, where: ArrayLike, occupied: bool = True) -> None:
        self.modify_cost(where, math.inf if occupied else 1.0)

    def query(self, start: ArrayLike) -> Array:
        """The path from ``start`` to the goal, repairing the plan after changes (the start
        may move: the keys grow by the heuristic distance it moved, as D* Lite's km)."""
        if not hasattr(self, "g"):
            raise RuntimeError("no plan: call plan(goal) first")
        s = _cell(self.occgrid, start, "start")
        self.km += self._h(self.start_cell, s)
        self.start_cell = s
        self.expanded = 0
        self._compute()
        if math.isinf(self.rhs[s[1], s[0]]):
            raise NoPathError(f"the goal is not reachable from {_pt(start)}")
        cells = [s]
        u = s
        while u != self.goal_cell:
            best, nxt = math.inf, None
            for v, d in self._neighbours(u):
                c = self._cost(u, v, d) + self.g[v[1], v[0]]
                if c < best:
                    best, nxt = c, v
            if nxt is None or len(cells) > self.costmap.size:
                raise NoPathError("the plan has no way on from a cell of the path")
            u = nxt
            cells.append(u)
        self.cost = float(self.rhs[s[1], s[0]]) * self.occgrid.cellsize
        return self.occgrid.g2w(np.array(cells))

    def distance(self, where: ArrayLike) -> float:
        """The planned cost (m, times cell costs) from the cell of ``where`` to the goal."""
        c, r = self._as_cell(where)
        return float(self.rhs[r, c]) * self.occgrid.cellsize


