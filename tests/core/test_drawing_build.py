"""Mistakes in a drawing panel are build errors at their FILE:LINE:COL, with a hint where it helps;
a good one builds into app code that declares the panel."""

from __future__ import annotations

from pathlib import Path

import pytest

from ejsgen.cli import main

HEAD = """ejs: 1
title: D
model:
  variables:
    x: 0.0
    y: 0.0
    P: [[0.0, 0.0], [1.0, 1.0], [2.0, 0.5]]
    Q: [1.0, 2.0, 3.0]
    W: [[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]]
    n: 0
  custom: |
    def on_circle(px, py):
        a = atan2(py, px)
        return [cos(a), sin(a)]
view:
  - drawing:
"""


def _errors(tmp_path: Path, capsys: pytest.CaptureFixture[str], body: str) -> list[str]:
    spec = tmp_path / "d.ejs.yaml"
    spec.write_text(HEAD + body)
    assert main(["validate", str(spec)]) == 1
    return [line.removeprefix(f"{spec}:") for line in capsys.readouterr().err.splitlines() if line.startswith(str(spec))]


def test_an_unknown_2d_kind_or_property_is_named_with_a_suggestion(tmp_path, capsys) -> None:
    body = (
        "      children:\n"
        "        - partcle: {position: [x, y]}\n"
        "        - circle: {position: [x, y], radius: 1, colr: red}\n"
        "        - 5\n"
    )
    assert _errors(tmp_path, capsys, body) == [
        "18:11: error: unknown 2D element kind 'partcle'; did you mean 'particle'?",
        "19:49: error: unknown key 'colr'; did you mean 'color'?",
        "20:11: error: each 2D element is a one-key mapping 'kind: {properties}'; kinds: point, particle, circle, segment, "
        "arrow, spring, polygon, polyline, trace, text, image, axes, grid, vehicle, laser, occupancy, path, ellipse, particles",
    ]


def test_a_position_of_the_wrong_shape_is_refused(tmp_path, capsys) -> None:
    body = (
        "      children:\n"
        "        - point: {position: Q}\n"  # a 3-vector
        "        - particle: {position: W}\n"  # 2 x 3
        "        - particle: {position: [x, y, 0]}\n"
        "        - spring: {start: P, end: [1, 1]}\n"  # a spring is not a set
        "        - polygon: {points: [[0, 0], [1, 1, 2]]}\n"
    )
    assert _errors(tmp_path, capsys, body) == [
        "18:29: error: the position of point 'point1' must be [x, y] or an N x 2 array, but 'Q' has shape (3,)",
        "19:32: error: the position of particle 'particle1' must be [x, y] or an N x 2 array, but 'W' has shape (2, 3); "
        "a 2 x N array: transpose it with .T",
        "20:32: error: the position of particle 'particle2' needs 2 numbers, got 3",
        "21:27: error: the start of spring 'spring1' must be [x, y], but 'P' has shape (3, 2)",
        "22:38: error: the points of polygon 'polygon1': each point is [x, y], but row 2 has 3 numbers",
    ]


def test_drag_mistakes(tmp_path, capsys) -> None:
    body = (
        "      children:\n"
        "        - particle: {position: [x, y], drag: {bind: [x, z]}}\n"  # z is no variable
        "        - particle: {position: [x, y], drag: {bind: x}}\n"  # one variable, no along
        "        - particle: {position: [x, y], drag: {bind: [x, y], along: curve, curve: on_circl}}\n"
        "        - particle: {position: [x, y], drag: {bind: [x, y], along: region}}\n"
        "        - polyline: {points: P, drag: {bind: P}}\n"
        "        - particle: {position: [x, y], drag: {bind: [x, y], region: [1, 0, 0, 1]}}\n"
        "        - particle: {position: [x, y], drag: {bind: [x, y], along: curve, curve: 'x**2'}}\n"
        "        - particle: {position: [x, y], drag: {bind: [x, y], along: curve, curve: 'lambda px, py: [px, qq]'}}\n"
    )
    assert _errors(tmp_path, capsys, body) == [
        "18:57: error: unknown name 'z'",
        "19:53: error: one variable ('x') is one coordinate: say which with along: x or along: y; or bind both: bind: [x, y_variable]",
        "20:82: error: the curve 'on_circl' is not a function of custom code; did you mean 'on_circle'?",
        "21:68: error: along: region needs region: [xmin, xmax, ymin, ymax]",
        "22:39: error: a polyline cannot be dragged; draggable: point, particle, circle, segment, arrow, spring, text, image, vehicle",
        "23:69: error: a region is [xmin, xmax, ymin, ymax] with xmin < xmax and ymin < ymax",
        "24:82: error: a curve is the name of a custom function, or a lambda of the pointer's x and y, got 'x**2'; "
        "e.g. curve: 'lambda px, py: [px, 0.1*px**2]' (the parabola under the pointer)",
        "25:103: error: unknown name 'qq'",
    ]


def test_key_and_panel_mistakes(tmp_path, capsys) -> None:
    body = (
        "      x_range: [1, 0]\n"
        "      background: whte\n"
        "      keys:\n"
        "        ArowUp: n = n + 1\n"
        "        F1: n = 0\n"
        "      children:\n"
        "        - image: {position: [0, 0]}\n"
    )
    assert _errors(tmp_path, capsys, body) == [
        "17:16: error: x_range is [min, max] with min < max, got [1, 0]",
        "18:19: error: unknown colour 'whte'; did you mean 'white'?",
        "20:9: error: 'ArowUp' is not a key a panel can report; did you mean 'ArrowUp'?",
        "21:9: error: 'F1' is not a key a panel can report; did you mean 'F'?",
        "23:18: error: an image takes source: (an array expression) or file: (an image file), one of them",
    ]


def test_an_unknown_name_in_a_child_expression_points_into_it(tmp_path, capsys) -> None:
    body = (
        "      children:\n"
        "        - arrow: {position: [x, y], vector: [vxx, 1]}\n"
    )
    assert _errors(tmp_path, capsys, body) == ["18:46: error: unknown name 'vxx'"]


def test_a_good_panel_builds_into_records_of_the_app(tmp_path) -> None:
    from ejsgen.cli import build
    from ejsrl.app import load_app
    from ejsrl.view.elements2d import Drawing

    body = (
        "      x_range: [-2, 2]\n"
        "      y_range: [-2, 2]\n"
        "      keys: {Up: n = n + 1, Space: n = 0, '+': n = n + 5}\n"
        "      children:\n"
        "        - particle: {name: p, position: P, drag: {bind: P}}\n"
        "        - circle: {position: [x, y], radius: 0.5, drag: {bind: [x, y], along: curve, curve: on_circle}}\n"
        "        - spring: {start: [0, 0], end: [x, y], drag: {bind: [x, y], handle: end}}\n"
        "        - text: {position: [0, 1], text: 'n = {n}'}\n"
    )
    spec = tmp_path / "d.ejs.yaml"
    spec.write_text(HEAD + body)
    app = load_app(build(spec, tmp_path / "app"))
    (drawing,) = [el for el in app.view if isinstance(el, Drawing)]
    assert set(drawing.keys) == {"ArrowUp", "Space", "+"}
    kinds = [(s.kind, s.name) for s in drawing.children]
    assert kinds == [("particle", "p"), ("circle", "circle1"), ("spring", "spring1"), ("text", "text1")]
    assert drawing.children[0].drag.bind == ("P",) and drawing.children[0].drag.set_x is None
    assert drawing.children[1].drag.along == "curve"
    assert drawing.children[2].drag.handle == "end"


def test_the_panel_engine_loads_from_a_pyz_bundle(tmp_path) -> None:
    import subprocess
    import sys

    from ejsgen.cli import build
    from testkit import EXAMPLES

    out = build(EXAMPLES / "projectile_2d.ejs.yaml", tmp_path / "proj", bundle=True)
    pyz = out / "proj.pyz"
    code = ("import sys; sys.path.insert(0, sys.argv[1]); from ejsrl.view import _panel2d as p; "
            "assert '.pyz' in p.__file__, p.__file__; print(len(p.engine_js())); print('window.__ejs2d' in p.engine_js())")
    r = subprocess.run([sys.executable, "-P", "-c", code, str(pyz)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    size, found = r.stdout.split()
    assert int(size) > 10_000 and found == "True"


def test_a_keyboard_needs_a_scene(tmp_path, capsys) -> None:
    spec = tmp_path / "k.ejs.yaml"
    spec.write_text("ejs: 1\ntitle: K\nmodel:\n  variables:\n    n: 0\nview:\n  - keyboard: {keys: {ArrowUp: n = n + 1}}\n")
    assert main(["validate", str(spec)]) == 1
    err = capsys.readouterr().err
    assert f"{spec}:7:5: error: a keyboard acts on the 3D view, and this view has no scene; give the keys to a drawing panel" in err
    spec.write_text(spec.read_text() + "  - folder: {children: [{scene: [{sphere: {radius: 1}}]}]}\n")
    assert main(["validate", str(spec)]) == 0
