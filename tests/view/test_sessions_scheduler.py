"""The classroom's stepper pool: fair when overloaded, nothing for idle tasks, bounded threads;
and the command line that chooses between a simulation per tab and one shared."""

from __future__ import annotations

import threading
import time

import pytest

from ejsrl.app import _sessions, cli
from ejsrl.app._loop import App
from ejsrl.app._scheduler import Scheduler
from testkit.browser_lab import VIEW, Pendulum, make_app


class Busy:
    """A task that wants ``fps`` frames a second, each taking ``cost`` seconds of its worker."""

    def __init__(self, fps: float, cost: float, playing: bool = True) -> None:
        self.period, self.cost, self.playing = 1.0 / fps, cost, playing
        self.frames = 0

    def tick(self, due: float) -> float | None:
        time.sleep(self.cost)
        self.frames += 1
        if not self.playing:
            return None
        now = time.monotonic()
        nxt = due + self.period
        return nxt if nxt >= now else now


def test_an_overloaded_pool_slows_every_task_evenly():
    # 5 tasks asking 30 frames/s of 10 ms on one worker: 150 frames/s asked, 100 possible
    pool = Scheduler(1)
    tasks = [Busy(30.0, 0.010) for _ in range(5)]
    try:
        for t in tasks:
            pool.wake(t)
        time.sleep(3.0)
    finally:
        pool.stop()
    frames = [t.frames for t in tasks]
    assert sum(frames) > 100, frames  # the worker was kept busy (about 300 possible; less on a loaded machine)
    assert max(frames) - min(frames) <= 0.15 * max(frames) + 1, f"uneven frames: {frames}"
    assert max(frames) < 0.85 * 90  # nobody got its full 30 frames/s


def test_a_pool_that_keeps_up_gives_each_task_its_rate_and_idle_tasks_nothing():
    pool = Scheduler(2)
    playing = [Busy(30.0, 0.001) for _ in range(3)]
    idle = Busy(30.0, 0.001, playing=False)
    try:
        for t in (*playing, idle):
            pool.wake(t)
        time.sleep(2.0)
        frames = [t.frames for t in playing]
        assert idle.frames == 1  # one frame when woken, then nothing
        pool.wake(idle)
        time.sleep(0.2)
        assert idle.frames == 2
    finally:
        pool.stop()
    for n in frames:
        assert 50 <= n <= 62, frames  # 30 frames/s for 2 s, no catching up beyond it


def test_the_pool_has_the_threads_it_was_given():
    before = threading.active_count()
    pool = Scheduler(3)
    try:
        for _ in range(20):
            pool.wake(Busy(30.0, 0.0))
        assert threading.active_count() == before + 3
    finally:
        pool.stop()


def test_the_default_limit_follows_the_cores_and_the_lab_cost():
    assert _sessions.default_max_sessions(0.001, 30.0, cpus=2) == 35  # 1.6 cores / ((1.1 * 1.0 + 0.4) ms * 30)
    assert _sessions.default_max_sessions(0.001, 30.0, cpus=4) == 71
    assert _sessions.default_max_sessions(0.020, 30.0, cpus=2) == 2  # a heavy lab: the floor
    assert _sessions.default_max_sessions(1e-9, 30.0, cpus=64) == _sessions.MAX_DEFAULT_SESSIONS
    # a cheap lab's frames still cost the sending: the pendulum's 0.25 ms frames (its view
    # included), 1 core (a process) -> 0.8 / ((1.1 * 0.25 + 0.4) ms * 30) = 39 a process, 78 on
    # two cores, where bench/classroom.py held 60 at load 6.7 and 80 at 24.4 frames/s
    assert _sessions.default_max_sessions(0.00025, 30.0, cpus=1.0) == 39
    # the six-axis arm's 0.72 ms frames: 22 a process, 44 on two cores (bench/classroom.py held 40);
    # visual servoing's 4.72 ms: 4 a process, 8 on two cores (held 8; 10 ran at 0.94 of real time)
    assert _sessions.default_max_sessions(0.00072, 30.0, cpus=1.0) == 22
    assert _sessions.default_max_sessions(0.00472, 30.0, cpus=1.0) == 4
    app = make_app()
    cost = _sessions.measure_frame_cost(app, frames=4)
    assert 0.0 < cost < 0.05
    assert app.model.t == 0.0 and not app.is_playing()  # the probe leaves the app as it was


@pytest.fixture
def served_with(monkeypatch):
    """Run ``cli.main`` with ``App.serve`` recorded instead of serving."""
    calls: list[dict] = []
    monkeypatch.setattr(App, "serve", lambda self, host, port, **kw: calls.append(dict(host=host, port=port, **kw)))

    def run(*argv: str) -> tuple[int, list[dict]]:
        status = cli.main(Pendulum, VIEW, sim=make_app().sim, meta=make_app().meta, base_dir=".", argv=list(argv))
        return status, calls

    return run


def test_serving_gives_each_tab_its_own_simulation_unless_shared(served_with):
    status, calls = served_with()
    assert status == 0 and calls[-1]["per_client"] is True and calls[-1]["max_sessions"] is None
    assert calls[-1]["grace"] == 60.0
    status, calls = served_with("--shared")
    assert status == 0 and calls[-1]["per_client"] is False
    status, calls = served_with("--max-sessions", "12", "--grace", "5")
    assert calls[-1]["max_sessions"] == 12 and calls[-1]["grace"] == 5.0


def test_bad_session_options_are_plain_errors(served_with, capsys):
    assert served_with("--max-sessions", "0")[0] == 2
    assert "--max-sessions must be at least 1" in capsys.readouterr().err
    assert served_with("--grace", "-1")[0] == 2
    assert "--grace" in capsys.readouterr().err


def test_help_describes_the_classroom_options(capsys):
    with pytest.raises(SystemExit):
        cli.main(Pendulum, VIEW, sim=make_app().sim, meta=make_app().meta, base_dir=".", argv=["--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "--shared" in out and "one simulation for everyone" in out
    assert "--max-sessions N" in out and "the next one is told the lab is full" in out
    assert "--grace SECONDS" in out and "a reload finds it again" in out


def test_the_measured_cost_counts_a_picture_at_the_rate_the_view_reads_it():
    """An image element is read at most IMAGE_RATE times a second (the costliest thing a
    frame computes, a virtual camera's picture, is not made 30 or 60 times a second): its
    cost counts in that share of the frames, a label's in every frame."""
    import numpy as np

    from ejsrl.app import App, AppMeta, SimConfig
    from ejsrl.view._plots import IMAGE_RATE
    from ejsrl.view.elements import Dynamic, Image, Label
    from testkit.view_lab import LabModel

    def costly(m):
        end = time.thread_time() + 0.004  # 4 ms of CPU, as a camera picture
        while time.thread_time() < end:
            pass
        return np.zeros((8, 8), np.uint8)

    def cost_with(element, fps: float) -> float:
        app = App(LabModel, [element], sim=SimConfig(fps=fps), meta=AppMeta(title="T"))
        return min(_sessions.measure_frame_cost(app, frames=6) for _ in range(2))

    base = min(_sessions.measure_frame_cost(App(LabModel, [], sim=SimConfig(fps=60.0), meta=AppMeta(title="T")), frames=6)
               for _ in range(2))
    as_label = cost_with(Label(Dynamic(lambda m: (costly(m), "x")[1], "x"), where="t:1:1"), 60.0) - base
    as_image = cost_with(Image(Dynamic(costly, "img"), "camera", where="t:1:1"), 60.0) - base
    assert as_label == pytest.approx(0.004, rel=0.25)
    assert as_image == pytest.approx(0.004 * IMAGE_RATE / 60.0, rel=0.3)
