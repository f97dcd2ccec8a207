"""Say where spec code is when it runs much longer than it should (an ``init:`` that never ends).

An endless ``init:`` used to leave ``--headless`` and a served app silent (the front of a
served lab waited 180 s for its processes) with no word of the spec line. ``watch_slow``
runs a block of user code and, if it is still running after ``SLOW_SECONDS``, prints once
where it is in the spec:

    lab.ejs.yaml:12:5: warning: init: has been running for 3 s and is at this line now (an endless loop?); Ctrl+C stops it

The place is read from the running thread's stack (``sys._current_frames``): the deepest
frame in the app's module whose line ``SPEC_LINES`` maps to the spec.
"""

from __future__ import annotations

import os
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TextIO

__all__ = ["SLOW_SECONDS", "watch_slow", "where_now"]

SLOW_SECONDS = float(os.environ.get("EJSRL_SLOW_SECONDS", "3"))
"""Seconds of running before ``watch_slow`` speaks (``EJSRL_SLOW_SECONDS`` overrides)."""


def where_now(thread_id: int, model_cls: type) -> str:
    """The spec location ``file:line:col`` the thread ``thread_id`` is running now ('' if none)."""
    frame = sys._current_frames().get(thread_id)
    module = sys.modules.get(model_cls.__module__)
    app_file = getattr(module, "__file__", None)
    lines: dict[int, tuple[int, int]] = getattr(model_cls, "SPEC_LINES", {})
    spec = getattr(model_cls, "SPEC", "") or getattr(getattr(module, "META", None), "spec", "")
    while frame is not None:  # innermost first: the first frame of app.py is the deepest
        if app_file is not None and frame.f_code.co_filename == app_file and frame.f_lineno in lines:
            line, col = lines[frame.f_lineno]
            return f"{spec}:{line}:{col}"
        frame = frame.f_back
    return ""


@contextmanager
def watch_slow(model_cls: type, what: str = "init:", *, after: float | None = None, log: TextIO | None = None) -> Iterator[None]:
    """Run the block; if it runs longer than ``after`` seconds, print once where it is.

    ``what``: the code's name in the message (``init:``); ``log``: where (standard error).
    """
    after = SLOW_SECONDS if after is None else after
    thread_id = threading.get_ident()
    done = threading.Event()

    def watch() -> None:
        if done.wait(after):
            return
        where = where_now(thread_id, model_cls)
        text = f"{what} has been running for {after:g} s" + (" and is at this line now" if where else "")
        print(f"{where + ': ' if where else ''}warning: {text} (an endless loop?); Ctrl+C stops it",
              file=log or sys.stderr, flush=True)

    watcher = threading.Thread(target=watch, name="ejsrl-slow-watch", daemon=True)
    watcher.start()
    try:
        yield
    finally:
        done.set()
