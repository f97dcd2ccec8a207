"""Lines whose shape changes are drawn in the same browser frame as the bodies they join (a real
Chromium, screenshots while playing).

A zigzag spring drawn as a 3D ``line`` stretches and shrinks between a wall and an oscillating
plate: its end must stay on the plate's edge. A ``trail`` follows a ball on an ellipse (not a rigid motion of the trail, as a circle's would be): its head
must stay on the ball. viser's client draws a node's pose in the frame that receives it but a
line's new points a browser frame later; sent as points (before the fix) the spring's end and the
trail's head were off their bodies by up to 25-30 px here in one screenshot in four or so.

Both lines are drawn just in front of their bodies, along the lines of sight from the camera
through the bodies' own points, so the spring's end and the trail's head land on the very pixels
of the plate's edge and of the ball's centre, whatever the perspective.
"""

from __future__ import annotations

import numpy as np
import pytest

from testkit.browser import ARTIFACTS, canvas_pixels, hide_notifications, serving, wait_until

SLOW = 120_000

LAB = """\
ejs: 1
title: Spring and trail
model:
  variables:
    t: 0.0
    dt: 0.01
    x: 0.3
    v: 0.0
    phi: 0.0
  evolution:
    - ode: {equations: {x: v, v: -90*x, phi: 7.0}}
  custom: |
    def seen(p):
        # a point 2 % of the way from p towards the camera at (0, -3, 0): drawn over p, on p's pixel
        c = np.array([0.0, -3.0, 0.0])
        return c + (np.asarray(p, dtype=float) - c)*0.98

    def spring(a, b):
        # a zigzag of 8 coils from a to b along x, with straight leads: 20 points
        a = np.asarray(a, dtype=float)
        b = np.asarray(b, dtype=float)
        lead = 0.08
        s = np.linspace(0.0, 1.0, 17)
        pts = np.outer(1.0 - s, a + [lead, 0, 0]) + np.outer(s, b - [lead, 0, 0])
        pts[1:-1:2, 2] += 0.06
        pts[2:-1:2, 2] -= 0.06
        return seen(np.vstack([a, pts, b]))
view:
  - scene:
      - view: {position: [0, -3, 0], target: [0, 0, 0], fov: 50}
      - box: {name: wall, position: [-1.25, 0, -0.45], size: [0.04, 0.02, 0.4], color: "#808080"}
      - box: {name: plate, position: [x, 0, -0.45], size: [0.2, 0.02, 0.2], color: "#ff0000"}
      - line: {name: spring, points: "spring([-1.23, 0, -0.45], [x - 0.1, 0, -0.45])", color: "#0000ff", width: 2}
      - sphere: {name: ball, position: ["0.45*cos(phi)", 0, "0.45 + 0.25*sin(phi)"], radius: 0.04, color: "#00c000"}
      - trail: {name: path, point: "seen([0.45*cos(phi), 0, 0.45 + 0.25*sin(phi)])", max_points: 10, color: "#ff00ff", width: 3}
simulation: {fps: 30, autoplay: true}
"""


def build_lab(tmp_path):
    from ejsgen.cli import build

    spec = tmp_path / "line_sync.ejs.yaml"
    spec.write_text(LAB)
    return build(spec, tmp_path / "app")


def spring_gap(img: np.ndarray) -> float | None:
    """Pixels between the spring's end (its rightmost blue pixel, on the plate's middle row) and
    the plate's left edge (its leftmost red pixel), in the lower half of the picture; None if
    either is not in the picture."""
    h = img.shape[0]
    low = img[h // 2 :]
    r, g, b = low[..., 0], low[..., 1], low[..., 2]
    red = (r > g + 60) & (r > b + 60)
    blue = (b > r + 60) & (b > g + 60)
    if red.sum() < 50 or blue.sum() < 50:
        return None
    ys, xs = np.nonzero(red)
    middle = (ys.min() + ys.max()) // 2
    band = blue[max(0, middle - 3) : middle + 4]
    bys, bxs = np.nonzero(band)
    if len(bxs) == 0:
        return None
    # the line's end is half its width beyond its last point (a 2 px line: 1 px)
    return abs(float(bxs.max()) - 1.0 - float(xs.min()))


def trail_gap(img: np.ndarray) -> float | None:
    """Pixels from the ball's centre (its green disc's box, upper half of the picture) to the
    nearest pixel of the trail (magenta) drawn over it; None if either is not in the picture."""
    h = img.shape[0]
    up = img[: h // 2]
    r, g, b = up[..., 0], up[..., 1], up[..., 2]
    green = (g > r + 60) & (g > b + 60)
    magenta = (r > g + 80) & (b > g + 80)
    if green.sum() < 30 or magenta.sum() < 20:
        return None
    ys, xs = np.nonzero(green)
    if xs.min() < 2 or ys.min() < 2 or xs.max() > up.shape[1] - 3:
        return None
    centre = np.array([(xs.min() + xs.max()) / 2.0, (ys.min() + ys.max()) / 2.0])
    mys, mxs = np.nonzero(magenta)
    return float(np.min(np.hypot(mxs - centre[0], mys - centre[1])))


@pytest.mark.browser
def test_a_spring_and_a_trail_stay_on_their_bodies_while_playing(tmp_path, page):
    with serving(build_lab(tmp_path)) as (app, url):
        page.set_default_timeout(SLOW)
        page.goto(url)
        page.wait_for_selector("canvas", state="attached", timeout=SLOW)
        hide_notifications(page)
        wait_until(lambda: app.model.t > 1.0, timeout=60, what="the plate to oscillate and the ball to go round")
        springs, trails, xs = [], [], []
        for _ in range(60):
            img = canvas_pixels(page)
            img[-120:, :120] = 255  # the axes gizmo in the bottom-left corner
            with app.lock:
                xs.append(app.model.x)
            s, tr = spring_gap(img), trail_gap(img)
            if s is not None:
                springs.append(s)
            if tr is not None:
                trails.append(tr)
        page.screenshot(path=str(ARTIFACTS / "line_sync_spring_trail.png"))
    assert max(xs) - min(xs) > 0.3, "the plate hardly moved"
    assert len(springs) >= 50 and len(trails) >= 50, (len(springs), len(trails))
    s, tr = np.array(springs), np.array(trails)
    print(f"spring end to plate: median {np.median(s):.2f} px, p90 {np.percentile(s, 90):.2f} px, max {s.max():.2f} px")
    print(f"trail head to ball: median {np.median(tr):.2f} px, p90 {np.percentile(tr, 90):.2f} px, max {tr.max():.2f} px")
    assert np.median(s) < 1.5 and s.max() < 3.0, np.round(s, 1)
    assert np.median(tr) < 1.5 and tr.max() < 3.0, np.round(tr, 1)
