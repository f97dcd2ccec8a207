"""What a simulation's code prints, kept for its ``console`` view element.

Spec code's ``print(...)`` in a lab with a console is ``ModelBase.print``: it prints as
Python's ``print`` does (to the terminal; a headless run's standard output) and adds the
text to the :class:`ConsoleLog` of the model's controller, the app of one browser tab (a
session), so one tab's prints never show in another's. The log keeps the last
:data:`ConsoleLog.MAX_LINES` lines, each cut to :data:`ConsoleLog.MAX_LINE` characters.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any

__all__ = ["ConsoleLog", "console_log", "quiet_prints", "prints_quiet"]

_QUIET: ContextVar[bool] = ContextVar("ejsrl_quiet_prints", default=False)


@contextmanager
def quiet_prints() -> Iterator[None]:
    """Within it, in this thread, spec code's ``print()`` and ``alert()`` go nowhere: not
    to the terminal, not to a console, not to an alert. For throw-away runs nobody reads:
    the served lab's template app, and the start-up measurement of its cost (a lab printed
    its ``init`` line four times before "serving on"). Threads started within it print
    as usual (a new thread starts with the default context)."""
    token = _QUIET.set(True)
    try:
        yield
    finally:
        _QUIET.reset(token)


def prints_quiet() -> bool:
    """Whether this thread is inside :func:`quiet_prints`."""
    return _QUIET.get()


class ConsoleLog:
    """The lines a simulation printed, oldest first; bounded, thread-safe.

    ``revision`` grows by one with every change (a write or a clear), so a view redraws
    only when it differs from the one it showed.
    """

    #: lines kept (the oldest go first)
    MAX_LINES = 2000
    #: characters kept of one line (the rest is replaced by an ellipsis)
    MAX_LINE = 2000

    def __init__(self) -> None:
        self._lines: deque[str] = deque(maxlen=self.MAX_LINES)
        self._partial = ""  # printed with end="" and not yet ended
        self._lock = threading.Lock()
        self.revision = 0

    def write(self, text: str) -> None:
        """Add printed ``text`` (line breaks end lines; a last piece without one waits for more)."""
        if not text:
            return
        with self._lock:
            parts = text.replace("\r\n", "\n").split("\n")
            self._partial = _cut(self._partial + parts[0])
            for part in parts[1:]:
                self._lines.append(self._partial)
                self._partial = _cut(part)
            self.revision += 1

    def clear(self) -> None:
        """Forget every line (the console's Clear button)."""
        with self._lock:
            self._lines.clear()
            self._partial = ""
            self.revision += 1

    def lines(self, last: int | None = None) -> list[str]:
        """The ``last`` lines (all kept by default), a line still being printed included."""
        with self._lock:
            out = list(self._lines)
            if self._partial:
                out.append(self._partial)
        return out if last is None else out[-last:] if last > 0 else []


def _cut(line: str) -> str:
    limit = ConsoleLog.MAX_LINE
    return line if len(line) <= limit else line[: limit - 1] + "…"


_MAKE = threading.Lock()


def console_log(controller: Any) -> ConsoleLog:
    """The console log of ``controller`` (an app: one simulation, one browser tab), made on first use."""
    log = getattr(controller, "_ejs_console", None)
    if log is None:
        with _MAKE:
            log = getattr(controller, "_ejs_console", None)
            if log is None:
                log = ConsoleLog()
                controller._ejs_console = log
    return log
