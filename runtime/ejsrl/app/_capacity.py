"""How many sessions of a lab fit on this machine: the default ``--max-sessions``.

:func:`measure_frame_cost` plays the lab for a few frames and takes the CPU time of one
display frame as a served tab's frame takes it (the steps, the world, and its view's own
work: reading, diffing and queueing what it shows); :func:`default_max_sessions`
turns it into places, calibrated by ``bench/classroom.py`` (the constants below say what it
measured). :mod:`ejsrl.app._sessions` re-exports both.
"""

from __future__ import annotations

import math
import os
import time
from typing import Any

__all__ = ["CPU_SHARE", "MAX_DEFAULT_SESSIONS", "SEND_SECONDS", "UNMEASURED_SESSIONS", "VIEW_FACTOR", "default_max_sessions", "measure_frame_cost"]

#: the share of the machine's cores that sessions may use when the default limit is derived
CPU_SHARE = 0.8
#: CPU seconds a served tab's frame costs beyond what :func:`measure_frame_cost` measures,
#: whatever the lab: viser's event loop serialising, compressing and sending it, and the
#: sessions' threads taking turns for the GIL. ``bench/classroom.py`` (issue #30, load 22, CPU
#: of the whole server per frame sent): pendulum 0.63 ms served for 0.34 ms measured, visual
#: servoing 6.2 for 5.0; the six-axis arm 0.91 for 1.43 (its measured first two seconds of
#: play cost more than the eight the bench serves)
SEND_SECONDS = 0.0004
#: what a session costs while served over what :func:`measure_frame_cost` measures (which
#: already includes its view's own work): a heavier frame costs a little more served (the
#: sessions' threads share caches and the GIL). ``bench/classroom.py`` at load 6-9: visual
#: servoing 4.4-5.3 ms served for 4.7-5.1 measured; 8 held, 10 at 28 frames/s but 0.94 of real
#: time, and with 1.0 its default was 10; the six-axis arm 0.68-0.78 for 0.72-0.85 (40 held,
#: default 44), the pendulum 0.54-0.56 for 0.25 (60 held at load 6.7, 80 at 24.4 frames/s;
#: default 78). At load 3.7-5.5 later: pendulum 80, six-axis 48 and servoing 10 held (defaults
#: 80-84, 42 and 8: the default errs on the side of full rate)
VIEW_FACTOR = 1.1
MAX_DEFAULT_SESSIONS = 100
#: the places a process offers when its lab could not be measured (the template's ``init:``
#: did not end in time: see ``ejsrl.app.cli``); ``--max-sessions`` sets them
UNMEASURED_SESSIONS = 8


def measure_frame_cost(app: Any, frames: int = 60) -> float:
    """CPU seconds one display frame of ``app`` takes while playing, as a served tab's frame
    takes them: the steps, the world, and the view's own per-frame work (reading every value
    it shows, diffing the panel, plots, images and 3D scene, and queueing viser's messages),
    each part at the rate the view runs it (plots ``max_rate`` a second, images ``IMAGE_RATE``).

    The view is a real one (:class:`ejsrl.view.viser_view.ViserView`) on a private viser server
    on loopback that no tab connects to (so nothing is serialised or sent: :data:`SEND_SECONDS`
    counts that), stopped after; the process's CPU time (a camera's picture is drawn partly in Mesa's
    rasteriser threads). ``app`` is played for ``frames`` frames after :data:`WARM_SECONDS` of
    unmeasured ones, back to back as a busy server runs frames, on a clock that moves one frame period a
    frame (so the rates above, and a real-time lab's steps, are those of the lab's frame rate),
    then reset, its spec code's prints and alerts silenced (``quiet_prints``: a throw-away run,
    not a student's). Returns the mean over the frames: the plots' and images' pictures
    come every few frames."""
    from ejsrl.sim._console import quiet_prints

    with quiet_prints():
        return _frame_cost(app, frames)


#: seconds of the lab played before the measured frames: its first frames cost more than a
#: class's steady frames (the six-axis arm's first second 2.6 ms a frame, its second 1.8, then
#: 0.75-0.95: ``bench/classroom.py`` measures after two seconds of play, and a class plays for minutes)
WARM_SECONDS = 2.0


class _Beat:
    """A clock (seconds) that moves only when told: one frame period a measured frame."""

    def __init__(self, start: float) -> None:
        self.now = start

    def __call__(self) -> float:
        return self.now


def _frame_cost(app: Any, frames: int) -> float:
    import contextlib
    import io

    from ejsrl.view._plots import IMAGE_SETTLE
    from ejsrl.view.viser_view import ViserView, make_server

    server, _url = make_server("127.0.0.1", 0, banner=False)
    views, clock = list(app.views), app.clock
    period = 1.0 / max(float(app.sim.fps), 1.0)
    beat = _Beat(clock())
    costs: list[float] = []
    try:
        app.clock = beat
        view = ViserView(app, server)  # its panel, plots and images read the beat too
        app.views = [view]
        beat.now += IMAGE_SETTLE  # images are shown (and read) from then on when no page says it is laid out
        app.play()
        warm = max(4, min(240, round(WARM_SECONDS / period)))
        for k in range(warm + frames):
            start = time.process_time()  # the process's: Mesa's rasteriser threads draw a camera's picture
            app.frame()
            if k >= warm:
                costs.append(time.process_time() - start)
            beat.now += period
        view.close()
    finally:
        app.views = views
        app.clock = clock
        app.reset()
        with contextlib.redirect_stdout(io.StringIO()):  # viser's "Server stopped"
            server.stop()
    return sum(costs) / len(costs) if costs else 0.0


def default_max_sessions(frame_cost: float, fps: float, cpus: float | None = None) -> int:
    """How many sessions playing at ``fps`` frames of ``frame_cost`` CPU seconds fit in
    :data:`CPU_SHARE` of ``cpus`` cores (one process: one core, the GIL), each frame
    costing ``frame_cost`` times :data:`VIEW_FACTOR` plus :data:`SEND_SECONDS`; between 2
    and :data:`MAX_DEFAULT_SESSIONS`."""
    n = cpus if cpus is not None else (os.cpu_count() or 1)
    per_session = (max(frame_cost, 1e-4) * VIEW_FACTOR + SEND_SECONDS) * max(float(fps), 1.0)
    return int(min(MAX_DEFAULT_SESSIONS, max(2, math.floor(n * CPU_SHARE / per_session))))
