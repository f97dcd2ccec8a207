"""The 2D panel's mobile-robot kinds (vehicle, laser, occupancy, path, ellipse, particles)
without a browser: the PRM-and-laser lab's frame puts the vehicle's outline at its pose,
each laser ray from the sensor to where an independent LaserScanner's beam stops, the
built map's picture cell for cell, the PRM path; an ellipse holds its chi-squared radius
about its centre; particles and paths take N x 3 poses; bad properties are build errors at
FILE:LINE:COL."""

from __future__ import annotations

import base64
import math
from pathlib import Path

import numpy as np
import pytest

from ejsgen.errors import SpecErrors
from testkit import ROOT

LAB = ROOT / "examples" / "mobile_prm_laser.ejs.yaml"


def _fake_gui():  # type: ignore[no-untyped-def]
    """tests/view/test_panel2d.py's FakeGui (what viser's GUI API would be given)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("_panel2d_tests", ROOT / "tests" / "view" / "test_panel2d.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)  # type: ignore[union-attr]
    return mod.FakeGui()


def built(tmp_path: Path, spec: Path | str):  # type: ignore[no-untyped-def]
    from ejsgen.cli import build
    from ejsrl.app import load_app
    from ejsrl.view._drawing import DrawingBinding
    from ejsrl.view.elements2d import Drawing

    if isinstance(spec, str):
        path = tmp_path / "lab.ejs.yaml"
        path.write_text(spec)
        spec = path
    app = load_app(build(spec, tmp_path / "app"))
    drawing = next(el for el in app.view if isinstance(el, Drawing))
    return app, DrawingBinding(_fake_gui(), drawing, app, key="d")


def xy(item) -> np.ndarray:  # type: ignore[no-untyped-def]
    width = 4 if item["t"] in ("segments", "arrows", "rects") else 2
    return np.frombuffer(base64.b64decode(item["xy"]), dtype="<f4").reshape(-1, width).astype(float)


def test_the_lab_draws_the_robot_its_scan_its_map_and_its_path(tmp_path) -> None:  # type: ignore[no-untyped-def]
    import cv2

    from ejsrl.mobile import BinaryOccupancyGrid, LaserScanner

    app, b = built(tmp_path, LAB)
    m = app.model
    app.play()
    for _ in range(40):
        app.frame()
    b.refresh()
    items = b.frame["items"]
    pose = np.array(m.pose)
    # the vehicle: its pose's position first (the drag handle), then its triangle turned by theta
    robot = next(it for it in items if it["t"] == "polyline" and it["closed"])
    pts = xy(robot)
    np.testing.assert_allclose(pts[0], pose[:2], atol=1e-5)
    nose = pose[:2] + 0.6 * 1.2 * np.array([math.cos(pose[2]), math.sin(pose[2])])
    np.testing.assert_allclose(pts[2], nose, atol=1e-5)
    assert np.isnan(pts[1]).all() and len(pts) == 5
    # the laser: 61 rays from the sensor to where the beams stop on the floor plan
    walls = np.asarray(m.walls)
    scanner = LaserScanner(BinaryOccupancyGrid(walls, cellsize=0.5), n=61, fov=math.pi, max_range=8.0)
    r = scanner.scan(pose)
    rays = next(it for it in items if it["t"] == "segments" and it["stroke"] == "#f03e3e")
    seg = xy(rays)
    a = pose[2] + np.linspace(-math.pi / 2, math.pi / 2, 61)
    np.testing.assert_allclose(seg[:, :2], np.tile(pose[:2], (61, 1)), atol=1e-5)
    np.testing.assert_allclose(seg[:, 2:], pose[:2] + r[:, None] * np.column_stack((np.cos(a), np.sin(a))), atol=1e-4)
    hits = next(it for it in items if it["t"] == "markers" and it["fill"] == "#f03e3e")
    assert len(xy(hits)) == int(np.count_nonzero(r < 8.0)) > 0
    # the map: one pixel per cell, the top row the largest y; black walls, white free, grey unseen
    grid = next(it for it in items if it["t"] == "image")
    assert (grid["x0"], grid["x1"], grid["y0"], grid["y1"]) == (-0.25, 29.75, -0.25, 19.75) and grid["smooth"] is False
    png = base64.b64decode(grid["src"].split(",", 1)[1])
    img = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_GRAYSCALE)
    known = np.asarray(m.known)
    assert img.shape == known.shape
    np.testing.assert_array_equal(img[::-1] == 0, known == 1.0)
    np.testing.assert_array_equal(img[::-1] == 255, known == 0.0)
    assert 0 < np.count_nonzero(known == 1.0) and np.all(walls[known == 1.0])  # every wall seen is a wall
    # the path: the planner's, with a dot at its start and a cross at the goal
    path = next(it for it in items if it["t"] == "polyline" and it["stroke"] == "#2f9e44")
    np.testing.assert_allclose(xy(path), np.asarray(m.path), atol=1e-5)
    goal = next(it for it in items if it["t"] == "markers" and it["shape"] == "cross")
    np.testing.assert_allclose(xy(goal)[0], np.asarray(m.path)[-1], atol=1e-5)


KINDS = """\
ejs: 1
title: kinds
model:
  variables:
    t: 0.0
    P: {expr: "np.array([[0.5, 0.2, 0.0], [0.2, 0.3, 0.0], [0.0, 0.0, 0.1]])"}
    c: {value: [1.0, -1.0]}
    poses: {expr: "np.array([[0.0, 0.0, 0.5], [1.0, 2.0, 1.0], [3.0, 1.0, -1.0]])"}
    x0: 2.0
    y0: 1.0
    v3: {value: [1.0, 2.0, 3.0]}
    m32: {value: [[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]]}
view:
  - drawing:
      x_range: [-5, 5]
      y_range: [-5, 5]
      children:
        - ellipse: {name: e, position: c, covariance: P, confidence: 0.9, scale: 2}
        - particles: {name: p, points: poses, color: orange}
        - path: {name: route, points: poses}
        - vehicle:
            name: v
            pose: [x0, y0, 0.3]
            footprint: [[1, 0.5], [-1, 0.5], [-1, -0.5], [1, -0.5]]
            drag: {bind: [x0, y0]}
"""


def test_ellipse_particles_path_and_a_dragged_footprint(tmp_path) -> None:  # type: ignore[no-untyped-def]
    app, b = built(tmp_path, KINDS)
    b.refresh()
    items = b.frame["items"]
    ell = xy(items[0])
    d = ell - [1.0, -1.0]
    P2 = np.array([[0.5, 0.2], [0.2, 0.3]]) * 4.0  # scale 2: a covariance 4 times larger
    m2 = np.einsum("ij,jk,ik->i", d, np.linalg.inv(P2), d)
    np.testing.assert_allclose(m2, -2.0 * math.log(1.0 - 0.9), rtol=1e-5)  # chi-squared, 2 dof, 90 %
    np.testing.assert_allclose(xy(items[1]), [[0, 0], [1, 2], [3, 1]], atol=1e-6)
    assert items[1]["fill"] == "orange"
    np.testing.assert_allclose(xy(items[2]), [[0, 0], [1, 2], [3, 1]], atol=1e-6)
    car = next(it for it in items if it.get("id") == "v")
    c, s = math.cos(0.3), math.sin(0.3)
    corners = np.array([[1, 0.5], [-1, 0.5], [-1, -0.5], [1, -0.5]]) @ np.array([[c, s], [-s, c]]) + [2.0, 1.0]
    np.testing.assert_allclose(xy(car)[2:], corners, atol=1e-5)
    assert b.drag("v", "move", -1.5, 2.5)  # dragging the vehicle moves its pose's position
    assert (app.model.x0, app.model.y0) == (-1.5, 2.5)
    b.refresh()
    np.testing.assert_allclose(xy(next(it for it in b.frame["items"] if it.get("id") == "v"))[0], [-1.5, 2.5], atol=1e-6)


def _errors(tmp_path: Path, child: str) -> list[str]:
    from ejsgen.cli import build

    text = KINDS.split("      children:\n")[0] + "      children:\n" + child
    spec = tmp_path / "bad.ejs.yaml"
    spec.write_text(text)
    with pytest.raises(SpecErrors) as info:
        build(spec, tmp_path / "bad")
    return [str(e).replace(f"{tmp_path}/", "") for e in info.value.errors]


@pytest.mark.parametrize(("child", "where", "words"), [
    ("        - vehicle: {pose: c}\n", "bad.ejs.yaml:18:27", "needs 3 numbers, but 'c' has shape (2,)"),
    ("        - ellipse: {position: c, covariance: v3}\n", "bad.ejs.yaml:18:46", "must be a square covariance matrix"),
    ("        - ellipse: {position: c, covariance: P, confidence: 95}\n", "bad.ejs.yaml:18:61", "between 0 and 1"),
    ("        - particles: {points: v3}\n", "bad.ejs.yaml:18:31", "N x 2 (positions) or N x 3 (poses)"),
    ("        - laser: {pose: v3, ranges: m32}\n", "bad.ejs.yaml:18:37", "must be a vector (n,), one per beam"),
    ("        - vehicel: {pose: v3}\n", "bad.ejs.yaml:18:11", "did you mean 'vehicle'"),
])
def test_bad_mobile_kinds_are_build_errors_at_their_place(tmp_path, child: str, where: str, words: str) -> None:  # type: ignore[no-untyped-def]
    errors = _errors(tmp_path, child)
    assert any(e.startswith(where) and words in e for e in errors), errors


SCENE = """\
ejs: 1
title: kinds 3D
imports:
  - from ejsrl.mobile import BinaryOccupancyGrid, LaserScanner
model:
  variables:
    t: 0.0
    x: {expr: "np.array([2.0, 1.0, 0.5])"}
    walls: {expr: "np.eye(6, dtype=bool)"}
    sc: {expr: "LaserScanner(BinaryOccupancyGrid(np.eye(6), cellsize=0.5), n=5, fov=pi, max_range=3.0)"}
    P: {expr: "np.diag([0.2, 0.1, 0.01])"}
    pts: {expr: "np.array([[0.0, 0.0, 0.1], [1.0, 1.0, 0.2]])"}
  evolution:
    - code: |
        x = x + np.array([0.01, 0.0, 0.01])
        t = t + 0.1
view:
  - scene:
      - vehicle: {name: car, pose: x, length: 1.2, height: 0.4, color: steelblue}
      - laser: {name: scan, pose: x, ranges: "sc.scan(x)", color: red}
      - occupancy: {name: map, grid: "BinaryOccupancyGrid(walls, cellsize=0.5)", height: 0.3}
      - path: {name: route, points: pts, color: green}
      - ellipse: {name: unc, position: "x[:2]", covariance: P, scale: 2, confidence: 0.5}
      - particles: {name: cloud, points: pts, color: orange}
"""


def test_the_3d_kinds_put_the_vehicle_scan_grid_path_ellipse_and_particles_on_the_plane(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from ejsgen.cli import build
    from ejsrl.app import load_app
    from ejsrl.mobile import BinaryOccupancyGrid, LaserScanner

    spec = tmp_path / "scene.ejs.yaml"
    spec.write_text(SCENE)
    app = load_app(build(spec, tmp_path / "app"))
    app.play()
    for _ in range(5):
        app.frame()
    assert app.error is None
    w, x = app.scene.world, np.array(app.model.x)
    car = w.nodes["car"]
    T = car.T_world()
    np.testing.assert_allclose(T[:2, 3], x[:2], atol=1e-12)
    np.testing.assert_allclose(T[:2, 0], [math.cos(x[2]), math.sin(x[2])], atol=1e-12)
    (part,) = car.parts()  # a prism 0.4 m high over the 1.2 m triangle, its nose 0.72 m ahead
    assert part.vertices[:, 2].max() == pytest.approx(0.4) and part.vertices[:, 0].max() == pytest.approx(0.72)
    scan = w.nodes["scan"].props["points"]
    r = LaserScanner(BinaryOccupancyGrid(np.eye(6), cellsize=0.5), n=5, fov=math.pi, max_range=3.0).scan(x)
    a = x[2] + np.linspace(-math.pi / 2, math.pi / 2, 5)
    np.testing.assert_allclose(scan[0::2, :2], np.tile(x[:2], (5, 1)), atol=1e-12)
    np.testing.assert_allclose(scan[1::2, :2], x[:2] + r[:, None] * np.column_stack((np.cos(a), np.sin(a))), atol=1e-12)
    (blocks,) = w.nodes["map"].parts()  # one block 0.3 m high per occupied cell, centred on it
    assert len(blocks.vertices) == 8 * 6
    centres = blocks.vertices.reshape(6, 8, 3).mean(axis=1)
    np.testing.assert_allclose(centres, [[0.5 * k, 0.5 * k, 0.15] for k in range(6)], atol=1e-12)
    np.testing.assert_allclose(w.nodes["route"].props["points"], [[0, 0, 0.02], [1, 1, 0.02]])
    np.testing.assert_allclose(w.nodes["cloud"].props["points"], [[0, 0, 0.02], [1, 1, 0.02]])
    e = w.nodes["unc"].props["points"][:, :2] - x[:2]
    m2 = np.einsum("ij,jk,ik->i", e, np.linalg.inv(4 * np.diag([0.2, 0.1])), e)
    np.testing.assert_allclose(m2, -2 * math.log(0.5), rtol=1e-9)


def test_the_browser_mirror_draws_the_3d_kinds_and_moves_the_vehicle_by_its_pose(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """viser's scene (what the browser is sent): a mesh for the vehicle and the grid, lines
    for the scan, path and ellipse, a point cloud; a new pose moves the vehicle's frame
    and sends no new mesh."""
    from ejsgen.cli import build
    from ejsrl.app import load_app
    from ejsrl.view._scene_mirror import SceneMirror
    from ejsrl.view.viser_view import make_server

    spec = tmp_path / "scene.ejs.yaml"
    spec.write_text(SCENE)
    app = load_app(build(spec, tmp_path / "app"))
    server, _url = make_server("127.0.0.1", 0)
    try:
        mirror = SceneMirror(server.scene)
        app.play()
        app.frame()
        mirror.sync(app.scene.world)
        kinds = {n: type(mirror._nodes[n].geoms[0]).__name__ for n in ("car", "scan", "map", "route", "unc", "cloud")}
        assert kinds["cloud"] == "PointCloudHandle" and "Mesh" in kinds["car"] and "Mesh" in kinds["map"], kinds
        assert all("Line" in kinds[n] or "Spline" in kinds[n] for n in ("scan", "route", "unc")), kinds
        created = mirror.counters["create"]
        app.frame()
        mirror.sync(app.scene.world)
        x = np.array(app.model.x)
        assert mirror._nodes["car"].frame.position == pytest.approx((x[0], x[1], 0.0))
        assert mirror.counters["create"] == created and mirror.counters["geometry"] == 0
    finally:
        server.stop()


def test_the_3d_lattice_lab_drives_its_plan_to_the_goal_pose_among_the_shelves(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """examples/mobile_lattice_3d: the plan's cost is its moves' costs (1 a straight metre,
    turn_cost a quarter turn) and it ends on the goal pose; the car, driven by pure pursuit
    along the arcs, ends there too; the scene holds a block per shelf cell, the car at its
    pose and one ray per beam."""
    from ejsgen.cli import build
    from ejsrl.app import load_app

    app = load_app(build(ROOT / "examples" / "mobile_lattice_3d.ejs.yaml", tmp_path / "app"))
    m = app.model
    moves = m.moves
    assert m.cost == pytest.approx(moves.count("S") + m.turn_cost * (moves.count("L") + moves.count("R")))
    np.testing.assert_allclose(np.asarray(m.plan)[-1], [m.gx, m.gy, math.radians(m.gh)], atol=1e-9)
    app.play()
    for _ in range(int(30 / 0.05)):  # 30 s of driving (display frames step the model as the app's loop does)
        app.frame()
        if math.hypot(m.pose[0] - m.gx, m.pose[1] - m.gy) < 0.12:
            break
    assert app.error is None
    assert math.hypot(m.pose[0] - m.gx, m.pose[1] - m.gy) < 0.12
    assert abs(math.remainder(m.pose[2] - math.radians(m.gh), 2 * math.pi)) < 0.15
    w = app.scene.world
    (blocks,) = w.nodes["shelves"].parts()
    assert len(blocks.vertices) == 8 * int(np.count_nonzero(m.shelves))
    np.testing.assert_allclose(w.nodes["car"].T_world()[:2, 3], np.asarray(m.pose)[:2], atol=1e-12)
    assert w.nodes["scan"].props["points"].shape == (62, 3)
