"""Planners on occupancy grids: the distance-transform planner's paths equal the Toolbox's
(recorded), its distances equal an independent Dijkstra (scipy's csgraph) and are never
above the Toolbox's; A* and D* Lite find paths of the shortest length, and D* Lite replans
after cells change to the cost a fresh search finds, expanding fewer cells."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from ejsrl import mobile as M


def grid_dijkstra(occ: np.ndarray, goal: tuple[int, int]) -> np.ndarray:
    """Shortest 8-connected distances (cells) to goal (col, row), with scipy's Dijkstra."""
    rows, cols = occ.shape
    idx = np.arange(occ.size).reshape(occ.shape)
    src, dst, w = [], [], []
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if dr == dc == 0:
                continue
            r0, r1 = max(0, -dr), rows - max(0, dr)
            c0, c1 = max(0, -dc), cols - max(0, dc)
            a = idx[r0:r1, c0:c1]
            b = idx[r0 + dr:r1 + dr, c0 + dc:c1 + dc]
            ok = ~occ[r0:r1, c0:c1] & ~occ[r0 + dr:r1 + dr, c0 + dc:c1 + dc]
            src.append(a[ok])
            dst.append(b[ok])
            w.append(np.full(ok.sum(), math.sqrt(2) if dr and dc else 1.0))
    G = csr_matrix((np.concatenate(w), (np.concatenate(src), np.concatenate(dst))), shape=(occ.size, occ.size))
    d = dijkstra(G, indices=idx[goal[1], goal[0]])
    return d.reshape(occ.shape)


@pytest.mark.parametrize("name", ["walls", "maze"])
def test_distance_transform_paths_equal_the_toolbox(name: str, rtb_ref, inputs) -> None:  # type: ignore[no-untyped-def]
    grid = M.BinaryOccupancyGrid(inputs.maps()[name])
    for row in rtb_ref["planners"][name]:
        dx = M.DistanceTransformPlanner(grid)
        dx.plan(row["goal"])
        np.testing.assert_array_equal(dx.query(row["start"]), row["path"])
        ours = dx.distancemap
        ref = np.array(row["distancemap"], dtype=float)
        ref[ref < 0] = np.nan
        exact = grid_dijkstra(grid.grid, tuple(row["goal"]))
        free = ~grid.grid & np.isfinite(exact)
        np.testing.assert_allclose(ours[free], exact[free], atol=1e-9, rtol=0)
        assert np.all(ours[free] <= ref[free] + 1e-5)  # the Toolbox's float32 may stop early, above


def test_astar_and_dstar_find_shortest_paths(inputs) -> None:  # type: ignore[no-untyped-def]
    occ = inputs.maps()["walls"]
    grid = M.BinaryOccupancyGrid(occ)
    goal, start = (35, 25), (2, 2)
    exact = grid_dijkstra(grid.grid, goal)[start[1], start[0]]
    astar = M.AStarPlanner(grid)
    path = astar.query(start, goal)
    assert astar.cost == pytest.approx(exact, abs=1e-9)
    assert M.path_length(path) == pytest.approx(exact, abs=1e-9)
    assert not any(grid.isoccupied(p) for p in path)
    steps = np.abs(np.diff(path, axis=0))
    assert steps.max() <= 1 and (steps.sum(axis=1) >= 1).all()  # neighbour to neighbour
    dstar = M.DstarPlanner(grid.copy())
    dstar.plan(goal)
    p2 = dstar.query(start)
    assert dstar.cost == pytest.approx(exact, abs=1e-9)
    assert M.path_length(p2) == pytest.approx(exact, abs=1e-9)


def test_dstar_replans_when_the_map_changes(inputs) -> None:  # type: ignore[no-untyped-def]
    occ = inputs.maps()["walls"]
    grid = M.BinaryOccupancyGrid(occ)
    goal, start = (35, 25), (2, 2)
    dstar = M.DstarPlanner(grid.copy())
    dstar.plan(goal)
    first = dstar.query(start)
    full = dstar.expanded
    # close the first door the path goes through (column 12, rows 5-8)
    for r in range(5, 9):
        dstar.set_obstacle((12, r))
    changed = occ.copy()
    changed[5:9, 12] = 1
    exact = grid_dijkstra(changed.astype(bool), goal)
    assert not math.isfinite(exact[start[1], start[0]])  # that door was the only way: no path now
    with pytest.raises(M.NoPathError, match=r"the goal is not reachable from \(2, 2\)"):
        dstar.query(start)
    # open a new door lower down and make a band of cells costly
    for r in range(0, 3):
        dstar.set_obstacle((12, r), occupied=False)
    changed[0:3, 12] = 0
    for c in range(14, 24):
        dstar.modify_cost((c, 2), 5.0)
    second = dstar.query(start)
    assert dstar.expanded < full  # repaired, not planned again
    fresh = M.DstarPlanner(M.BinaryOccupancyGrid(changed), costmap=dstar.costmap.copy())
    fresh.plan(goal)
    fresh_path = fresh.query(start)
    assert dstar.cost == pytest.approx(fresh.cost, abs=1e-9)
    assert not np.array_equal(first, second)
    assert all(not changed[int(p[1]), int(p[0])] for p in second) and all(not changed[int(p[1]), int(p[0])] for p in fresh_path)
    # with unit costs everywhere the repaired cost is scipy's Dijkstra
    unit = M.DstarPlanner(M.BinaryOccupancyGrid(changed))
    unit.plan(goal)
    unit.query(start)
    assert unit.cost == pytest.approx(grid_dijkstra(changed.astype(bool), goal)[start[1], start[0]], abs=1e-9)


def test_planners_refuse_bad_endpoints(inputs) -> None:  # type: ignore[no-untyped-def]
    grid = M.BinaryOccupancyGrid(inputs.maps()["walls"])
    dx = M.DistanceTransformPlanner(grid)
    with pytest.raises(ValueError, match="goal .* is in an obstacle"):
        dx.plan((12, 0))
    with pytest.raises(ValueError, match="outside the grid"):
        M.AStarPlanner(grid).query((0, 0), (100, 3))
    with pytest.raises(RuntimeError, match="call plan"):
        dx.query((1, 1))


def test_grid_from_an_image_file(tmp_path) -> None:  # type: ignore[no-untyped-def]
    import cv2

    img = np.full((20, 30), 255, np.uint8)
    img[0:5, 10:12] = 0  # a dark block at the top of the picture
    path = tmp_path / "map.png"
    cv2.imwrite(str(path), img)
    grid = M.BinaryOccupancyGrid.from_image(path, cellsize=0.5, origin=(-1.0, 2.0))
    assert grid.shape == (20, 30)
    assert grid.grid.sum() == 10
    # the top rows of the picture are the largest y
    assert grid.isoccupied((-1.0 + 0.5 * 10, 2.0 + 0.5 * 19)) and not grid.isoccupied((-1.0 + 0.5 * 10, 2.0))
    assert grid.isoccupied((100.0, 0.0))  # off the grid
    with pytest.raises(FileNotFoundError, match="cannot read the image"):
        M.BinaryOccupancyGrid.from_image(tmp_path / "missing.png")


def test_laser_scanner_ranges_to_walls() -> None:
    occ = np.zeros((41, 41), dtype=bool)
    occ[:, 30] = True  # a wall at x = 30 (cells of 0.1 m: x = 3.0 m)
    grid = M.BinaryOccupancyGrid(occ, cellsize=0.1)
    laser = M.LaserScanner(grid, n=5, fov=math.radians(60), max_range=10.0)
    x = (1.0, 2.0, 0.0)
    r = laser.scan(x)
    expect = (3.0 - 0.05 - 1.0) / np.cos(laser.angles)  # to the wall cell's edge
    np.testing.assert_allclose(r, expect, atol=0.03)  # quarter-cell steps
    pts = laser.points(x, r)
    assert np.all(np.abs(pts[:, 0] - 2.95) < 0.03)
