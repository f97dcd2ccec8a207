"""ODE integration for the ``ode`` pages of a model: every method of the language, events.

:class:`OdeIntegrator` advances a state ``y`` (float64, shape (n,)) by exactly one
simulation step ``h`` per call of :meth:`OdeIntegrator.step`:

- fixed-step methods (``euler``, ``euler_richardson``, ``rk4``) take one step of size h;
- adaptive explicit methods take internal steps with error control (absolute and relative
  tolerance ``tolerance``) and land exactly on ``t + h``, remembering the step size;
- implicit methods (``radau``, ``bdf``) keep a SciPy solver running across calls and
  read the state at ``t + h`` from its dense output.

Events (:class:`EventDef`) are located on the method's own trajectory, their action runs
at the located time (coinciding crossings fire together, once each, in list order), and
the method restarts from the new state. Arrays passed in are
never written to; every array returned is new, and is never modified afterwards.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from ._events import EventDef, EventTracker, Hit, ZenoError
from ._explicit import AdaptiveRK, make_fixed_step, rk_trial
from ._implicit import ImplicitStepper
from ._tableaus import TABLEAUS

__all__ = [
    "METHODS",
    "FIXED_STEP",
    "ADAPTIVE",
    "IMPLICIT",
    "EventDef",
    "SimulationStop",
    "ZenoError",
    "StepResult",
    "OdeIntegrator",
]

METHODS: tuple[str, ...] = (
    "euler",
    "euler_richardson",
    "rk4",
    "bogacki_shampine",
    "cash_karp",
    "fehlberg",
    "dopri5",
    "dop853",
    "radau",
    "bdf",
)
"""Every ``method`` an ``ode`` page may name."""
FIXED_STEP = {"euler", "euler_richardson", "rk4"}
"""Explicit methods that take exactly one step of size h."""
ADAPTIVE = {"bogacki_shampine", "cash_karp", "fehlberg", "dopri5", "dop853"}
"""Explicit embedded pairs with error control."""
IMPLICIT = {"radau", "bdf"}
"""Implicit methods for stiff models (SciPy)."""


class SimulationStop(Exception):
    """Raised to stop the simulation from inside the model (used by the run loop)."""


@dataclass(slots=True)
class StepResult:
    """Outcome of one :meth:`OdeIntegrator.step`."""

    t: float
    """Time reached: ``t + h``, or the event time if a ``stop`` event fired."""
    y: np.ndarray
    """(n,) state at ``t`` (a new array)."""
    fired: list[tuple[str, float]]
    """``(event name, time)`` of the events that fired, in time order."""
    stop: bool
    """An event with ``stop=True`` fired; ``t`` is its time."""


class OdeIntegrator:
    """Advance ``dy/dt = rates(t, y)`` one simulation step at a time.

    Args:
        rates: ``f(t, y) -> dy/dt``, (n,) -> (n,). Exceptions propagate unchanged.
        method: one of :data:`METHODS`.
        tolerance: absolute and relative tolerance of the adaptive and implicit methods.
        max_step: largest internal step of the adaptive and implicit methods (None: no
            limit). Fixed-step methods always take one step of size h.
        events: zero-crossing events checked during every step.
    """

    def __init__(
        self,
        rates: Callable[[float, np.ndarray], np.ndarray],
        method: str = "rk4",
        *,
        tolerance: float = 1e-6,
        max_step: float | None = None,
        events: Sequence[EventDef] = (),
    ) -> None:
        if method not in METHODS:
            close = difflib.get_close_matches(str(method), METHODS, n=1)
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise ValueError(f"unknown ODE method {method!r}; {hint}choose one of: {', '.join(METHODS)}")
        if not (isinstance(tolerance, (int, float)) and tolerance > 0 and math.isfinite(tolerance)):
            raise ValueError(f"tolerance must be a positive number, not {tolerance!r}")
        if max_step is not None and not max_step > 0:
            raise ValueError(f"max_step must be positive, not {max_step!r}")
        self.rates = rates
        self.method = method
        self.tolerance = float(tolerance)
        self.max_step = math.inf if max_step is None else float(max_step)
        self.events = tuple(events)
        self._tracker = EventTracker(self.events) if self.events else None
        self._last: tuple[float, np.ndarray] | None = None
        self._k_last: np.ndarray | None = None
        if method in FIXED_STEP:
            self._fixed = make_fixed_step(TABLEAUS[method])
            self._impl = self._step_fixed if self._tracker is None else self._step_fixed_events
        elif method in ADAPTIVE:
            self._tableau = TABLEAUS[method]
            self._rk = AdaptiveRK(
                rates, self._tableau, atol=self.tolerance, rtol=self.tolerance, max_step=self.max_step
            )
            self._impl = self._step_adaptive
        else:
            self._imp = ImplicitStepper(
                rates, method, atol=self.tolerance, rtol=self.tolerance, max_step=self.max_step
            )
            self._impl = self._step_implicit

    # -- public -------------------------------------------------------------------------

    def step(self, t: float, y: np.ndarray, h: float, t_end: float | None = None) -> StepResult:
        """Advance from (t, y) by exactly h (or to the time of a ``stop`` event).

        ``t_end``: the time the step reaches, if the caller knows it better than ``t + h``
        (a page counting its steps gives ``t0 + n * h``, free of the round-off that adding
        h step after step accumulates); it must be ``t + h`` up to round-off. Fixed-step
        methods still take a step of exactly h. Raises :class:`ZenoError` if an event fires
        more than 100 times in this step.
        """
        return self._impl(t, y, h, t + h if t_end is None else t_end)

    def reset(self) -> None:
        """Forget all memory (step size, FSAL stage, implicit solver, event state).

        Call it when the state was changed from outside (the view, an action).
        """
        self._last = None
        self._k_last = None
        if self.method in ADAPTIVE:
            self._rk.reset()
        elif self.method in IMPLICIT:
            self._imp.reset()

    # -- helpers ------------------------------------------------------------------------

    def _continues(self, t: float, y: np.ndarray) -> bool:
        """Whether (t, y) is exactly what the previous call returned."""
        last = self._last
        return last is not None and t == last[0] and np.array_equal(y, last[1])

    def _finish(
        self, t: float, y: np.ndarray, fired: list[tuple[str, float]], stop: bool, k: np.ndarray | None = None
    ) -> StepResult:
        self._last = (t, y.copy())
        self._k_last = k
        return StepResult(t, y, fired, stop)

    def _record(self, hits: Sequence[Hit], fired: list[tuple[str, float]]) -> bool:
        """Add the events that just fired to ``fired``; True if one of them stops the simulation."""
        stop = False
        for hit in hits:
            ev = self.events[hit.index]
            fired.append((ev.name, hit.t))
            stop = stop or ev.stop
        return stop

    def _check_h(self, h: float) -> None:
        if not h >= 0:
            raise ValueError(
                f"the step of method {self.method!r} must be positive, not {h!r}"
                + (" (events need a forward step)" if self._tracker is not None else "")
            )

    # -- fixed step ---------------------------------------------------------------------

    def _step_fixed(self, t: float, y: np.ndarray, h: float, t_end: float) -> StepResult:
        return StepResult(t_end, self._fixed(self.rates, t, y, h, None), [], False)

    def _step_fixed_events(self, t: float, y: np.ndarray, h: float, t_end: float) -> StepResult:
        self._check_h(h)
        y = np.asarray(y, dtype=float)
        tr = self._tracker
        if not self._continues(t, y):
            tr.start(t, y)
        tr.new_call()
        f = self.rates
        step = self._fixed
        t_start = t
        fired: list[tuple[str, float]] = []
        while t < t_end:
            k0 = f(t, y)
            y1 = step(f, t, y, h if t == t_start else t_end - t, k0)

            def state_at(x: float, t0: float = t, y0: np.ndarray = y, k0: np.ndarray = k0) -> np.ndarray:
                return step(f, t0, y0, x - t0, k0)

            hits = tr.check(t, y, t_end, y1, state_at)
            if not hits:
                t, y = t_end, y1
                break
            y = tr.fire(hits, f, t_end - t)
            t = hits[0].t
            if self._record(hits, fired):
                return self._finish(t, y, fired, True)
        return self._finish(t_end, y if h else y.copy(), fired, False)

    # -- adaptive explicit --------------------------------------------------------------

    def _step_adaptive(self, t: float, y: np.ndarray, h: float, t_end: float) -> StepResult:
        self._check_h(h)
        y = np.asarray(y, dtype=float)
        cont = self._continues(t, y)
        k = self._k_last if cont else None
        tr = self._tracker
        if tr is not None:
            if not cont:
                tr.start(t, y)
            tr.new_call()
        f = self.rates
        rk = self._rk
        tab = self._tableau
        fired: list[tuple[str, float]] = []
        if h == 0:
            return self._finish(t, y.copy(), fired, False, k)
        while t < t_end:
            if k is None:
                k = f(t, y)
            t1, y1, k1 = rk.advance(t, y, k, t_end)
            if tr is not None:

                def state_at(x: float, t0: float = t, y0: np.ndarray = y, k0: np.ndarray = k) -> np.ndarray:
                    return rk_trial(f, tab, t0, y0, x - t0, k0)[0]

                hits = tr.check(t, y, t1, y1, state_at)
                if hits:
                    y = tr.fire(hits, f, t1 - t)
                    t = hits[0].t
                    rk.reset()
                    k = None
                    if self._record(hits, fired):
                        return self._finish(t, y, fired, True)
                    continue
            t, y, k = t1, y1, k1
        return self._finish(t_end, y, fired, False, k)

    # -- implicit -----------------------------------------------------------------------

    def _step_implicit(self, t: float, y: np.ndarray, h: float, t_end: float) -> StepResult:
        self._check_h(h)
        y = np.asarray(y, dtype=float)
        imp = self._imp
        tr = self._tracker
        if not (imp.running and self._continues(t, y)):
            imp.restart(t, y)
            if tr is not None:
                tr.start(t, y)
        if tr is not None:
            tr.new_call()
        f = self.rates
        fired: list[tuple[str, float]] = []
        if h == 0:
            return self._finish(t, y.copy(), fired, False)
        while t < t_end:
            t1, y1 = imp.advance(t, t_end)
            if tr is not None:
                hits = tr.check(t, y, t1, y1, imp.state_at)
                if hits:
                    y = tr.fire(hits, f, t1 - t)
                    t = hits[0].t
                    imp.restart(t, y)
                    if self._record(hits, fired):
                        return self._finish(t, y, fired, True)
                    continue
            t, y = t1, y1
        return self._finish(t_end, y, fired, False)
