"""How many sessions of a lab fit on this machine: the default ``--max-sessions``.

:func:`measure_frame_cost` plays the lab for a few frames and takes the CPU time of one
display frame (the steps, the world, every value its view shows); :func:`default_max_sessions`
turns it into places, calibrated by ``bench/classroom.py`` (the constants below say what it
measured). :mod:`ejsrl.app._sessions` re-exports both.
"""

from __future__ import annotations

import math
import os
import time
from typing import Any

__all__ = ["CPU_SHARE", "MAX_DEFAULT_SESSIONS", "SEND_SECONDS", "VIEW_FACTOR", "default_max_sessions", "measure_frame_cost"]

#: the share of the machine's cores that sessions may use when the default limit is derived
CPU_SHARE = 0.8
#: CPU seconds viser's event loop spends on a tab's frame whatever the lab (serialising,
#: compressing, sending): ``bench/classroom.py`` measured 0.6 ms a frame in all for the
#: pendulum, whose frame alone takes 0.2-0.35 ms; without it the pendulum's default was
#: 100 places a process where 40 held
SEND_SECONDS = 0.0004
#: what a session costs while served over what :func:`measure_frame_cost` measures (which
#: already reads every value its view shows): ``bench/classroom.py`` measured 1.4 ms a frame
#: served for the six-axis arm (1.95 ms measured), 3.6-4.2 ms for visual servoing (3.4-4.1)
#: and 0.3 ms for the pendulum (0.3). With 1.5 the six-axis arm's default was 16 places where
#: 24 held.
VIEW_FACTOR = 1.0
MAX_DEFAULT_SESSIONS = 100


def measure_frame_cost(app: Any, frames: int = 12) -> float:
    """CPU seconds one display frame of ``app`` takes while playing: the steps, the world,
    and every value its view shows (plots, images, labels, controls), images counted at
    the rate the view reads them (``IMAGE_RATE`` of ``ejsrl.view._plots``). ``app`` is
    played for ``frames`` frames at its frame rate, then reset, its spec code's prints and
    alerts silenced (``quiet_prints``: a throw-away run, not a student's)."""
    from ejsrl.sim._console import quiet_prints

    with quiet_prints():
        return _frame_cost(app, frames)


def _frame_cost(app: Any, frames: int) -> float:
    from ejsrl.view._plots import IMAGE_RATE
    from ejsrl.view.elements import Control, Dynamic, Folder, Image, Label, Plot, Tabs

    props: list[tuple[Any, str]] = []
    pictures: list[tuple[Any, str]] = []

    def walk(elements: list[Any]) -> None:
        for el in elements:
            if isinstance(el, Folder):
                walk(el.children)
            elif isinstance(el, Tabs):
                for _label, children in el.tabs:
                    walk(children)
            elif isinstance(el, Plot):
                props.append((el.x, el.where))
                props.extend((s.y, s.where or el.where) for s in el.series)
            elif isinstance(el, Image):
                pictures.append((el.source, el.where))
                if el.points is not None:
                    pictures.append((el.points, el.where))
            elif isinstance(el, Label):
                props.append((el.text, el.where))
            elif isinstance(el, Control):
                props.append((Dynamic(el.get, el.bind), el.where))

    walk(list(app.view or []))
    period = 1.0 / max(float(app.sim.fps), 1.0)
    picture_share = min(1.0, IMAGE_RATE * period)
    costs: list[float] = []
    app.play()
    try:
        for _ in range(frames):
            start = time.thread_time()
            app.frame()
            with app.lock:
                for prop, where in props:
                    app.safe_value(prop, where)
                middle = time.thread_time()
                for prop, where in pictures:
                    app.safe_value(prop, where)
            end = time.thread_time()
            costs.append(middle - start + (end - middle) * picture_share)
            time.sleep(period)
    finally:
        app.reset()
    costs.sort()
    return costs[len(costs) // 2] if costs else 0.0


def default_max_sessions(frame_cost: float, fps: float, cpus: float | None = None) -> int:
    """How many sessions playing at ``fps`` frames of ``frame_cost`` CPU seconds fit in
    :data:`CPU_SHARE` of ``cpus`` cores (one process: one core, the GIL), each frame
    costing ``frame_cost`` times :data:`VIEW_FACTOR` plus :data:`SEND_SECONDS`; between 2
    and :data:`MAX_DEFAULT_SESSIONS`."""
    n = cpus if cpus is not None else (os.cpu_count() or 1)
    per_session = (max(frame_cost, 1e-4) * VIEW_FACTOR + SEND_SECONDS) * max(float(fps), 1.0)
    return int(min(MAX_DEFAULT_SESSIONS, max(2, math.floor(n * CPU_SHARE / per_session))))
