"""A clock that moves only when a test says so, for the app's and the view's timers."""

from __future__ import annotations


class FakeClock:
    """``clock()`` returns ``now``; ``advance(dt)`` moves it forward (never back)."""

    def __init__(self, start: float = 1000.0) -> None:
        self.now = float(start)

    def __call__(self) -> float:
        return self.now

    def advance(self, dt: float) -> None:
        if dt < 0:
            raise ValueError("a clock does not go back")
        self.now += float(dt)
