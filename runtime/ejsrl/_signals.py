"""SIGINT and SIGTERM handled as a clean stop, for the ``ejsgen run`` launcher and built apps."""

from __future__ import annotations

import signal
import threading
from typing import Any

__all__ = ["STOP_SIGNALS", "SignalScope"]

#: the signals that ask a lab to stop (Ctrl+C in a terminal, ``kill`` or a service manager)
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class SignalScope:
    """A context in which :data:`STOP_SIGNALS` call :meth:`_handle`; the old handlers come back on exit.

    Handlers can only be set in the main thread; elsewhere the scope changes nothing.
    Subclasses say what a signal does by overriding :meth:`_handle`.
    """

    def __init__(self) -> None:
        self._old: dict[int, Any] = {}

    def __enter__(self) -> Any:
        if threading.current_thread() is threading.main_thread():
            for sig in STOP_SIGNALS:
                self._old[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, old in self._old.items():
            signal.signal(sig, old)
        self._old.clear()

    def _handle(self, signum: int, frame: object) -> None:  # pragma: no cover - overridden
        raise NotImplementedError
