"""The points a plot keeps from frame to frame.

Two kinds of history, both fed one point per display frame:

- :class:`PlotBuffer`, the strip chart of a plot's series that have no ``x`` of their own:
  one x (the plot's ``x``, usually the time) and one y per series, trimmed to the plot's
  ``window`` (x-span) and ``max_points``. The same x again replaces the last point (the lab
  is paused and a slider moved); an x that goes back starts the chart over (a reset, or
  the user set the time back) -- unless the model's clock (its independent variable)
  advanced since the last point: then x is a quantity that turns (a phase plot
  ``x: theta``) and the point is added, so the whole orbit is kept.
- :class:`TraceBuffer`, the x-y history of one series with an ``x`` of its own (a phase
  orbit), with its own ``max_points``: a point is added when the model's clock advanced,
  replaces the last one when it did not (paused: the trace's head follows a slider), and
  the trace starts over when the clock goes back.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["PlotBuffer", "TraceBuffer"]


class PlotBuffer:
    """The points of a strip chart: x (n,) and one y (n,) per series, trimmed to window and max_points."""

    def __init__(self, n_series: int, *, window: float | None = None, max_points: int = 2000) -> None:
        self.n_series = n_series
        self.window = window
        self.max_points = max(2, int(max_points))
        cap = self.max_points * 2
        self._x = np.empty(cap)
        self._y = np.empty((n_series, cap))
        self._start = 0
        self._end = 0
        #: the model's clock at the last point (None: the model has none)
        self._clock: float | None = None
        #: whether x has ever gone back while the clock advanced (then x is not monotonic)
        self.turns = False
        self.rev = 0

    def __len__(self) -> int:
        return self._end - self._start

    def clear(self) -> None:
        """Forget every point."""
        self._start = self._end = 0
        self._clock = None
        self.turns = False
        self.rev += 1

    def append(self, x: float, ys: list[float], clock: float | None = None) -> bool:
        """Add one point at the model's ``clock`` (None: it has none); returns False (and adds
        nothing) if any value is not finite."""
        if not math.isfinite(x) or not all(math.isfinite(y) for y in ys):
            return False
        last_clock, self._clock = self._clock, clock
        if clock is not None and last_clock is not None and clock < last_clock:
            self.clear()  # the clock went back: a reset, or the user set the time
            self._clock = clock
        if len(self) and x == self._x[self._end - 1]:
            # the same instant again (paused, or a value changed from the panel): replace it
            last = self._end - 1
            if self._y[:, last].tolist() == list(ys):
                return True
            self._y[:, last] = ys
            self.rev += 1
            return True
        if len(self) and x < self._x[self._end - 1]:
            if clock is not None and last_clock is not None and clock > last_clock:
                self.turns = True  # x turned while time went on: a curve, keep it whole
            else:
                self.clear()  # x went back with the clock standing: start over
                self._clock = clock
        if self._end == len(self._x):
            n = len(self)
            self._x[:n] = self._x[self._start : self._end]
            self._y[:, :n] = self._y[:, self._start : self._end]
            self._start, self._end = 0, n
        self._x[self._end] = x
        self._y[:, self._end] = ys
        self._end += 1
        if len(self) > self.max_points:
            self._start = self._end - self.max_points
        if self.window is not None and not self.turns:
            # x only grows: the points that left the window are the first few, usually one
            lo = x - self.window
            xs = self._x
            while xs[self._start] < lo:
                self._start += 1
        self.rev += 1
        return True

    def data(self) -> tuple[np.ndarray, ...]:
        """``(x, y_0, y_1, ...)`` as fresh float64 arrays."""
        s, e = self._start, self._end
        return (self._x[s:e].copy(), *(self._y[i, s:e].copy() for i in range(self.n_series)))


class TraceBuffer:
    """The last ``max_points`` (x, y) points of one series, in the order they came."""

    def __init__(self, max_points: int = 2000) -> None:
        self.max_points = max(2, int(max_points))
        self._xy = np.empty((self.max_points * 2, 2))
        self._start = 0
        self._end = 0
        self._clock: float | None = None
        self.rev = 0

    def __len__(self) -> int:
        return self._end - self._start

    def clear(self) -> None:
        """Forget every point."""
        self._start = self._end = 0
        self._clock = None
        self.rev += 1

    def append(self, x: float, y: float, clock: float | None = None) -> bool:
        """Add ``(x, y)`` at the model's ``clock`` (None: it has none; then a point equal to
        the last is not added again); False (nothing added) if a value is not finite."""
        if not (math.isfinite(x) and math.isfinite(y)):
            return False
        last_clock, self._clock = self._clock, clock
        if clock is not None and last_clock is not None and clock < last_clock:
            self.clear()
            self._clock = clock
        if len(self):
            last = self._end - 1
            same_time = clock is not None and last_clock is not None and clock == last_clock
            if same_time or (clock is None and self._xy[last, 0] == x and self._xy[last, 1] == y):
                if self._xy[last, 0] != x or self._xy[last, 1] != y:
                    self._xy[last] = (x, y)
                    self.rev += 1
                return True
        if self._end == len(self._xy):
            n = len(self)
            self._xy[:n] = self._xy[self._start : self._end]
            self._start, self._end = 0, n
        self._xy[self._end] = (x, y)
        self._end += 1
        if len(self) > self.max_points:
            self._start = self._end - self.max_points
        self.rev += 1
        return True

    def data(self) -> np.ndarray:
        """The points, (n, 2) float64 (a fresh array)."""
        return self._xy[self._start : self._end].copy()
