"""A session that the machine cannot step at full rate says so in its time readout, with the
measured rate; at full rate it says nothing."""

from __future__ import annotations

import pytest


def run_frames(served, seconds: float, fps: float) -> None:
    """Play ``seconds`` of the clock, a frame every 1/``fps`` s."""
    for _ in range(int(round(seconds * fps))):
        served.clock.advance(1.0 / fps)
        served.app.frame()


def readout(served) -> str:
    return served.view.panel.readout.content


def test_a_lab_stepped_at_half_its_frame_rate_says_it_runs_at_half_speed(served):
    served.app.play()
    run_frames(served, 2.5, 30.0)  # the lab asks for 30 frames/s: full speed
    assert "speed" not in readout(served) and served.app.speed == pytest.approx(1.0, abs=0.05)
    run_frames(served, 2.5, 15.0)  # the machine manages 15
    assert served.app.speed == pytest.approx(0.5, abs=0.05)
    assert "running at 50% speed (the server is busy)" in readout(served)
    run_frames(served, 2.5, 30.0)  # the class went home
    assert "speed" not in readout(served)
    served.app.pause()
    served.app.frame()
    assert "speed" not in readout(served)  # a paused lab is not slow


@pytest.mark.parametrize("served", [dict(realtime=True)], indirect=True)
def test_a_realtime_lab_that_falls_behind_shows_its_real_time_factor(served):
    served.app.play()
    # each step of 0.1 simulated s costs 0.06 s of the clock, and frames come 0.05 s apart:
    # a frame runs one step (its time is up after it), so 0.1 simulated s per 0.11 s
    model = served.app.model
    real_step = model._ejs_step

    def slow_step():
        served.clock.advance(0.06)
        return real_step()

    model._ejs_step = slow_step
    for _ in range(60):
        served.clock.advance(0.05)
        served.app.frame()
    speed = served.app.speed
    assert speed == pytest.approx(0.1 / 0.11, abs=0.03)
    assert f"running at {speed:.0%} of real time (the server is busy)" in readout(served)
