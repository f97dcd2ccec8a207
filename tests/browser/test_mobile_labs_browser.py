"""The mobile-robot labs (issue #27) in a real browser: a car driven to the pose a student
drags and turns with the keys ends on that pose, drawn where the model is; EKF localisation
driven from the keyboard draws the filter's 95 % ellipse from the model's own covariance,
and its sensor switch works from the keyboard. Their gallery pictures are taken here."""

from __future__ import annotations

import base64
import json
import math

import numpy as np
import pytest

from testkit.browser import open_lab_tab, panel_point, serving_example, tab_lab, wait_until


@pytest.fixture(scope="module")
def car_lab():
    with serving_example("mobile_car_to_pose") as served:
        yield served


@pytest.fixture(scope="module")
def ekf_lab():
    with serving_example("mobile_ekf_localisation") as served:
        yield served


def polylines(page) -> list[np.ndarray]:  # type: ignore[no-untyped-def]
    """Every polyline/polygon of the panel's last frame, decoded from the page (float32)."""
    frame = json.loads(page.evaluate("Object.values(window.__ejs2d.panels)[0].text"))
    out = []

    def walk(node):  # type: ignore[no-untyped-def]
        if isinstance(node, dict):
            if node.get("t") == "polyline" and "xy" in node:
                out.append(np.frombuffer(base64.b64decode(node["xy"]), dtype="<f4").reshape(-1, 2).astype(float))
            for v in node.values():
                walk(v)
        elif isinstance(node, list):
            for v in node:
                walk(v)

    walk(frame)
    return out


def drawn(page, pts: np.ndarray, tol: float = 1e-4) -> bool:  # type: ignore[no-untyped-def]
    """Is a polyline with exactly these points (to float32) in the panel's frame?"""
    return any(p.shape[0] >= len(pts) and np.abs(p[:len(pts)] - pts).max() < tol for p in polylines(page))


@pytest.mark.browser
def test_the_car_drives_to_the_pose_dragged_and_turned_by_the_student(car_lab, browser_context):
    from ejsrl.mobile import vehicle_outline
    from testkit.browser import save_shot

    app, url = car_lab
    page = open_lab_tab(browser_context, url)
    try:
        lab = tab_lab(app, page)
        m = lab.model
        # drag the goal (green disc) from (5, 3) to (3, -4)
        page.mouse.move(*panel_point(page, m.gx, m.gy))
        page.mouse.down()
        page.mouse.move(*panel_point(page, 3.0, -4.0), steps=6)
        page.mouse.up()
        wait_until(lambda: abs(m.gx - 3.0) < 0.1 and abs(m.gy + 4.0) < 0.1, what="the goal dragged to (3, -4)")
        gx, gy = m.gx, m.gy
        # the panel has the keyboard since the drag: two turns of -15 degrees
        page.keyboard.press("ArrowRight")
        page.keyboard.press("ArrowRight")
        wait_until(lambda: m.goal_heading == 60.0, what="ArrowRight twice: the goal turned to 60 degrees")
        page.keyboard.press("Space")
        wait_until(lambda: lab.is_playing(), what="Space: play")
        wait_until(lambda: m.t > 4.0, timeout=60, what="4 s of driving")
        save_shot(page, "mobile_car_to_pose")  # on its way (the gallery's picture)
        wait_until(lambda: m.dist < 1e-3 and abs(m.herr) < 0.05, timeout=120, what="the car on the goal pose")
        assert math.hypot(m.x - gx, m.y - gy) < 1e-3
        assert abs((m.theta - math.radians(60.0) + math.pi) % (2 * math.pi) - math.pi) < 1e-3
        page.keyboard.press("Space")
        wait_until(lambda: not lab.is_playing(), what="Space: pause")
        # the car is drawn where the model is (its outline, as vehicle_outline gives it)
        car = np.vstack([vehicle_outline([m.x, m.y, m.theta], 1.6 * m.L)])
        wait_until(lambda: drawn(page, car, tol=1e-3), what="the car outline at the model's pose")
    finally:
        page.close()


@pytest.mark.browser
def test_ekf_lab_draws_its_covariance_ellipse_and_takes_the_keyboard(ekf_lab, browser_context):
    from ejsrl.mobile import ellipse_points
    from testkit.browser import save_shot

    app, url = ekf_lab
    page = open_lab_tab(browser_context, url)
    try:
        lab = tab_lab(app, page)
        m = lab.model
        page.mouse.click(*panel_point(page, 10.5, -10.5))  # an empty corner: the panel takes the keyboard
        page.keyboard.press("ArrowUp")
        wait_until(lambda: m.speed == 1.25, what="ArrowUp: faster")
        page.keyboard.press("ArrowLeft")
        wait_until(lambda: abs(m.steer - 0.2) < 1e-12, what="ArrowLeft: steer left")
        page.keyboard.press("Space")
        wait_until(lambda: m.t > 15.0, timeout=120, what="15 s of driving")
        page.keyboard.press("Space")
        wait_until(lambda: not lab.is_playing(), what="Space: pause")
        assert m.err < 0.3 and m.sigma < 0.2
        ell = ellipse_points(m.magnification**2 * m.P[:2, :2], m.xe[:2], confidence=0.95)
        wait_until(lambda: drawn(page, ell), what="the 95 % ellipse of the model's P on the panel")
        save_shot(page, "mobile_ekf_localisation")
        page.keyboard.press("s")
        wait_until(lambda: not m.sensor_on, what="S: the sensor off")
        t0, s0 = m.t, m.sigma
        page.keyboard.press("Space")
        wait_until(lambda: m.t > t0 + 10.0, timeout=120, what="10 s of dead reckoning")
        page.keyboard.press("Space")
        assert m.sigma > 2 * s0  # without the sensor the uncertainty grows
    finally:
        page.close()


@pytest.fixture(scope="module")
def dstar_lab():
    with serving_example("mobile_dstar_replanning") as served:
        yield served


@pytest.mark.browser
def test_dstar_lab_repairs_the_path_when_an_obstacle_is_dragged_into_it(dstar_lab, browser_context):
    import sys

    from testkit import ROOT
    from testkit.browser import save_shot

    sys.path.insert(0, str(ROOT / "tests" / "mobile"))
    from test_planners import grid_dijkstra

    app, url = dstar_lab
    page = open_lab_tab(browser_context, url)
    try:
        lab = tab_lab(app, page)
        m = lab.model
        before = m.path.copy()
        # drag the right-hand block from (24, 14) to (23, 10), across the path
        page.mouse.move(*panel_point(page, 24.0, 14.0))
        page.mouse.down()
        page.mouse.move(*panel_point(page, 23.0, 10.0), steps=8)
        page.mouse.up()
        wait_until(lambda: abs(m.blocks[2][0] - 23.0) < 0.3 and abs(m.blocks[2][1] - 10.0) < 0.3,
                   what="the block dragged to (23, 10)")
        wait_until(lambda: "repaired" in m.status, what=f"the repaired path (status: {m.status!r})")

        def consistent() -> bool:  # the last drag event handled: the path fits the grid D* has
            with lab.lock:
                grid = m.planner.occgrid.grid.copy()
                cells = np.round(m.path).astype(int)
                return len(cells) > 1 and not grid[cells[:, 1], cells[:, 0]].any() and \
                    m.cost == pytest.approx(grid_dijkstra(grid, (27, 17))[2, 2], abs=1e-9)

        # the repaired path: clear of the grid D* now has, as short as scipy's Dijkstra finds
        wait_until(consistent, what="a repaired path clear of the new obstacles, of the shortest length")
        assert not np.array_equal(before, m.path) and m.cost > 41.22  # the block was in its way
        # the lab compares the repair with a plan from scratch on the same map
        with lab.lock:
            from ejsrl.mobile import BinaryOccupancyGrid, DstarPlanner

            fresh = DstarPlanner(BinaryOccupancyGrid(m.planner.occgrid.grid.copy()))
            fresh.plan((27, 17))
            fresh.query((2, 2))
            assert m.scratch == fresh.expanded and f"from scratch: {fresh.expanded}" in m.status
        wait_until(lambda: drawn(page, m.path, tol=1e-4), what="the new path on the panel")
        save_shot(page, "mobile_dstar_replanning")
    finally:
        page.close()


@pytest.fixture(scope="module")
def slam_lab():
    with serving_example("mobile_ekf_slam") as served:
        yield served


@pytest.mark.browser
def test_slam_lab_draws_the_map_it_builds_with_its_ellipses(slam_lab, browser_context):
    from ejsrl.mobile import ellipse_points
    from testkit.browser import save_shot

    app, url = slam_lab
    page = open_lab_tab(browser_context, url)
    try:
        lab = tab_lab(app, page)
        m = lab.model
        page.mouse.click(*panel_point(page, 10.5, 10.5))  # an empty corner: the panel takes the keyboard
        page.keyboard.press("Space")
        wait_until(lambda: m.nmapped >= 12, timeout=120, what="a dozen landmarks mapped")
        page.keyboard.press("Space")
        wait_until(lambda: not lab.is_playing(), what="Space: pause")
        with lab.lock:
            first = min(m.ekf.landmarks, key=lambda i: m.ekf.landmarks[i][0])
            ring = ellipse_points(m.magnification**2 * m.ekf.landmark_P(first), m.mapped[0], confidence=0.95, n=32)
        wait_until(lambda: drawn(page, ring), what="the first landmark's 95 % ellipse on the panel")
        save_shot(page, "mobile_ekf_slam")
    finally:
        page.close()


@pytest.fixture(scope="module")
def pf_lab():
    with serving_example("mobile_particle_filter") as served:
        yield served


def marker_sets(page) -> list[np.ndarray]:  # type: ignore[no-untyped-def]
    """Every point set (markers) of the panel's last frame, decoded (float32)."""
    frame = json.loads(page.evaluate("Object.values(window.__ejs2d.panels)[0].text"))
    out = []

    def walk(node):  # type: ignore[no-untyped-def]
        if isinstance(node, dict):
            if node.get("t") == "markers" and "xy" in node:
                out.append(np.frombuffer(base64.b64decode(node["xy"]), dtype="<f4").reshape(-1, 2).astype(float))
            for v in node.values():
                walk(v)
        elif isinstance(node, list):
            for v in node:
                walk(v)

    walk(frame)
    return out


@pytest.mark.browser
def test_particle_lab_particles_gather_on_the_car_and_scatter_on_the_button(pf_lab, browser_context):
    from testkit.browser import save_shot

    app, url = pf_lab
    page = open_lab_tab(browser_context, url)
    try:
        lab = tab_lab(app, page)
        m = lab.model

        def particles_drawn() -> bool:
            with lab.lock:
                mine = m.particles.copy()
            return any(s.shape == mine.shape and np.abs(s - mine).max() < 1e-4 for s in marker_sets(page))

        assert m.spread > 4.0
        page.mouse.click(*panel_point(page, 10.5, 10.5))
        page.keyboard.press("Space")
        wait_until(lambda: m.t > 0.6, timeout=120, what="0.6 s of driving")
        save_shot(page, "mobile_particle_filter")  # the particles gathering (the gallery's picture)
        wait_until(lambda: m.t > 8.0, timeout=120, what="8 s of driving")
        page.keyboard.press("Space")
        wait_until(lambda: not lab.is_playing(), what="Space: pause")
        assert m.spread < 0.5 and m.err < 0.3
        wait_until(particles_drawn, what="the particles drawn where the filter has them")
        page.get_by_role("button", name="Scatter the particles").click()
        wait_until(lambda: m.spread > 4.0, what="Scatter: the particles over the whole map again")
        wait_until(particles_drawn, what="the scattered particles drawn")
    finally:
        page.close()
