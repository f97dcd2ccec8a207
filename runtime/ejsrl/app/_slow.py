"""Say where spec code is when it runs much longer than it should (an ``init:`` that never ends).

An endless ``init:`` used to leave ``--headless`` and a served app silent (the front of a
served lab waited 180 s for its processes) with no word of the spec line. ``watch_slow``
runs a block of user code and, if it is still running after ``SLOW_SECONDS``, prints once
where it is in the spec:

    lab.ejs.yaml:12:5: warning: init: has been running for 3 s and is at this line now (an endless loop?); Ctrl+C stops it

The place is read from the running thread's stack (``sys._current_frames``): the deepest
frame in the app's module whose line ``SPEC_LINES`` maps to the spec.

A served lab also says it in the page of the tab whose simulation is stuck (a new tab's
``init:``, or Reset after a student set a value that makes ``init:`` loop): the block's
``tell`` callables, and those :func:`telling` set for the running thread, are called with
the page's words (``TITLE`` and a body); each returns the notification handles it made
(objects with ``remove()``), which are removed when the block ends.
"""

from __future__ import annotations

import logging
import os
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import Any, TextIO

__all__ = ["SLOW_SECONDS", "TITLE", "Overran", "Tell", "run_within", "telling", "watch_slow", "where_now"]

log = logging.getLogger(__name__)

TITLE = "The simulation is still starting"
"""The title of the page's notification of a slow block."""

Tell = Callable[[str, str], "Iterable[Any] | None"]
"""``tell(title, body)``: show a slow block's warning in a page; returns the handles it made."""

_LOCAL = threading.local()


@contextmanager
def telling(tell: Tell) -> Iterator[None]:
    """While the block runs, every slow block of this thread also calls ``tell`` (a new tab's
    session tells its tab while its ``init:`` runs)."""
    stack: list[Tell] = _LOCAL.__dict__.setdefault("tells", [])
    stack.append(tell)
    try:
        yield
    finally:
        stack.remove(tell)

SLOW_SECONDS = float(os.environ.get("EJSRL_SLOW_SECONDS", "3"))
"""Seconds of running before ``watch_slow`` speaks (``EJSRL_SLOW_SECONDS`` overrides)."""


class Overran(BaseException):
    """Raised inside a block that :func:`run_within` gave up waiting for. A BaseException, so
    spec code's ``except Exception`` (and the app's error guard) lets it through; its
    traceback passes through the spec code it stopped, so it names that spec line."""


def run_within(fn: Callable[[], Any], seconds: float, *, name: str = "ejsrl-bounded") -> tuple[bool, Any]:
    """``(True, fn())`` if ``fn`` returns within ``seconds`` of wall time, run in a thread of
    its own (its exception is raised here); else ``(False, exc)``: :class:`Overran` was raised
    inside ``fn`` (a Python loop stops at once; a long call into C when it returns, waited
    for a further second at most) and ``exc`` is that exception if it came out in time, else
    None. For an ``init:`` that must not hold a server's start: a thread cannot be killed, so
    the endless one is stopped by an exception in its own code."""
    out: dict[str, Any] = {}

    def run() -> None:
        try:
            try:
                out["value"] = fn()
            except BaseException as exc:  # noqa: BLE001 - handed to the caller
                out["error"] = exc
        except Overran:  # it came just as fn returned
            pass

    thread = threading.Thread(target=run, name=name, daemon=True)
    thread.start()
    thread.join(seconds)
    if not thread.is_alive():
        if "error" in out and not isinstance(out["error"], Overran):
            raise out["error"]
        return "value" in out, out.get("value", out.get("error"))
    import ctypes

    assert thread.ident is not None
    ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(thread.ident), ctypes.py_object(Overran))
    thread.join(1.0)
    if "value" in out:  # it returned just then
        return True, out["value"]
    error = out.get("error")
    if error is not None and not isinstance(error, Overran):
        raise error
    return False, error


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


def importing(thread_id: int) -> bool:
    """Whether the thread ``thread_id`` is importing a module now (its stack is in importlib's)."""
    frame = sys._current_frames().get(thread_id)
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib"):
            return True
        frame = frame.f_back
    return False


def _waited(done: threading.Event, after: float, thread_id: int, tick: float = 0.1) -> bool:
    """Wait until the thread ``thread_id`` has run ``after`` seconds of its own code (True) or
    ``done`` is set (False). Time it spends importing modules does not count: a spec's first
    ``capture()`` imports trimesh and SciPy, seconds on a busy machine, and that is no
    endless loop. Sampled every ``tick`` seconds (a tick found importing counts as import)."""
    own, last = 0.0, time.monotonic()
    while own < after:
        if done.wait(tick):
            return False
        now = time.monotonic()
        if not importing(thread_id):
            own += now - last
        last = now
    return True


def page_text(what: str, after: float, where: str) -> str:
    """The page's words for a block ``what`` running ``after`` seconds, now at spec place ``where``."""
    place = f" and is at {where} now" if where else ""
    return (f"Its {what} has been running for {after:g} s{place} (an endless loop?). It goes on when that code ends; "
            "Ctrl+C in the terminal that serves the lab stops it.")


@contextmanager
def watch_slow(
    model_cls: type, what: str = "init:", *, after: float | None = None, log: TextIO | None = None, tell: Tell | None = None
) -> Iterator[None]:
    """Run the block; if it runs longer than ``after`` seconds, print once where it is, and
    tell the pages (``tell`` and those of :func:`telling`); their notifications go when it ends.

    ``what``: the code's name in the message (``init:``); ``log``: where (standard error).
    """
    after = SLOW_SECONDS if after is None else after
    thread_id = threading.get_ident()
    tells = [*_LOCAL.__dict__.get("tells", ()), *([tell] if tell is not None else [])]
    done = threading.Event()
    shown: list[Any] = []
    shown_lock = threading.Lock()

    def watch() -> None:
        if not _waited(done, after, thread_id):
            return
        where = where_now(thread_id, model_cls)
        text = f"{what} has been running for {after:g} s" + (" and is at this line now" if where else "")
        print(f"{where + ': ' if where else ''}warning: {text} (an endless loop?); Ctrl+C stops it",
              file=log or sys.stderr, flush=True)
        body = page_text(what, after, where)
        for t in tells:
            try:
                handles = list(t(TITLE, body) or ())
            except Exception:  # a page that went away (``log`` here is the parameter: the module's logger by name)
                logging.getLogger(__name__).debug("telling a page of a slow block failed", exc_info=True)
                continue
            with shown_lock:
                if done.is_set():  # the block ended meanwhile
                    _remove(handles)
                else:
                    shown.extend(handles)

    watcher = threading.Thread(target=watch, name="ejsrl-slow-watch", daemon=True)
    watcher.start()
    try:
        yield
    finally:
        with shown_lock:
            done.set()
            _remove(shown)


def _remove(handles: Iterable[Any]) -> None:
    for handle in handles:
        try:
            handle.remove()
        except Exception:  # its tab is gone
            log.debug("removing a slow block's notification failed", exc_info=True)
