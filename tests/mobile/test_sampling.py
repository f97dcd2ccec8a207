"""Sampling planners: PRM paths are clear of obstacles (every segment checked on the grid
independently, at 1/20 cell) and no shorter than the straight line, and approach the
any-angle shortest path as the roadmap grows; RRT's car-like paths are clear, end on the
goal pose, and never turn tighter than the vehicle's minimum radius."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ejsrl import mobile as M


def clear(grid: M.BinaryOccupancyGrid, path: np.ndarray) -> bool:
    for a, b in zip(path[:-1, :2], path[1:, :2]):
        for s in np.linspace(0, 1, max(2, int(np.hypot(*(b - a)) * 20 / grid.cellsize) + 1)):
            if grid.isoccupied(a + s * (b - a)):
                return False
    return True


def test_prm_paths_are_clear_and_shorten_with_more_points(inputs) -> None:  # type: ignore[no-untyped-def]
    grid = M.BinaryOccupancyGrid(inputs.maps()["walls"])
    start, goal = (2.0, 2.0), (35.0, 25.0)
    costs = []
    for n in (150, 400):
        prm = M.PRMPlanner(grid, npoints=n, seed=3)
        prm.plan()
        path = prm.query(start, goal)
        assert np.array_equal(path[0], start) and np.array_equal(path[-1], goal)
        assert clear(grid, path)
        assert prm.cost == pytest.approx(M.path_length(path), rel=1e-12)
        assert prm.cost >= math.dist(start, goal)
        costs.append(prm.cost)
    # near the shortest: the grid's 8-connected shortest path (A*) is within 8 % of the
    # any-angle one, and a roadmap's path within a few % more
    astar = M.AStarPlanner(grid)
    astar.query(start, goal)
    assert max(costs) < astar.cost * 1.05


def test_prm_refuses_ends_in_obstacles(inputs) -> None:  # type: ignore[no-untyped-def]
    grid = M.BinaryOccupancyGrid(inputs.maps()["walls"])
    prm = M.PRMPlanner(grid, npoints=50, seed=1)
    with pytest.raises(RuntimeError, match="call plan"):
        prm.query((1, 1), (2, 2))
    prm.plan()
    with pytest.raises(ValueError, match=r"the goal \(12, 0\) is in an obstacle"):
        prm.query((2, 2), (12, 0))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rrt_car_like_paths_respect_the_turning_radius(inputs, seed: int) -> None:  # type: ignore[no-untyped-def]
    grid = M.BinaryOccupancyGrid(inputs.maps()["walls"])
    rrt = M.RRTPlanner(grid, L=1.0, steer_max=0.6, seed=seed)
    goal = np.array([35.0, 25.0, math.pi / 2])
    path = rrt.query((2.0, 2.0, 0.0), goal)
    assert clear(grid, path)
    end = path[-1]
    assert math.hypot(end[0] - goal[0], end[1] - goal[1]) < 0.5 and abs(M.angdiff(end[2], goal[2])) < 0.5
    # consecutive poses: the heading turns by at most ds / R_min over a step of ds
    d = np.hypot(*np.diff(path[:, :2], axis=0).T)
    turn = np.abs(M.angdiff(np.diff(path[:, 2])))
    moving = d > 1e-9
    assert np.all(turn[moving] <= d[moving] / rrt.radius_min * (1 + 1e-3))  # d: the chord of the arc
    assert rrt.radius_min == pytest.approx(1.0 / math.tan(0.6))
