"""The PRM-and-laser lab in a real browser (issue #27's mobile kinds): after driving, the
pixels where the model's vehicle is are the vehicle's fill, the laser's returns (where an
independent LaserScanner's beams stop on the floor plan) are red dots, the map's walls the
laser has seen are black and the cells it has not seen grey; dragging the goal gives a new
PRM path ending there. Its gallery picture is taken here."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest

from testkit.browser import hide_notifications, open_lab_tab, panel_point, save_shot, serving_example, tab_lab, wait_until


@pytest.fixture(scope="module")
def prm_lab():
    with serving_example("mobile_prm_laser") as served:
        yield served


def _far_from_segments(p: np.ndarray, A: np.ndarray, B: np.ndarray, d: float) -> bool:
    """Is the point p (2,) farther than d from every segment A[i]-B[i] (m)?"""
    AB = B - A
    t = np.clip(np.einsum("ij,ij->i", p - A, AB) / np.maximum(np.einsum("ij,ij->i", AB, AB), 1e-12), 0.0, 1.0)
    return bool(np.hypot(*(A + t[:, None] * AB - p).T).min() > d)


def _pixels(page) -> np.ndarray:  # type: ignore[no-untyped-def]
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("RGB")).astype(int)


@pytest.mark.browser
def test_prm_laser_lab_draws_the_robot_its_scan_and_the_map_where_the_model_says(prm_lab, browser_context):
    from ejsrl.mobile import BinaryOccupancyGrid, LaserScanner

    app, url = prm_lab
    page = open_lab_tab(browser_context, url)
    try:
        hide_notifications(page)
        lab = tab_lab(app, page)
        m = lab.model
        box = page.locator("canvas.ejs2d-c").first.bounding_box()

        def css(x: float, y: float) -> tuple[float, float]:
            return panel_point(page, x, y, box)

        # drag the goal to the middle room's top: a new path ends there
        page.mouse.move(*css(m.gx, m.gy))
        page.mouse.down()
        page.mouse.move(*css(15.0, 17.0), steps=6)
        page.mouse.up()
        wait_until(lambda: abs(m.gx - 15.0) < 0.1 and abs(m.gy - 17.0) < 0.1 and len(m.path) >= 2
                   and np.hypot(*(np.asarray(m.path)[-1] - [m.gx, m.gy])) < 1e-9, what="a new path to the dragged goal")
        page.keyboard.press("Space")
        wait_until(lambda: lab.is_playing(), what="Space: play")
        wait_until(lambda: m.t > 6.0, timeout=120, what="6 s of driving")
        page.keyboard.press("Space")
        wait_until(lambda: not lab.is_playing(), what="Space: pause")
        pose, known = np.array(m.pose), np.array(m.known)
        wait_until(lambda: page.evaluate("Object.values(window.__ejs2d.panels)[0].text").count(f"{m.seen} of 2400") > 0,
                   what="the paused frame drawn")
        shot = _pixels(page)

        def rgb(x: float, y: float) -> np.ndarray:
            u, v = css(x, y)
            return shot[int(round(v)), int(round(u))]

        # the vehicle: its fill (#a5d8ff) at the centroid of its triangle, ahead of the pose
        c = pose[:2] + 0.2 / 3 * 1.2 * np.array([math.cos(pose[2]), math.sin(pose[2])])
        r, g, b = rgb(*c)
        assert b > 220 and r < 200 and abs(g - 216) < 40, (r, g, b)
        # the laser: a red dot where each beam stops on a wall (an independent scanner)
        scanner = LaserScanner(BinaryOccupancyGrid(np.asarray(m.walls), cellsize=0.5), n=61, fov=math.pi, max_range=8.0)
        ranges = scanner.scan(pose)
        a = pose[2] + scanner.angles
        hits = [(pose[0] + d * math.cos(t), pose[1] + d * math.sin(t)) for d, t in zip(ranges, a) if d < 8.0]
        assert len(hits) >= 5
        red = [rgb(*h) for h in hits]
        reddish = sum(1 for r, g, b in red if r > 180 and g < 140 and b < 140)
        assert reddish >= 0.8 * len(hits), red
        # the map: cells the laser has not seen grey (0.5: halfway from white to black), walls
        # it has seen black (a few may lie under the roadmap's lines: most of them)
        rows, cols = np.nonzero(known == 0.5)
        centres = 0.5 * np.column_stack((cols, rows))
        A, B = np.asarray(m.roadmap_a), np.asarray(m.roadmap_b)
        clear = np.array([_far_from_segments(p, A, B, 0.35) for p in centres])  # not under a roadmap line
        pick = np.flatnonzero(clear)[np.linspace(0, clear.sum() - 1, 20).astype(int)]
        grey = [rgb(*centres[k]) for k in pick]
        assert sum(1 for p in grey if np.abs(p - 128).max() < 20) >= 18, grey
        rows, cols = np.nonzero(known == 1.0)
        black = [rgb(0.5 * c, 0.5 * r) for r, c in zip(rows, cols)]
        assert len(black) >= 10 and sum(1 for p in black if p.max() < 60) >= 0.7 * len(black), black[:10]
        save_shot(page, "mobile_prm_laser")
    finally:
        page.close()


@pytest.fixture(scope="module")
def lattice_lab():
    with serving_example("mobile_lattice_3d") as served:
        yield served


@pytest.mark.browser
def test_the_3d_lattice_lab_shows_the_car_driving_its_plan_with_its_laser(lattice_lab, browser_context):
    """The 3D scene in the browser: the car (blue) moves across the picture as it drives the
    plan, the laser's rays (red) are drawn, the car ends on the goal. Its gallery picture."""
    from PIL import Image

    app, url = lattice_lab
    page = open_lab_tab(browser_context, url, ready="canvas", state="attached")
    try:
        page.get_by_role("button", name="Restore view").first.wait_for()
        hide_notifications(page)
        lab = tab_lab(app, page)
        m = lab.model

        def blue_and_red() -> tuple[np.ndarray | None, int]:
            img = np.asarray(Image.open(io.BytesIO(page.locator("canvas").first.screenshot())).convert("RGB")).astype(int)
            r, g, b = img[..., 0], img[..., 1], img[..., 2]
            ys, xs = np.nonzero((b > r + 60) & (b > g + 20))  # the car, #1c7ed6 shaded
            red = int(np.count_nonzero((r > g + 80) & (r > b + 80)))  # the laser, #f03e3e
            return (np.array([xs.mean(), ys.mean()]) if len(xs) > 20 else None), red

        wait_until(lambda: blue_and_red()[0] is not None and blue_and_red()[1] > 50, timeout=60, what="the car and its laser drawn")
        start, _ = blue_and_red()
        page.get_by_role("button", name="Play").first.click()
        wait_until(lambda: m.t > 8.0, timeout=120, what="8 s of driving")
        save_shot(page, "mobile_lattice_3d")
        moved, red = blue_and_red()
        assert moved is not None and red > 50
        assert np.hypot(*(moved - start)) > 40  # the car crossed the picture (pixels)
        wait_until(lambda: math.hypot(m.pose[0] - m.gx, m.pose[1] - m.gy) < 0.12, timeout=120, what="the car on the goal")
    finally:
        page.close()
