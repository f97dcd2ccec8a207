"""The drawing element's binding without a browser: frames that put each element where the
model says, drags that write the bound variables within their constraint and run on_drag, keys
that run their actions, traces, sets and errors."""

from __future__ import annotations

import base64
from pathlib import Path

import numpy as np
import pytest

from ejsrl.view._drawing import DrawingBinding, nice_ticks, spring_points
from testkit import ROOT

from test_panel2d import FakeGui

PROJECTILE = ROOT / "examples" / "projectile_2d.ejs.yaml"


def built(tmp_path: Path, spec: Path | str):
    from ejsgen.cli import build
    from ejsrl.app import load_app
    from ejsrl.view.elements2d import Drawing

    if isinstance(spec, str):
        path = tmp_path / "lab.ejs.yaml"
        path.write_text(spec)
        spec = path
    app = load_app(build(spec, tmp_path / "app"))
    drawing = next(el for el in app.view if isinstance(el, Drawing))
    return app, DrawingBinding(FakeGui(), drawing, app, key="d")


def xy(item) -> np.ndarray:
    width = 4 if item["t"] in ("segments", "arrows", "rects") else 2
    return np.frombuffer(base64.b64decode(item["xy"]), dtype="<f4").reshape(-1, width).astype(float)


def item(binding, t: str, ident: str | None = None, n: int = 0):
    binding.refresh()
    items = [it for it in binding.frame["items"] if it["t"] == t and (ident is None or it.get("id") == ident)]
    return items[n]


@pytest.fixture
def projectile(tmp_path):
    return built(tmp_path, PROJECTILE)


def test_the_frame_puts_each_element_where_the_model_says(projectile) -> None:
    app, b = projectile
    m = app.model
    app.play()
    for _ in range(20):
        app.frame()
        b.refresh()  # the view refreshes every display frame
    f = b.frame
    assert f["bounds"] == [-1.0, 21.0, -1.0, 11.0] and f["aspect"] == "equal"
    ball = [it for it in f["items"] if it["t"] == "circles" and it["fill"] == "crimson"][0]
    assert np.allclose(xy(ball), [[m.x, m.y]], atol=1e-5) and ball["r"] == 0.2
    vel = [it for it in f["items"] if it["t"] == "arrows" and it["stroke"] == "royalblue"][0]
    assert np.allclose(xy(vel), [[m.x, m.y, 0.25 * m.vx, 0.25 * m.vy]], atol=1e-5)
    targets = [it for it in f["items"] if it.get("id") is None and it["t"] == "markers"][0]
    assert np.allclose(xy(targets), [[10, 0], [14, 0], [18, 0]])  # a set: one item, N rows
    trace = [it for it in f["items"] if it["t"] == "polyline" and it["stroke"] == "#868e96"][0]
    pts = xy(trace)
    assert len(pts) >= 20 and np.allclose(pts[-1], [m.x, m.y], atol=1e-5)
    # the analytic flight: y = y0 + v sin(a) t - g t^2 / 2 at the trace's last point
    a = np.radians(m.angle)
    assert abs(m.y - (m.y0 + m.v0 * np.sin(a) * m.t - 0.5 * m.g * m.t**2)) < 1e-9
    text = [it for it in f["items"] if it["t"] == "text"][0]
    assert text["text"] == f"{m.y:.1f} m"
    assert f["title"] == f"range so far: {m.x - m.x0:.2f} m   hits: 0"
    assert [t[0] for t in f["axes"]["x"]["ticks"]][:1] and f["axes"]["grid"] is True
    app.reset()
    b.clear()
    assert len(xy(item(b, "polyline", n=2))) == 1  # the trace starts again after a reset


def test_a_drag_is_clamped_to_its_region_and_runs_on_drag(projectile) -> None:
    app, b = projectile
    m = app.model
    assert b.drag("launcher", "start", 1.0, 0.5)
    assert b.drag("launcher", "move", 25.0, -3.0)  # right of and below the region [0, 10, 0, 8]
    assert (m.x0, m.y0) == (10.0, 0.0)
    assert (m.x, m.y) == (10.0, 0.0)  # on_drag: initialize(): the ball starts from the launcher
    b.drag("launcher", "release", 4.0, 9.0)
    assert (m.x0, m.y0) == (4.0, 8.0)
    assert np.allclose(xy(item(b, "circles", "launcher")), [[4.0, 8.0]])
    # the fixed relations ran: the launch arrow's tip moved with the launcher
    assert abs(m.tip_x - (4.0 + 0.25 * m.v0 * np.cos(np.radians(m.angle)))) < 1e-12


def test_dragging_the_arrow_tip_sets_speed_and_angle(projectile) -> None:
    app, b = projectile
    m = app.model
    launch = item(b, "arrows", "launch")
    assert launch["handle"] == "end" and launch["drag"] == "xy"
    b.drag("launch", "move", m.x0 + 0.25 * 10.0, m.y0 + 0.25 * 10.0)  # 10*sqrt(2) m/s at 45 degrees
    assert abs(m.v0 - 10.0 * np.sqrt(2)) < 1e-9 and abs(m.angle - 45.0) < 1e-9
    b.drag("launch", "move", m.x0 - 3.0, m.y0 - 1.0)  # backwards and down: the angle stays in [0, 90]
    assert m.angle == 90.0 or m.angle == 0.0
    assert not b.drag("ball", "move", 0.0, 0.0)  # not draggable: nothing happens
    assert not b.drag("nobody", "move", 0.0, 0.0)


def test_keys_run_their_actions(projectile) -> None:
    app, b = projectile
    m = app.model
    angle = m.angle
    b.on_event({"k": "key", "key": "ArrowUp", "phase": "down"})
    assert m.angle == angle + 1.0
    b.on_event({"k": "key", "key": "ArrowUp", "phase": "up"})  # a release does nothing
    assert m.angle == angle + 1.0
    assert not app.is_playing()
    b.on_event({"k": "key", "key": " ", "phase": "down"})  # Space
    assert app.is_playing()
    assert not b.key("q")


CURVE = """ejs: 1
title: C
model:
  variables:
    x: 1.0
    y: 0.0
    P: [[0.0, 0.0], [1.0, 1.0], [2.0, 0.5]]
    moves: 0
    released: 0
  custom: |
    def on_circle(px, py):
        a = atan2(py, px)
        return [2*cos(a), 2*sin(a)]
view:
  - drawing:
      x_range: [-3, 3]
      y_range: [-3, 3]
      children:
        - particle: {name: bead, position: [x, y], drag: {bind: [x, y], along: curve, curve: on_circle,
                     on_drag: moves = moves + 1, on_release: released = released + 1}}
        - point: {name: cloud, position: P, drag: {bind: P}}
        - segment: {name: s, start: [0, 0], end: [x, y], drag: {bind: y, along: y, handle: end}}
        - particle: {name: bad, position: "np.zeros((2, 5))"}
"""
PARABOLA = """        - point: {name: para, position: [x, y], drag: {bind: [x, y], along: curve, curve: "lambda px, py: [px, 0.5*px**2]"}}
"""


def test_a_drag_on_a_curve_a_set_row_and_along_y(tmp_path) -> None:
    app, b = built(tmp_path, CURVE.replace('        - particle: {name: bad, position: "np.zeros((2, 5))"}\n', ""))
    m = app.model
    b.drag("bead", "move", 3.0, 4.0)
    assert np.allclose([m.x, m.y], [1.2, 1.6]) and m.moves == 1  # the circle of radius 2, towards (3, 4)
    b.drag("bead", "release", 0.0, -5.0)
    assert np.allclose([m.x, m.y], [0.0, -2.0]) and m.released == 1 and m.moves == 1
    b.on_event({"k": "drag", "id": "cloud", "phase": "move", "x": 5.0, "y": 6.0, "i": 1})
    assert np.array_equal(m.P, [[0.0, 0.0], [5.0, 6.0], [2.0, 0.5]])  # row 1 of the set, the others kept
    frame_items = {it.get("id"): it for it in (b.refresh() or b.frame)["items"]}
    assert frame_items["cloud"]["drag"] == "xy" and frame_items["s"]["drag"] == "y"
    x_before = m.x
    b.drag("s", "move", 9.0, 1.5)  # along y: x is not written
    assert (m.x, m.y) == (x_before, 1.5)
    b.on_event({"k": "drag", "id": "cloud", "phase": "move", "x": 1.0, "y": 1.0, "i": 7})  # no row 7
    assert app.error is not None and "row 7" in app.error.message


def test_a_set_of_the_wrong_shape_at_run_time_is_an_error_naming_the_element(tmp_path) -> None:
    app, b = built(tmp_path, CURVE)
    b.refresh()
    assert app.error is not None
    assert "N x 2" in app.error.message and "transpose" in app.error.message
    assert app.error.where.endswith(":23:21")  # the element's properties in the spec
    # the other elements are still drawn (the trial's panel went blank), the error written on it
    ids = [it.get("id") for it in b.frame["items"]]
    assert ids.count("bead") == 1 and ids.count("cloud") == 1 and len(b.frame["items"]) == 3
    assert "bad" in b.frame["error"] and "N x 2" in b.frame["error"] and b.frame["error"].startswith("\u26a0 ")
    assert b.panel.last_frame == b.frame


def test_an_error_after_good_frames_keeps_the_last_picture_with_the_error_on_it(tmp_path) -> None:
    spec = CURVE.replace('position: "np.zeros((2, 5))"', 'position: "np.zeros((2, 5)) if x > 1.5 else [x, y]"')
    app, b = built(tmp_path, spec)
    b.panel.max_rate = float("inf")  # every frame sent (no rate between these refreshes)
    b.refresh()
    good = b.panel.last_frame
    assert app.error is None and "error" not in good and len(good["items"]) == 4
    app.model.x = 2.0  # the set now has the wrong shape: that element is left out, the rest drawn
    b.refresh()
    assert app.error is not None and "N x 2" in app.error.message
    assert len(b.panel.last_frame["items"]) == 3 and "bad" in b.panel.last_frame["error"]
    app.model.y = 1.0  # while the error is shown nothing is evaluated: the picture stays
    b.refresh()
    assert b.panel.last_frame["items"] == b.frame["items"] and "error" in b.panel.last_frame
    app.reset()  # Reset clears the error: frames as before, without the note
    b.refresh()
    assert app.error is None and "error" not in b.panel.last_frame and len(b.panel.last_frame["items"]) == 4


def test_an_error_elsewhere_before_the_first_frame_still_draws_the_panel(tmp_path) -> None:
    spec = CURVE.replace('        - particle: {name: bad, position: "np.zeros((2, 5))"}\n', "").replace(
        "    released: 0\n", "    released: 0\n  init: |\n    released = 1/0\n")
    app, b = built(tmp_path, spec)
    assert app.error is not None and "division by zero" in app.error.message
    b.refresh()
    assert len(b.panel.last_frame["items"]) == 3 and "division by zero" in b.panel.last_frame["error"]


def test_spring_points_zig_zag_between_the_ends() -> None:
    a, b = np.array([0.0, 0.0]), np.array([4.0, 0.0])
    pts = spring_points(a, b, coils=5, radius=0.2)
    assert len(pts) == 2 * 5 + 4
    assert np.array_equal(pts[0], a) and np.array_equal(pts[-1], b)
    mids = pts[2:-2]
    assert np.allclose(np.abs(mids[:, 1]), 0.2) and np.all(np.sign(mids[:-1, 1]) != np.sign(mids[1:, 1]))
    assert np.all(np.diff(mids[:, 0]) > 0) and mids[0, 0] > 0.4 and mids[-1, 0] < 3.6
    # turned by 90 degrees, the spring turns with it
    turned = spring_points(a, np.array([0.0, 4.0]), coils=5, radius=0.2)
    assert np.allclose(turned[:, ::-1] * [1, -1], pts * [1, 1]) or np.allclose(np.abs(turned[2:-2, 0]), 0.2)


def test_nice_ticks() -> None:
    assert nice_ticks(-1, 21) == [0, 5, 10, 15, 20]
    assert nice_ticks(0, 1) == pytest.approx([0, 0.2, 0.4, 0.6, 0.8, 1.0])
    assert nice_ticks(-0.003, 0.003) == pytest.approx([-0.003, -0.002, -0.001, 0, 0.001, 0.002, 0.003])
    assert nice_ticks(1, 1) == []


def test_the_projectile_lands_where_the_closed_form_says(projectile) -> None:
    app, _b = projectile
    m = app.model
    v, a, g, y0, x0 = m.v0, np.radians(m.angle), m.g, m.y0, m.x0
    app.play()
    for _ in range(2000):
        app.frame()
        if not app.is_playing():
            break
    assert not app.is_playing() and app.error is None  # the ground event stopped it
    t_land = (v * np.sin(a) + np.sqrt((v * np.sin(a)) ** 2 + 2 * g * y0)) / g
    assert abs(m.t - t_land) < 1e-5
    assert abs(m.x - (x0 + v * np.cos(a) * t_land)) < 1e-4
    assert m.hits == int(np.any(np.abs(m.targets[:, 0] - m.x) < 0.6))


PICTURE = """ejs: 1
title: I
assets: [dot.png]
model:
  variables:
    img: {expr: "np.zeros((4, 6, 3), dtype=np.uint8)"}
    show: true
    shade: 0.5
view:
  - drawing:
      x_range: [0, 10]
      y_range: [0, 10]
      axes: true
      children:
        - image: {source: img, position: [5, 5], size: [6, 4]}
        - image: {file: dot.png, position: [1, 1], size: [2, 2]}
        - particle: {position: [1, 1], visible: show, color: "[shade, 0, 1 - shade]"}
        - grid: {spacing: 2}
        - axes: {}
"""


def test_images_visibility_colours_grids_and_axes(tmp_path) -> None:
    import cv2

    dot = np.zeros((3, 3, 3), dtype=np.uint8)
    dot[1, 1] = (0, 0, 255)  # BGR: red in the middle
    cv2.imwrite(str(tmp_path / "dot.png"), dot)
    app, b = built(tmp_path, PICTURE)
    app.model.img[1, 2] = (10, 200, 30)
    b.refresh()
    images = [it for it in b.frame["items"] if it["t"] == "image"]
    assert (images[0]["x0"], images[0]["y0"], images[0]["x1"], images[0]["y1"]) == (2.0, 3.0, 8.0, 7.0)

    def decoded(src: str) -> np.ndarray:
        raw = base64.b64decode(src.removeprefix("data:image/png;base64,"))
        return cv2.cvtColor(cv2.imdecode(np.frombuffer(raw, np.uint8), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)

    assert np.array_equal(decoded(images[0]["src"]), app.model.img)  # the array's pixels, losslessly
    assert tuple(decoded(images[1]["src"])[1, 1]) == (255, 0, 0)  # the file, read relative to the app
    particle = [it for it in b.frame["items"] if it["t"] == "circles"][0]
    assert particle["fill"] == "rgb(128,0,128)"
    app.model.show = False
    b.refresh()
    assert not [it for it in b.frame["items"] if it["t"] == "circles"]
    grid = [it for it in b.frame["items"] if it["t"] == "segments"][0]
    rows = xy(grid)
    vertical = rows[rows[:, 0] == rows[:, 2]]
    assert set(np.round(vertical[:, 0], 9)) >= {0.0, 2.0, 4.0, 6.0, 8.0, 10.0}
    assert np.all(np.round(vertical[:, 0] / 2, 9) % 1 == 0)  # every spacing, nothing between
    axes = [it for it in b.frame["items"] if it["t"] == "arrows"][0]
    assert np.allclose(xy(axes), [[0, 0, 10, 0], [0, 0, 0, 10]])
    ticks = dict(b.frame["axes"]["x"]["ticks"])
    assert ticks[0] == "0" and ticks[10] == "10" and ticks[-2] == "\u22122"
    # a new picture is encoded again only when its pixels change
    src = images[0]["src"]
    b.refresh()
    assert [it for it in b.frame["items"] if it["t"] == "image"][0]["src"] is src


LIMITS = """ejs: 1
title: L
model:
  variables:
    x: {value: 0.0, min: -1.0, max: 1.0}
    n: {value: 0, min: 0, max: 5}
view:
  - drawing:
      x_range: [-10, 10]
      y_range: [-10, 10]
      children:
        - particle: {name: a, position: [x, 0], drag: {bind: x, along: x}}
        - particle: {name: b, position: [0, n], drag: {bind: [x, n]}}
"""


def test_a_drag_keeps_to_the_variables_declared_min_and_max_and_rounds_integers(tmp_path) -> None:
    app, b = built(tmp_path, LIMITS)
    m = app.model
    b.drag("a", "move", 7.5, 3.0)
    assert m.x == 1.0
    b.drag("b", "move", -4.0, 2.6)
    assert m.x == -1.0 and m.n == 3 and isinstance(m.n, int)
    b.drag("b", "move", 0.25, 99.0)
    assert m.x == 0.25 and m.n == 5


def test_a_trace_moves_its_last_point_while_time_stands_still(projectile) -> None:
    app, b = projectile
    b.refresh()
    b.drag("launcher", "move", 3.0, 2.0)  # paused at t = 0: the ball moves with the launcher
    b.drag("launcher", "move", 4.0, 3.0)
    trace = lambda: [it for it in (b.refresh() or b.frame)["items"] if it["t"] == "polyline"][2]  # noqa: E731
    assert np.allclose(xy(trace()), [[4.0, 3.0]])  # one point, where the ball is: no line from where it was
    app.play()
    app.frame()
    assert len(xy(trace())) == 2


def test_a_curve_given_as_a_lambda(tmp_path) -> None:
    spec = CURVE.replace('        - particle: {name: bad, position: "np.zeros((2, 5))"}\n', PARABOLA)
    app, b = built(tmp_path, spec)
    b.drag("para", "move", 1.5, -7.0)  # on the parabola y = x^2 / 2, under the pointer
    assert (app.model.x, app.model.y) == (1.5, 1.125)


RELAUNCH = """
ejs: 1
title: Relaunch
model:
  variables:
    t: 0.0
    dt: 0.01
    x0: 0.0
    x: 0.0
    y: 0.0
    vx: 1.0
    vy: 2.0
  evolution:
    - ode:
        equations: {x: vx, y: vy}
  custom: |
    def launch():
        t = 0.0
        x = x0
        y = 0.0
        CLEAR
view:
  - button: {label: Launch, action: "launch(); play()"}
  - drawing:
      x_range: [-1, 11]
      y_range: [-1, 11]
      children:
        - trace: {point: [x, y]}
        - trace: {name: other, point: [y, x]}
        - point: {name: launcher, position: [x0, 0], drag: {bind: x0, along: x}}
"""


def _relaunch(tmp_path, clear: str):
    tmp_path.mkdir(parents=True, exist_ok=True)
    app, b = built(tmp_path, RELAUNCH.replace("CLEAR", clear))
    b.refresh()                       # t = 0, paused: the trace is the start (0, 0)
    b.drag("launcher", "move", 5.0, 0.0)  # a new launch point; the ball has not moved
    app.run_action(next(el for el in app.view if getattr(el, "label", "") == "Launch"))
    app.frame()                       # playing: steps from the new point before the view sees it
    b.refresh()
    traces = [it for it in b.frame["items"] if it["t"] == "polyline"]
    return app, b, xy(traces[0]), xy(traces[1])


def test_clear_trace_starts_a_trace_again_when_time_does_not_go_back(tmp_path) -> None:
    # the relaunch of the trial: t already 0 and paused, the launch point moved, then launch and
    # play: without clear_trace() the trace runs from the old start (0, 0) to the new one (5, 0)
    _app, _b, pts, _ = _relaunch(tmp_path, "pass")
    assert np.allclose(pts[0], [0.0, 0.0]) and pts[-1][0] > 4.9  # the stray segment is there
    app, b, pts, other = _relaunch(tmp_path / "2", "clear_trace('trace1')")
    assert app.error is None
    assert pts.min(axis=0)[0] >= 5.0 - 1e-9 and np.allclose(pts[-1], [app.model.x, app.model.y], atol=1e-5)
    assert np.allclose(other[0], [0.0, 0.0])  # another trace is left alone
    app, b, pts, other = _relaunch(tmp_path / "3", "clear_trace()")  # every trace
    assert pts.min(axis=0)[0] >= 5.0 - 1e-9 and other.min(axis=0)[1] >= 5.0 - 1e-9


def test_clear_trace_of_a_name_no_trace_has_is_an_error_with_a_hint(tmp_path) -> None:
    app, b, _pts, _ = _relaunch(tmp_path, "clear_trace('trace')")
    assert app.error is not None and "clear_trace('trace')" in app.error.message
    assert "did you mean 'trace1'" in app.error.message


def test_reset_and_time_going_back_start_a_trace_again(tmp_path) -> None:
    app, b = built(tmp_path, RELAUNCH.replace("CLEAR", "pass"))
    b.refresh()
    app.play()
    for _ in range(5):
        app.frame()
        b.refresh()
    trace = lambda: xy([it for it in b.frame["items"] if it["t"] == "polyline"][0])  # noqa: E731
    assert len(trace()) == 6
    app.model.t = 0.0  # the independent variable goes back: a new trace from the point now
    app.model.x, app.model.y = 7.0, 7.0
    b.refresh()
    assert np.allclose(trace(), [[7.0, 7.0]])
    for _ in range(3):
        app.frame()
        b.refresh()
    app.reset()  # Reset: the views' on_reset, then the first frame shows the start alone
    b.clear()
    b.refresh()
    assert np.allclose(trace(), [[0.0, 0.0]])
