"""Two hints a new user's trial missed (issue #27): a variable given a quoted expression
(``pts: "np.zeros((22, 3))"``, text of shape ()) is named as text with the ``{expr: ...}``
form that computes it, and an unknown module written ``os.getpid()`` asks for an import
line in ``imports:`` rather than a one-letter variable; following either hint builds."""

from __future__ import annotations

from pathlib import Path

import pytest

from ejsgen.errors import SpecErrors

TEXT = """\
ejs: 1
title: hints
model:
  variables:
    t: 0.0
    pts: %s
view:
  - drawing:
      children:
        - path: {points: pts}
        - trace: {point: "[t, t]"}
  - scene:
      - line: {points: pts}
      - sphere: {position: pts}
"""

CODE = """\
ejs: 1
title: hints
%smodel:
  variables:
    t: 0.0
    s: 1.0
  evolution:
    - code: |
        t = t + %s
"""


def _build(tmp_path: Path, text: str) -> list[str]:
    """The build's errors, FILE relative to ``tmp_path`` ([] when it builds)."""
    from ejsgen.cli import build

    spec = tmp_path / "hints.ejs.yaml"
    spec.write_text(text)
    try:
        build(spec, tmp_path / "app")
    except SpecErrors as exc:
        return [str(e).replace(f"{tmp_path}/", "") for e in exc.errors]
    return []


def test_a_quoted_expression_is_named_as_text_with_the_expr_form(tmp_path: Path) -> None:
    errors = _build(tmp_path, TEXT % '"np.zeros((22, 3))"')
    hint = "'pts' is text: its value \"np.zeros((22, 3))\" is in quotes, so it is not computed; " \
           "for the value of an expression declare pts: {expr: \"np.zeros((22, 3))\"}"
    for where, words in (("hints.ejs.yaml:10:26", "the points of path 'path1' must be an N x 2 (positions) or N x 3 (poses) array"),
                         ("hints.ejs.yaml:13:24", "the points of line 'line1' must be N x 3"),
                         ("hints.ejs.yaml:14:28", "the position of 'sphere1' needs 3 numbers")):
        assert any(e.startswith(where) and words in e and e.endswith(hint) for e in errors), (where, errors)
    assert _build(tmp_path, TEXT % '{expr: "np.zeros((22, 3))"}') == []  # the hint's form builds


@pytest.mark.parametrize(("use", "col", "hint"), [
    ("os.getpid() * 0", 17, "'os' is a module: add 'import os' to the spec's imports: list"),
    ("sys.getrecursionlimit() * 0", 17, "'sys' is a module: add 'import sys' to the spec's imports: list"),
    ("math.sqrt(s)", 17, "'math' is a module: add 'import math' to the spec's imports: list (its functions and constants are "
                         "already names without 'math.': sin(x), sqrt(x), pi)"),
    ("numpy.sqrt(s)", 17, "NumPy is already 'np' without an import (np.zeros, np.linalg.norm); or add 'import numpy' to the spec's imports: list"),
])
def test_an_unknown_module_asks_for_an_import_line(tmp_path: Path, use: str, col: int, hint: str) -> None:
    errors = _build(tmp_path, CODE % ("", use))
    name = use.split(".")[0]
    assert [e for e in errors if f"unknown name '{name}'" in e] == [f"hints.ejs.yaml:9:{col}: error: unknown name '{name}'; " + hint]
    assert not any("did you mean 's'" in e for e in errors), errors
    assert _build(tmp_path, CODE % (f"imports:\n  - import {name}\n", use)) == []


def test_a_misspelt_variable_still_gets_the_variable(tmp_path: Path) -> None:
    """Only a name written as ``name.attr`` is taken for a module: ``ss`` alone is a typo of ``s``."""
    errors = _build(tmp_path, CODE % ("", "ss"))
    assert errors == ["hints.ejs.yaml:9:17: error: unknown name 'ss'; did you mean 's'?"], errors
