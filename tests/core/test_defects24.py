"""Issue #24, item 7: the small defects new authors met, each as the author meets it.

- ``start_program(name)`` from ``init`` (or from a custom function ``init`` calls) starts
  the program, and again after every reset;
- ``x^2`` is refused when the spec is built, at the ``^``, with "did you mean x**2";
- a variable named after a prelude name (``e`` for a restitution) is refused with the
  reason and a name to use instead;
- a local of an ODE page's ``preliminary`` is seen by that page's rates; used anywhere
  else, the error says where it is visible and how to share it;
- every public function of ``ejsrl.vision`` is in the language reference, with its
  signature and the first line of its docstring.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from ejsgen.errors import SpecErrors
from ejsrl.app import load_app
from testkit import ROOT

LANGUAGE = ROOT / "specs" / "language.md"


def build_text(tmp_path: Path, text: str, name: str = "lab") -> Path:
    from ejsgen.cli import build

    spec = tmp_path / f"{name}.ejs.yaml"
    spec.write_text(text, encoding="utf-8")
    return build(spec, tmp_path / name)


def build_errors(tmp_path: Path, text: str, name: str = "bad") -> list[str]:
    """The build's error lines (``FILE:LINE:COL: message (hint)``), as ``ejsgen build`` prints them."""
    with pytest.raises(SpecErrors) as info:
        build_text(tmp_path, text, name)
    return [str(e) for e in info.value.errors]


def position(text: str, line_text: str, needle: str) -> tuple[int, int]:
    """1-based (line, column) of ``needle`` in the first line of ``text`` holding ``line_text``."""
    for i, line in enumerate(text.splitlines(), start=1):
        if line_text in line:
            return i, line.index(needle, line.index(line_text)) + 1
    raise AssertionError(f"{line_text!r} not in the spec")


# -- 1. start_program() from init ---------------------------------------------------------------

PROGRAM = """\
ejs: 1
title: A program started by init
imports:
  - from ejsrl.robotics import models
model:
  variables:
    t: 0.0
    dt: 0.01
    arm: {{expr: "models.planar(2)"}}
    q: [0.0, 0.0]
    stage: 0
    t_arrived: -1.0
  init: |
    {start}
  evolution:
    - code: |
        t = t + dt
  custom: |
    def begin():
        start_program('go')
  programs:
    go:
      robot: arm
      q: q
      code: |
        stage = 1
        move_j([1.0, -0.5], time=1.0)
        t_arrived = t
        stage = 2
view:
  - button: {{label: Halt, action: "stop_program('go')"}}
"""


@pytest.mark.parametrize("start", ["start_program('go')", "begin()"], ids=["in-init", "from-a-custom-function"])
def test_start_program_from_init_starts_it(tmp_path: Path, start: str) -> None:
    app = load_app(build_text(tmp_path, PROGRAM.format(start=start)))
    assert app.error is None
    assert app.model.stage == 1  # the statements before the first move ran at once
    assert app.model._ejs_program_status("go").startswith("program 'go': running")
    for _ in range(150):
        app.step_once()
    assert app.model.stage == 2
    assert np.allclose(app.model.q, [1.0, -0.5])  # the move took its second of simulated time
    assert app.model.t_arrived == pytest.approx(1.0, abs=0.011)
    # a reset stops the program, then init runs and starts it again from its first line
    app.reset()
    assert np.allclose(app.model.q, [0.0, 0.0]) and app.model.t == 0.0
    assert app.model.stage == 1
    assert app.model._ejs_program_status("go").startswith("program 'go': running")
    for _ in range(150):
        app.step_once()
    assert app.model.stage == 2


def test_an_autostart_program_started_by_init_runs_once(tmp_path: Path) -> None:
    text = PROGRAM.format(start="start_program('go')").replace("      q: q\n", "      q: q\n      autostart: true\n")
    text = text.replace("        stage = 1\n", "        stage = stage + 1\n")
    app = load_app(build_text(tmp_path, text))
    assert app.model.stage == 1  # started by init, not started a second time by autostart
