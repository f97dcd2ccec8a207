"""One element body serves the drawing panel and the 3D scene (issue #27's trial): the
path's and the particles' ``points``, the ellipse's ``position`` (its centre) mean the same
in both, and both draw what an independent computation gives; the 3D scene's former
spellings (``path:``, ``particles:``, ``centre:``) are refused with the key to use."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ejsgen.errors import SpecErrors

#: the same bodies, written once, go under the drawing panel and the 3D scene
BODIES = """\
        - ellipse: {position: c, covariance: P, confidence: 0.9, scale: 2}
        - particles: {points: poses, color: orange}
        - path: {points: "poses[:, :2]"}
"""

SPEC = """\
ejs: 1
title: one body
model:
  variables:
    t: 0.0
    P: {expr: "np.array([[0.5, 0.2, 0.0], [0.2, 0.3, 0.0], [0.0, 0.0, 0.1]])"}
    c: {value: [1.0, -1.0]}
    poses: {expr: "np.array([[0.0, 0.0, 0.5], [1.0, 2.0, 1.0], [3.0, 1.0, -1.0]])"}
view:
  - drawing:
      x_range: [-5, 5]
      y_range: [-5, 5]
      children:
%s  - scene:
%s"""


def _sibling(name: str):  # type: ignore[no-untyped-def]
    """A test module of this folder (its helpers)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"_mobile_{name}", Path(__file__).with_name(f"{name}.py"))
    mod = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(mod)  # type: ignore[union-attr]
    return mod


def _spec(tmp_path: Path, bodies_3d: str) -> Path:
    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(SPEC % (BODIES, bodies_3d))
    return spec


def _chi2(xy: np.ndarray) -> np.ndarray:
    """Each point's squared Mahalanobis distance from [1, -1] under 4 x P's top-left 2 x 2."""
    d = xy - [1.0, -1.0]
    return np.einsum("ij,jk,ik->i", d, np.linalg.inv(4.0 * np.array([[0.5, 0.2], [0.2, 0.3]])), d)


def test_the_same_bodies_draw_the_same_in_the_panel_and_the_scene(tmp_path: Path) -> None:
    from ejsgen.cli import build
    from ejsrl.app import load_app
    from ejsrl.view._drawing import DrawingBinding
    from ejsrl.view.elements2d import Drawing

    kinds = _sibling("test_mobile_kinds")
    _fake_gui, xy = kinds._fake_gui, kinds.xy

    bodies_3d = BODIES.replace("        - ", "      - ")
    app = load_app(build(_spec(tmp_path, bodies_3d), tmp_path / "app"))
    app.play()
    app.frame()
    assert app.error is None
    drawing = next(el for el in app.view if isinstance(el, Drawing))
    b = DrawingBinding(_fake_gui(), drawing, app, key="d")
    b.refresh()
    ell2, parts2, path2 = (xy(it) for it in b.frame["items"][:3])
    nodes = app.scene.world.nodes
    ell3, parts3, path3 = (nodes[n].props["points"] for n in ("ellipse1", "particles1", "path1"))
    limit = -2.0 * math.log(1.0 - 0.9)  # chi-squared, 2 degrees of freedom, 90 %
    np.testing.assert_allclose(_chi2(ell2), limit, rtol=1e-5)
    np.testing.assert_allclose(_chi2(ell3[:, :2]), limit, rtol=1e-9)
    np.testing.assert_allclose(ell3[:, 2], 0.02)
    for two, three in ((parts2, parts3), (path2, path3)):
        np.testing.assert_allclose(two, [[0, 0], [1, 2], [3, 1]], atol=1e-6)
        np.testing.assert_allclose(three, [[0, 0, 0.02], [1, 2, 0.02], [3, 1, 0.02]], atol=1e-12)
    # the ellipse's position is its centre, not a placement: its node stays where the scene has it
    np.testing.assert_allclose(nodes["ellipse1"].T_world(), np.eye(4))


def test_a_path_that_does_not_change_is_not_sent_again(tmp_path: Path) -> None:
    from ejsrl.mobile._nodes import PathNode

    node = PathNode("p", points=np.array([[0.0, 0.0, 0.5], [1.0, 2.0, 1.0]]))
    np.testing.assert_allclose(node.props["points"], [[0, 0, 0.02], [1, 2, 0.02]])
    rev = node.rev
    assert not node.set(points=np.array([[0.0, 0.0, 0.5], [1.0, 2.0, 1.0]]))
    assert node.set(z=0.5) and node.rev == rev + 1
    np.testing.assert_allclose(node.props["points"], [[0, 0, 0.5], [1, 2, 0.5]])


@pytest.mark.parametrize(("body", "col", "key", "hint"), [
    ("      - path: {path: poses}\n", 16, "path", "did you mean 'points'?"),
    ("      - particles: {particles: poses}\n", 21, "particles", "did you mean 'points'?"),
    ("      - ellipse: {centre: c, covariance: P}\n", 19, "centre", "did you mean 'position'?"),
])
def test_the_former_3d_spellings_are_refused_with_the_key_to_use(tmp_path: Path, body: str, col: int, key: str, hint: str) -> None:
    from ejsgen.cli import build

    with pytest.raises(SpecErrors) as info:
        build(_spec(tmp_path, body), tmp_path / "app")
    errors = [str(e).replace(f"{tmp_path}/", "") for e in info.value.errors]
    line = SPEC.count("\n", 0, SPEC.index("  - scene:")) + BODIES.count("\n") + 2
    assert any(e.startswith(f"lab.ejs.yaml:{line}:{col}") and f"unknown key '{key}'" in e and hint in e for e in errors), errors


def test_a_literal_body_draws_the_same_in_both(tmp_path: Path) -> None:
    """Lists written out (not expressions) are accepted by the scene as by the panel."""
    from ejsgen.cli import build
    from ejsrl.app import load_app

    body = ("        - path: {points: [[0, 0], [1, 2], [3, 1]]}\n"
            "        - ellipse: {position: [1, -1], covariance: [[0.5, 0.2], [0.2, 0.3]], confidence: 0.9, scale: 2}\n")
    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(SPEC % (body, body.replace("        - ", "      - ")))
    app = load_app(build(spec, tmp_path / "app"))
    app.play()
    app.frame()
    assert app.error is None
    nodes = app.scene.world.nodes
    np.testing.assert_allclose(nodes["path1"].props["points"], [[0, 0, 0.02], [1, 2, 0.02], [3, 1, 0.02]], atol=1e-12)
    np.testing.assert_allclose(_chi2(nodes["ellipse1"].props["points"][:, :2]), -2.0 * math.log(0.1), rtol=1e-9)


@pytest.mark.parametrize(("body", "key", "words"), [
    ("particles: {points: c}", "points", "must be an N x 2 (positions) or N x 3 (poses) array, but 'c' has shape (2,)"),
    ("ellipse: {position: c, covariance: c}", "covariance", "must be a square covariance matrix, 2 x 2 or larger, but 'c' has shape (2,)"),
    ("ellipse: {position: c, covariance: P, confidence: 95}", "confidence", "is a probability between 0 and 1 (not included), got 95"),
])
def test_a_bad_body_is_the_same_build_error_in_both(tmp_path: Path, body: str, key: str, words: str) -> None:
    """The scene checks a mobile kind's keys by the panel's rules: the same words at the same key."""
    from ejsgen.cli import build

    text = SPEC % (f"        - {body}\n", f"      - {body}\n")
    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(text)
    with pytest.raises(SpecErrors) as info:
        build(spec, tmp_path / "app")
    errors = [str(e).replace(f"{tmp_path}/", "") for e in info.value.errors]
    lines = text.split("\n")
    panel = lines.index(f"        - {body}") + 1
    col = 8 + 2 + body.index(f"{key}: ") + len(key) + 2 + 1  # the value after '- ' and 'key: ', 1-based
    for line, c in ((panel, col), (panel + 2, col - 2)):
        assert any(e.startswith(f"lab.ejs.yaml:{line}:{c}: error:") and words in e for e in errors), (line, c, errors)
