"""Robot programs run alongside the simulation in simulated time."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from ejsrl.app import App, SimConfig, load_app
from ejsrl.view.elements import Button, Label

SPECS = Path(__file__).parent / "specs"


@pytest.fixture(scope="module")
def moves(tmp_path_factory):
    from ejsgen.cli import build

    out = build(SPECS / "program_moves.ejs.yaml", tmp_path_factory.mktemp("prog") / "moves")
    return sys.modules[load_app(out).model_cls.__module__], out


def make(module, out, **overrides) -> App:
    sim = getattr(module, "SIMULATION", SimConfig())  # app.py leaves out default settings
    return App(module.Model, module.VIEW, sim=sim, meta=module.META, base_dir=out, overrides=overrides)


def press(app: App, module, label: str) -> None:
    app.run_action(next(e for e in module.VIEW if isinstance(e, Button) and e.label == label))


def run_until(app: App, cond, limit: int = 5000) -> list[tuple[float, np.ndarray]]:
    trace = []
    for _ in range(limit):
        app.step_once()
        trace.append((app.model.t, np.array(app.model.q)))
        if cond():
            break
    return trace


def status(app: App, module) -> str:
    label = next(e for e in module.VIEW if isinstance(e, Label))
    return app.safe_value(label.text)


def test_programs_take_simulated_time_and_move_as_planned(moves) -> None:
    module, out = moves
    app = make(module, out)
    assert status(app, module) == "program 'demo': idle"
    press(app, module, "Run")
    assert app.model.stage == 1  # statements before the first command ran at once
    assert "running, line 30" in status(app, module)  # at the first move_j (spec line 30)
    trace = run_until(app, lambda: app.model.stage >= 4)
    # synchronous move with time=2: every joint arrives together at t = 2
    assert app.model.t_sync == pytest.approx(2.0, abs=1e-9)
    q_at = dict((round(t, 6), q) for t, q in trace)
    assert np.allclose(q_at[2.0], [1.0, -0.5, 0.25])
    mid = q_at[1.0]
    fractions = mid / np.array([1.0, -0.5, 0.25])
    assert np.allclose(fractions, fractions[0])  # same fraction of the way: they move in sync
    # wait(0.5), then an asynchronous move at 1 rad/s peak speed: the longest joint (1 rad) sets the time
    ts = np.array([t for t, _ in trace])
    qs = np.array([q for _, q in trace])
    seg = (ts > 2.5 + 1e-9) & (ts <= app.model.t_async + 1e-9)
    speeds = np.abs(np.diff(qs[seg], axis=0)) / 0.01
    assert speeds.max() <= 1.0 + 1e-6
    # joint 2 travels 0.5 rad, joint 1 a full radian: asynchronous, joint 2 arrives first
    # (trapezoids at 1 rad/s and 4 rad/s^2: 0.75 s against 1.25 s)
    joint2_done = ts[seg][np.argmax(np.isclose(qs[seg][:, 1], 0.0))]
    assert joint2_done - 2.5 == pytest.approx(0.75, abs=0.02)
    assert app.model.t_async - 2.5 == pytest.approx(1.25, abs=0.02)
    assert np.allclose(qs[seg][-1], [0.0, 0.0, 0.25])
    # the pose target (identity) was solved by ikine: the arm's tool reaches it
    T = app.model.arm.fkine(app.model.q)
    assert np.allclose(T, app.model.target, atol=1e-8)
    assert app.model.grip == 1.0


def test_a_program_error_stops_the_program_not_the_app(moves) -> None:
    module, out = moves
    app = make(module, out, fail=True)
    app.play()
    press(app, module, "Run")
    run_until(app, lambda: app.model.stage >= 3 and "error" in status(app, module), limit=1000)
    text = status(app, module)
    assert "stopped on an error at program_moves.ejs.yaml:38:13" in text and "IndexError" in text
    assert app.error is None and app.is_playing()
    alerts = app.pop_alerts()
    assert any("program 'demo' stopped" in a for a in alerts)
    t = app.model.t
    app.step_once()
    assert app.model.t > t  # the simulation goes on


def test_stop_program_and_reset(moves) -> None:
    module, out = moves
    app = make(module, out)
    press(app, module, "Run")
    run_until(app, lambda: app.model.t > 1.0)
    press(app, module, "Halt")
    q = np.array(app.model.q)
    run_until(app, lambda: app.model.t > 1.5)
    assert np.array_equal(app.model.q, q)  # stopped where it was
    assert status(app, module) == "program 'demo': stopped"
    app.reset()
    assert status(app, module) == "program 'demo': idle" and app.model.stage == 0


def test_commands_are_statements_only(tmp_path) -> None:
    from ejsgen.cli import main

    text = (SPECS / "program_moves.ejs.yaml").read_text().replace("        t_sync = t\n", "        t_sync = wait(1)\n")
    spec = tmp_path / "bad.ejs.yaml"
    spec.write_text(text)
    assert main(["validate", str(spec)]) == 1
