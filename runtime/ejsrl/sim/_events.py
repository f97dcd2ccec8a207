"""Zero-crossing events: detection over a step, location in time, firing, Zeno guard.

An event fires when its function ``g(t, y)`` crosses zero in its direction during a
step. Signs are compared at the ends of each internal step of the integrator; a start at
exactly zero never counts as a crossing. The crossing is located on the integrator's own
trajectory (a callable ``state_at(t)``) by a bracketing Illinois/bisection search to
``1e-12 * (1 + |t|)``; the state on the side of the root *before* the crossing is passed
to the action.

After an action the event's sign is re-read at the new state. If the trajectory is still
heading through zero (the action did not turn it back, e.g. it only counted or slowed
the motion), the crossing that was just handled would be seen again a hair later; the
event is therefore disarmed until ``g`` has reached the other side. If the action turned
the motion back (a bounce), the event stays armed and the next crossing counts.

Events whose crossings coincide (within the time tolerance; typically several events on
the same ``when`` with different directions) fire together, once each, in list order,
whatever the earlier actions did to the state: a ``down`` bounce and a ``both`` counter
on the ball's height both fire at every impact.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, NamedTuple, Sequence

import numpy as np

__all__ = ["EventDef", "ZenoError", "EventTracker", "Hit", "MAX_FIRINGS"]

MAX_FIRINGS = 100
"""An event firing more often than this within one call of ``step`` is Zeno behaviour."""


@dataclass
class EventDef:
    """One event of an ``ode`` page."""

    name: str
    """Name from the spec (used in messages and in ``StepResult.fired``)."""
    when: Callable[[float, np.ndarray], float]
    """``g(t, y)``: the event fires when this crosses zero."""
    direction: int
    """+1 up (negative to positive), -1 down (positive to negative), 0 both."""
    action: Callable[[float, np.ndarray], "np.ndarray | None"]
    """Runs the user's action at the located ``(t, y)``; returns the new state or None."""
    stop: bool = False
    """Pause the simulation after the action (``step`` returns at the event time)."""
    after: bool = False
    """The action gets the time and state just *past* the crossing (the right end of the
    final bracket, where ``g`` has changed sign), as CVode's roots are: an FMU's event
    indicators are checked so (FMI). The step still restarts from the located time."""


class ZenoError(RuntimeError):
    """An event fired more than ``MAX_FIRINGS`` times within one step (or again at the
    very same instant, which would repeat forever)."""


class Hit(NamedTuple):
    """A located crossing."""

    index: int
    """Index of the event."""
    t: float
    """Time on the side of the root before the crossing."""
    y: np.ndarray
    """State at ``t``."""
    pre: int
    """Sign of g before the crossing (+1 or -1)."""
    t_after: float | None = None
    """Time just past the crossing (the bracket's right end, within the tolerance of ``t``)."""
    y_after: np.ndarray | None = None
    """State at ``t_after``."""


def _sign(x: float) -> int:
    return (x > 0) - (x < 0)


def locate(
    g_at: Callable[[float], tuple[float, np.ndarray]],
    t0: float,
    g0: float,
    y0: np.ndarray,
    t1: float,
    g1: float,
    tol: float,
    y1: np.ndarray | None = None,
) -> tuple[float, np.ndarray, float, np.ndarray | None]:
    """Bracket the root of g on [t0, t1] to width ``tol``; g0 != 0, g1 == 0 or opposite sign.

    Illinois (modified regula falsi) steps, with a bisection whenever a step did not halve
    the bracket. Returns the left end of the final bracket and its state (still strictly
    on g0's side), and the right end and its state (past the root; ``y1`` if never moved).
    """
    a, ga, ya, b, gb, yb = t0, g0, y0, t1, g1, y1
    pre = _sign(g0)
    side = 0
    bisect = False
    while b - a > tol:
        width = b - a
        if bisect or gb == ga:
            x = 0.5 * (a + b)
        else:
            x = b - gb * (b - a) / (gb - ga)
        x = min(max(x, a + 0.25 * tol), b - 0.25 * tol)
        gx, yx = g_at(x)
        if _sign(gx) == pre:
            a, ga, ya = x, gx, yx
            if side == -1:
                gb *= 0.5
            side = -1
        else:
            b, gb, yb = x, gx, yx
            if side == 1:
                ga *= 0.5
            side = 1
        bisect = (b - a) > 0.5 * width
    return a, ya, b, yb


class EventTracker:
    """The crossing state of every event along one trajectory."""

    def __init__(self, events: Sequence[EventDef]) -> None:
        for ev in events:
            if ev.direction not in (-1, 0, 1):
                raise ValueError(f"event {ev.name!r}: direction must be +1, -1 or 0, not {ev.direction!r}")
        self.events = tuple(events)
        n = len(self.events)
        self.g = [0.0] * n
        """g of every event at the current position."""
        self.armed = [True] * n
        """False while an event waits for g to reach the far side of a handled crossing."""
        self.waiting_for = [0] * n
        """Sign a disarmed event waits for."""
        self.count = [0] * n
        """Firings within the current call of ``step``."""
        self.last_time: list[float | None] = [None] * n
        """Time of the last firing within the current call of ``step``."""

    def start(self, t: float, y: np.ndarray) -> None:
        """Begin a fresh trajectory at (t, y): every event armed, g read there."""
        for i, ev in enumerate(self.events):
            self.g[i] = float(ev.when(t, y))
            self.armed[i] = True

    def new_call(self) -> None:
        """Reset the per-step Zeno counters."""
        n = len(self.events)
        self.count = [0] * n
        self.last_time = [None] * n

    def check(
        self,
        t0: float,
        y0: np.ndarray,
        t1: float,
        y1: np.ndarray,
        state_at: Callable[[float], np.ndarray],
    ) -> list[Hit]:
        """Look for crossings over the internal step (t0, y0) -> (t1, y1).

        Returns the earliest located crossings without moving the tracker on: every event
        whose crossing lies within the time tolerance of the earliest one (events on the
        same ``when``, or crossings that coincide), in list order, each with the time and
        state of the earliest. Returns ``[]`` after moving the tracker to (t1, y1).
        """
        events = self.events
        g1 = [float(ev.when(t1, y1)) for ev in events]
        hits: list[Hit] = []
        tol = 1e-12 * (1.0 + abs(t0))
        for i, ev in enumerate(events):
            if not self.armed[i]:
                continue
            s0 = _sign(self.g[i])
            if s0 == 0 or _sign(g1[i]) == s0 or ev.direction == s0:
                continue
            when = ev.when

            def g_at(x: float, when: Callable[[float, np.ndarray], float] = when) -> tuple[float, np.ndarray]:
                yx = state_at(x)
                return float(when(x, yx)), yx

            a, ya, b, yb = locate(g_at, t0, self.g[i], y0, t1, g1[i], tol, y1)
            hits.append(Hit(i, float(a), ya, s0, float(b), yb))
        if hits:
            first = min(hits, key=lambda h: (h.t, h.index))
            return [
                Hit(h.index, first.t, first.y, h.pre, h.t_after, h.y_after) for h in hits if h.t <= first.t + tol
            ]  # hits are in list order already
        for i in range(len(events)):
            g = g1[i]
            if not self.armed[i]:
                s = _sign(g)
                if s == 0 or s == self.waiting_for[i]:
                    self.armed[i] = True
            self.g[i] = g
        return []

    def fire(self, hits: Sequence[Hit], rates: Callable[[float, np.ndarray], np.ndarray], scale: float) -> np.ndarray:
        """Run the actions of ``hits`` (one instant, from :meth:`check`) and restart the tracker.

        The actions run in list order, each on the state the previous one left. Each event
        fires once for its crossing: afterwards, an event that fired and whose motion still
        heads through zero (its action did not turn it back) waits until ``g`` reaches the
        far side; any other event whose ``g`` the actions changed is armed afresh.

        ``scale`` is a time scale of the integration (the step); it sets the probe used to
        tell whether the motion still heads through zero. Returns the new state. Raises
        :class:`ZenoError` on an event's 101st firing in one step, or when an event fires
        again at the very instant of its previous firing.
        """
        t, y = hits[0].t, hits[0].y
        y_new = y
        for hit in hits:
            i = hit.index
            ev = self.events[i]
            if self.last_time[i] == t:
                raise ZenoError(
                    f"event {ev.name!r} fired {self.count[i] + 1} times in one step, the last ones at the same "
                    f"instant t={t:.12g}: Zeno behaviour (e.g. a ball with restitution 0); "
                    "the simulation was stopped"
                )
            self.count[i] += 1
            if self.count[i] > MAX_FIRINGS:
                raise ZenoError(
                    f"event {ev.name!r} fired more than {MAX_FIRINGS} times in one step at t={t:.12g}: "
                    "Zeno behaviour (e.g. a ball with restitution 0); the simulation was stopped"
                )
            self.last_time[i] = t
            if ev.after and y_new is y and hit.y_after is not None:
                out = ev.action(hit.t_after, hit.y_after)
            else:
                out = ev.action(t, y_new)
            if out is not None:
                out = np.asarray(out, dtype=float)
                if out.shape != y.shape:
                    raise ValueError(
                        f"event {ev.name!r}: the action returned a state of shape {out.shape}, expected {y.shape}"
                    )
                y_new = out
        fired = {h.index: h.pre for h in hits}
        changed = y_new is not y and not np.array_equal(y_new, y)
        slope: np.ndarray | None = None
        for j, ev in enumerate(self.events):
            pre = fired.get(j)
            g_before = float(ev.when(t, y)) if pre is None and changed else None
            g = float(ev.when(t, y_new))  # read last, so a model's variables hold the new state
            self.g[j] = g
            if pre is None:
                if g_before is not None and g != g_before:
                    self.armed[j] = True
                continue
            self.armed[j] = True
            if _sign(g) == pre:
                # Still on the near side: does the motion head through zero (same crossing) or back?
                eps = 1e-6 * scale if scale > 0 else 1e-9
                eps = max(eps, 4.0 * np.spacing(abs(t) + 1.0))
                if slope is None:
                    slope = rates(t, y_new)
                probe = float(ev.when(t + eps, y_new + eps * slope))
                if _sign(probe - g) == -pre:
                    self.armed[j] = False
                    self.waiting_for[j] = -pre
        return y_new
