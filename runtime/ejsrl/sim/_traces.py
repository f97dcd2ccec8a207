"""Requests from spec code to erase the traces of the drawing panels (``clear_trace``).

Spec code's ``clear_trace(name)`` (``ModelBase.clear_trace``) notes the request on the
model's controller, the app of one simulation (a browser tab), so that one tab's request
never erases another's traces; each drawing panel of that app (``ejsrl.view._drawing``)
compares the revision it last applied and starts the trace again from its point's next
position. A model without a view (a headless run, a sweep) has no panel: the request is
noted and nothing reads it.
"""

from __future__ import annotations

import difflib
import threading
from typing import Any

__all__ = ["TraceClears", "trace_clears"]


class TraceClears:
    """Revisions of erase requests: one for every trace (``clear_trace()``) and one per name.

    ``known``: the traces' names of the panels shown (None until a panel registers them),
    so that a wrong name is an error naming the traces there are.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.all = 0
        self.by_name: dict[str, int] = {}
        self.known: set[str] | None = None

    def register(self, names: Any) -> None:
        """A panel shows the traces ``names``."""
        with self._lock:
            self.known = (self.known or set()) | {str(n) for n in names}

    def request(self, name: str | None = None) -> None:
        """Erase the trace ``name`` (every trace when None). Raises ``ValueError`` for a name
        that is no trace of the panels shown (with the closest one)."""
        with self._lock:
            if name is None:
                self.all += 1
                return
            if not isinstance(name, str):
                raise ValueError(f"clear_trace() takes the name of a trace, a string, not {type(name).__name__}")
            if self.known is not None and name not in self.known:
                close = difflib.get_close_matches(name, sorted(self.known), n=1)
                hint = f"; did you mean {close[0]!r}?" if close else f" (the traces: {', '.join(sorted(self.known)) or 'none'})"
                raise ValueError(f"clear_trace({name!r}): no trace of that name{hint}")
            self.by_name[name] = self.by_name.get(name, 0) + 1

    def revision(self, name: str) -> int:
        """How many requests erased the trace ``name`` so far (those for every trace included)."""
        with self._lock:
            return self.all + self.by_name.get(name, 0)


_MAKE = threading.Lock()


def trace_clears(controller: Any) -> TraceClears:
    """The erase requests of ``controller`` (an app: one simulation), made on first use."""
    got = getattr(controller, "_ejs_trace_clears", None)
    if got is None:
        with _MAKE:
            got = getattr(controller, "_ejs_trace_clears", None)
            if got is None:
                got = TraceClears()
                try:
                    setattr(controller, "_ejs_trace_clears", got)
                except AttributeError:  # a controller that takes no attributes: requests go nowhere
                    pass
    return got
