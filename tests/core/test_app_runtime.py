"""The app runtime without a browser: stepping, events, errors with spec locations,
changes from the view, realtime pacing, alerts, and the command line's checks."""

from __future__ import annotations

import sys
import threading
from math import sqrt
from pathlib import Path

import numpy as np
import pytest

from ejsrl.app import App, SimConfig, load_app, parse_set
from ejsrl.view.elements import Button, Slider, Text
from testkit import run_app
from testkit.clock import FakeClock

SPECS = Path(__file__).parent / "specs"


@pytest.fixture(scope="module")
def checks_module(tmp_path_factory):
    from ejsgen.cli import build

    out = build(SPECS / "runtime_checks.ejs.yaml", tmp_path_factory.mktemp("rt") / "checks")
    return sys.modules[load_app(out).model_cls.__module__], out


def make_app(module, out, clock=None, **sim) -> App:
    cfg = SimConfig(**{**vars(getattr(module, "SIMULATION", SimConfig())), **sim})  # app.py leaves out default settings
    extra = {} if clock is None else {"clock": clock}
    return App(module.Model, module.VIEW, sim=cfg, meta=module.META, base_dir=out, **extra)


def control(module, cls, bind):
    return next(e for e in module.VIEW if isinstance(e, cls) and e.bind == bind)


def test_stop_event_pauses_at_the_located_time_and_alerts(checks_module) -> None:
    module, out = checks_module
    app = make_app(module, out)
    app.play()
    for _ in range(200):
        app.frame()
        if not app.is_playing():
            break
    assert not app.is_playing() and app.error is None
    t_half = sqrt(2 * 5.0 / 9.81)
    alerts = app.pop_alerts()
    assert len(alerts) == 1 and abs(float(alerts[0].split("=")[1]) - t_half) < 1e-4
    # the scene follows the model: the sphere is at the mass's height
    assert app.world["mass"].T_world()[2, 3] == pytest.approx(app.model.y)


def test_user_code_error_pauses_with_its_spec_location_and_the_app_goes_on(checks_module) -> None:
    module, out = checks_module
    app = make_app(module, out)
    app.play()
    app.apply_control(control(module, Slider, "k"), 0.0)  # fixed relations divide by k
    assert app.error is not None
    assert app.error.where == "runtime_checks.ejs.yaml:29:5"
    assert "ZeroDivisionError" in app.error.message
    assert not app.is_playing()
    app.play()  # refused while the error stands
    assert not app.is_playing()
    app.reset()  # clears the error; the model is whole again
    assert app.error is None and app.model.k == 1.0 and app.model.z == 1.0


def test_a_change_from_the_view_restarts_the_adaptive_solver(checks_module, monkeypatch) -> None:
    module, out = checks_module
    app = make_app(module, out)
    page = app.model._ejs_pages[0]
    calls = []
    monkeypatch.setattr(page.integrator, "reset", lambda: calls.append(1))
    app.apply_control(control(module, Slider, "y"), 12.5)
    assert calls and app.model.y == 12.5
    # and the motion goes on from the new state: after one step, y = 12.5 - g dt^2 / 2
    app.step_once()
    assert app.model.y == pytest.approx(12.5 - 0.5 * 9.81 * 0.01**2, abs=1e-9)


def test_text_control_and_custom_action(checks_module) -> None:
    module, out = checks_module
    app = make_app(module, out)
    app.apply_control(control(module, Text, "note"), "world")
    app.run_action(next(e for e in module.VIEW if isinstance(e, Button) and e.label == "Shout"))
    assert app.pop_alerts() == ["hello world"]


def test_reset_from_an_action_restores_initial_values(checks_module) -> None:
    module, out = checks_module
    app = make_app(module, out)
    for _ in range(10):
        app.step_once()
    assert app.model.t > 0
    app.run_action(next(e for e in module.VIEW if isinstance(e, Button) and e.label == "Again"))
    assert app.model.t == 0.0 and app.model.y == 10.0


class _Ticker:
    """A view whose every frame takes one frame period on the clock; stops the loop after ``n``."""

    def __init__(self, clock: FakeClock, stop: threading.Event, n: int, period: float) -> None:
        self.clock, self.stop, self.n, self.period, self.frames = clock, stop, n, period, 0

    def on_frame(self) -> None:
        self.clock.advance(self.period)
        self.frames += 1
        if self.frames >= self.n:
            self.stop.set()


def test_realtime_paces_time_to_the_wall_clock(checks_module) -> None:
    module, out = checks_module
    clock = FakeClock()
    app = make_app(module, out, clock=clock, realtime=True, fps=30)
    app.model.g = 0.0  # no event: keep falling at rest
    app.play()
    stop = threading.Event()
    ticker = _Ticker(clock, stop, n=30, period=1.0 / 30)  # one second of frames at 30 a second
    app.views.append(ticker)
    thread = threading.Thread(target=app.run_loop, args=(stop,))
    start = clock()
    thread.start()
    thread.join(timeout=60)
    assert not thread.is_alive() and ticker.frames == 30
    wall = clock() - start
    assert app.model.t == pytest.approx(wall, abs=0.25)
    # each frame catches up with the clock as it was when the frame began
    assert app.model.t == pytest.approx(29 / 30, abs=0.011)


def test_realtime_pacing_follows_the_clock_not_the_frames(checks_module) -> None:
    """Frames that come late (the clock moved 0.1 s between them) still give simulated
    time equal to the time on the clock."""
    module, out = checks_module
    clock = FakeClock()
    app = make_app(module, out, clock=clock, realtime=True, fps=30)
    app.model.g = 0.0
    app.play()
    app.frame()
    for _ in range(5):
        clock.advance(0.1)
        app.frame()
    assert app.model.t == pytest.approx(0.5, abs=0.011)


def test_steps_per_display_runs_that_many_steps_a_frame(checks_module) -> None:
    module, out = checks_module
    app = make_app(module, out, steps_per_display=7)
    app.play()
    app.frame()
    assert app.model.t == pytest.approx(0.07)


def test_parse_set_takes_literals_only() -> None:
    types = {"x": "float", "n": "int", "on": "bool", "s": "str", "q": "array"}
    assert parse_set("x=2.5", types) == ("x", 2.5)
    assert parse_set("n=3", types) == ("n", 3)
    assert parse_set("on=true", types) == ("on", True)
    assert parse_set("s=hello", types) == ("s", "hello")
    name, q = parse_set("q=[1, 2, 3]", types)
    assert name == "q" and np.array_equal(q, [1.0, 2.0, 3.0])
    for bad in ("x=__import__('os')", "n=2.5", "x=nan", "y=1", "q=[1, 'a']", "x"):
        with pytest.raises(ValueError):
            parse_set(bad, types)


def test_command_line_errors_exit_nonzero_without_traceback(checks_module) -> None:
    _, out = checks_module
    for args, text in (
        (["--headless", "--duration", "1", "--set", "yy=1"], "did you mean 'y'?"),
        (["--headless", "--duration", "1", "--vars", "t,vv"], "did you mean 'v'?"),
        (["--headless"], "--duration"),
        (["--duration", "1"], "go with --headless"),
    ):
        r = run_app(out, *args, timeout=60)
        assert r.returncode == 2, args
        assert text in r.stderr and "Traceback" not in r.stderr, r.stderr


def test_headless_stop_event_ends_the_run_cleanly(checks_module) -> None:
    _, out = checks_module
    r = run_app(out, "--headless", "--duration", "5", "--csv", "-", "--vars", "t,y", timeout=60)
    assert r.returncode == 0
    assert "alert: half way" in r.stderr and "paused itself" in r.stderr
    last = r.stdout.strip().splitlines()[-1].split(",")
    assert float(last[1]) == pytest.approx(5.0, abs=1e-6)


def test_the_app_serves_on_loopback_by_default(checks_module) -> None:
    _, out = checks_module
    text = (out / "app.py").read_text()
    r = run_app(out, "--help", timeout=60)
    assert "127.0.0.1" in r.stdout
    import ejsrl.app.cli as app_module

    assert app_module._parser("x").parse_args([]).host == "127.0.0.1"
    assert "eval(" not in text and "exec(" not in text


def test_preliminary_code_runs_before_each_rate_evaluation(tmp_path) -> None:
    from ejsgen.cli import build

    app = load_app(build(SPECS / "preliminary.ejs.yaml", tmp_path / "pre"))
    for _ in range(40):  # 2 s
        app.step_once()
    m = app.model
    assert m.calls == 4 * 40  # RK4: four evaluations of the rates a step
    assert m.x == pytest.approx(np.cos(m.w * m.t), abs=1e-5)  # the shared acceleration is the right one
    assert m.v == pytest.approx(-m.w * np.sin(m.w * m.t), abs=1e-4)


def test_a_state_that_blows_up_stops_with_the_equations_location(tmp_path) -> None:
    from ejsgen.cli import build

    out = build(SPECS / "preliminary.ejs.yaml", tmp_path / "pre")
    r = run_app(out, "--headless", "--duration", "50", "--set", "grow=50.0", "--set", "w=0", "--set", "v=5", timeout=60)
    assert r.returncode == 1
    assert "preliminary.ejs.yaml:21:9: error: the state became non-finite" in r.stderr
    assert "Traceback" not in r.stderr
