"""Issue #24: the independent variable of a fixed step is exact multiples of the step.

Adding ``dt`` to ``t`` step after step accumulates round-off (800 steps of 0.01 gave
7.999999999999874); an ODE page now counts its steps, ``t = t0 + n*dt``. What a user sees:
the headless CSV's ``t`` column reads exactly ``np.arange(n) * dt`` (and ``8.0`` after 800
steps), in every method, in the served loop as in a headless run; a step changed at run
time counts again from the time it was changed at; a ``stop`` event keeps the time it was
located at, and the next step goes exactly one step from there. The CSV's lines end in
``\\n`` alone.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np
import pytest

from ejsrl.app import load_app
from testkit import run_app

SPEC = """\
ejs: 1
title: Time grid
model:
  variables:
    t: 0.0
    dt: 0.01
    x: 1.0
    v: 0.0
  evolution:
    - ode:
        method: {method}
        equations:
          x: v
          v: -x
view:
  - label: {{text: "{{x:.3f}}"}}
"""

BALL = """\
ejs: 1
title: Ball stops on the floor
model:
  variables:
    t: 0.0
    dt: 0.01
    y: 1.0
    v: 0.0
  evolution:
    - ode:
        equations:
          y: v
          v: -9.81
        events:
          - {name: floor, when: y, direction: down, action: "v = -v", stop: true}
view:
  - label: {text: "{y:.3f}"}
"""


def _build(tmp_path: Path, text: str, name: str) -> Path:
    from ejsgen.cli import build

    spec = tmp_path / f"{name}.ejs.yaml"
    spec.write_text(text, encoding="utf-8")
    return build(spec, tmp_path / name)


@pytest.mark.parametrize("method", ["rk4", "euler", "dopri5", "radau"])
def test_headless_csv_time_is_exact_multiples_of_dt(tmp_path: Path, method: str) -> None:
    out = _build(tmp_path, SPEC.format(method=method), method)
    csv_path = tmp_path / "run.csv"
    r = run_app(out, "--headless", "--duration", "8", "--csv", str(csv_path), "--vars", "t,x")
    assert r.returncode == 0, r.stderr
    data = csv_path.read_bytes()
    assert b"\r" not in data  # lines end in \n, not CRLF
    rows = list(csv.reader(io.StringIO(data.decode())))
    assert rows[0] == ["t", "x"]
    t_text = [row[0] for row in rows[1:]]
    assert len(t_text) == 801
    assert t_text[-1] == "8.0"  # not 7.999999999999874
    expected = np.arange(801) * 0.01
    assert t_text == [repr(float(v)) for v in expected]  # as printed, digit for digit
    # the solution is unharmed: x = cos(t)
    x = np.array([float(row[1]) for row in rows[1:]])
    assert np.allclose(x, np.cos(expected), atol=0.05 if method == "euler" else 1e-5)


def test_served_loop_keeps_time_on_the_grid(tmp_path: Path) -> None:
    out = _build(tmp_path, SPEC.format(method="rk4"), "served")
    app = load_app(out)
    app.play()
    for _ in range(800):
        app.frame()  # the served loop's frame: steps_per_display steps, then the view
    assert app.model.t == 8.0
    # a change from the view that is not the time or the step keeps the count going
    app.model.v = 0.5
    app.model._ejs_restart_solvers()
    for _ in range(100):
        app.step_once()
    assert app.model.t == 900 * 0.01
    # a reset starts the count again from the initial time
    app.reset()
    assert app.model.t == 0.0
    for _ in range(300):
        app.step_once()
    assert app.model.t == 300 * 0.01 == 3.0


def test_a_step_changed_at_run_time_counts_from_the_time_it_changed(tmp_path: Path) -> None:
    out = _build(tmp_path, SPEC.format(method="rk4"), "change")
    app = load_app(out)
    for _ in range(100):
        app.step_once()
    t_change = app.model.t
    assert t_change == 1.0
    app.model.dt = 0.03
    for n in range(1, 301):
        app.step_once()
        assert app.model.t == t_change + n * 0.03
    # and a time set by hand (an action writing t) is where counting starts again
    app.model.t = 0.7
    for n in range(1, 11):
        app.step_once()
        assert app.model.t == 0.7 + n * 0.03


def test_a_stop_event_keeps_its_located_time_and_the_next_step_counts_from_it(tmp_path: Path) -> None:
    out = _build(tmp_path, BALL, "ball")
    app = load_app(out)
    app.play()
    for _ in range(1000):
        app.step_once()
        if not app.is_playing():
            break
    t_hit = app.model.t
    assert t_hit == pytest.approx(np.sqrt(2 / 9.81), abs=1e-9)  # located, not on the grid
    assert round(t_hit / 0.01) * 0.01 != t_hit
    app.play()
    for n in range(1, 51):
        app.step_once()
        assert app.model.t == t_hit + n * 0.01


def test_sweep_tables_write_plain_newlines(tmp_path: Path) -> None:
    from ejsrl.app.sweep_table import Column, Table, write_table

    table = Table({"k": Column("float", np.array([1.0, 2.0])), "peak": Column("float", np.array([0.5, 0.25]))})
    path = tmp_path / "runs.csv"
    write_table(table, path)
    data = path.read_bytes()
    assert b"\r" not in data and data.count(b"\n") == 3
