"""Fair share of a served app among its clients: what one client may cost the others.

:mod:`ejsrl.view._guard` checks *what* a client sends; this module bounds *how much*:

- :class:`Inbox` reads one websocket's messages for viser: a token bucket of
  :data:`MESSAGE_RATE` messages a second (bursts of :data:`MESSAGE_BURST`), and while a
  client is over it only the latest pending message of each kind counts (a control's
  value, the viewer camera, a gizmo's pose): a script sending 2,000 slider values a
  second gets its latest value applied 30 times a second, and costs the server no more
  than a student dragging the slider.
- :class:`AddressBook` counts the websockets open from each client address, for the cap
  of :data:`MAX_PER_ADDRESS` connections, and remembers which addresses were already
  logged as refused.
- :class:`QuietLog` writes each kind of log line once, at most :data:`LOG_KINDS` kinds,
  then a count of what it did not write once every :data:`LOG_SUMMARY_SECONDS`:
  2,000 hostile messages add a few hundred bytes to the teacher's terminal, not megabytes.
"""

from __future__ import annotations

import asyncio
import collections
import itertools
import logging
import os
import time
from collections.abc import Awaitable, Callable, Hashable
from typing import Any

__all__ = [
    "MESSAGE_RATE",
    "MESSAGE_BURST",
    "MAX_PENDING",
    "MAX_PER_ADDRESS",
    "REGISTER_SECONDS",
    "NOTIFY_SECONDS",
    "Inbox",
    "AddressBook",
    "QuietLog",
    "coalesce_key",
]

#: messages a second one client may have handled, sustained: a lab shows 30 frames a second,
#: so more values could not be seen (at 60, a flood of the six-axis arm's joint values, each
#: running its on_change code, still cost the other students a few frames a second)
MESSAGE_RATE = 30.0
#: ... and in a burst (messages)
MESSAGE_BURST = 20.0
#: the most distinct pending messages one client may have waiting (kinds of message and
#: controls); beyond it a new kind is dropped until the client is under its rate again
MAX_PENDING = 64
#: websockets open at once from one client address (a class behind one NAT shares one
#: address, so this is generous: a single script opening thousands is what it stops);
#: the environment variable ``EJSRL_MAX_PER_ADDRESS`` sets another number
_ASKED = os.environ.get("EJSRL_MAX_PER_ADDRESS", "").strip()
MAX_PER_ADDRESS = int(_ASKED) if _ASKED.isdigit() and int(_ASKED) > 0 else 200
#: seconds a websocket may stay open without registering (the page's first camera
#: message, sent as soon as the page has drawn) before it is closed
REGISTER_SECONDS = 15.0
#: the least seconds between two "Value refused" notifications to one client for one control
NOTIFY_SECONDS = 1.0
#: distinct kinds of line a :class:`QuietLog` writes before it only counts
LOG_KINDS = 16
#: seconds between a :class:`QuietLog`'s counts of the lines it did not write
LOG_SUMMARY_SECONDS = 60.0

_unique = itertools.count()


def coalesce_key(message: dict[str, Any]) -> Hashable:
    """What a newer message of the same key replaces while both wait: a control's value
    (by uuid), the viewer camera, a gizmo's pose (by name). Start and end of a drag, and
    anything else, replace nothing (a key of their own)."""
    kind = message.get("type")
    if kind == "GuiUpdateMessage":
        return ("value", message.get("uuid"))
    if kind == "ViewerCameraMessage":
        return ("camera",)
    if kind == "TransformControlsUpdateMessage":
        return ("gizmo", message.get("name"))
    return ("once", next(_unique))


class Inbox:
    """One websocket's messages, checked and paced: ``recv()`` is what viser's consumer
    awaits instead of the connection's own.

    ``receive()``: the connection's ``recv``; ``check(raw) -> (bytes, message) | None``:
    the guard's verdict (the rewritten bytes and the decoded message, or None to drop it);
    ``rate``, ``burst``: the token bucket (messages a second, messages); ``clock``: seconds.
    """

    def __init__(
        self,
        receive: Callable[..., Awaitable[Any]],
        check: Callable[[Any], tuple[bytes, dict[str, Any]] | None],
        *,
        rate: float = MESSAGE_RATE,
        burst: float = MESSAGE_BURST,
        clock: Callable[[], float] = time.monotonic,
        counts: dict[str, int] | None = None,
    ) -> None:
        self.receive = receive
        #: where messages replaced or dropped here are counted (the guard's ``dropped``)
        self.counts = counts if counts is not None else {}
        self.check = check
        self.rate = float(rate)
        self.burst = float(burst)
        self.clock = clock
        self.tokens = float(burst)
        self.stamp = clock()
        #: messages waiting for a token, oldest first, at most one per coalesce_key
        self.pending: collections.OrderedDict[Hashable, bytes] = collections.OrderedDict()
        #: messages replaced by a newer one of the same key, and dropped for MAX_PENDING
        self.coalesced = 0
        self.overflowed = 0
        self._reading: asyncio.Future[Any] | None = None

    def _refill(self) -> None:
        now = self.clock()
        self.tokens = min(self.burst, self.tokens + (now - self.stamp) * self.rate)
        self.stamp = now

    def _take(self) -> bool:
        self._refill()
        if self.tokens >= 1.0:
            self.tokens -= 1.0
            return True
        return False

    def _wait(self) -> float:
        """Seconds until the next token."""
        self._refill()
        return max(0.0, (1.0 - self.tokens) / self.rate)

    async def recv(self, decode: bool | None = None) -> bytes:
        """The next message for viser: a pending one once the bucket allows, else the next
        one the client sends that passes the check. Raises what the connection raises
        when it closes."""
        while True:
            if self.pending and self._take():
                return self.pending.popitem(last=False)[1]
            if self._reading is None:
                self._reading = asyncio.ensure_future(self.receive(decode))
                self._reading.add_done_callback(_retrieve)
            timeout = self._wait() if self.pending else None
            done, _ = await asyncio.wait({self._reading}, timeout=timeout)
            if not done:
                continue  # a token is due for a pending message
            task, self._reading = self._reading, None
            raw = task.result()
            verdict = self.check(raw)
            if verdict is None:
                continue
            out, message = verdict
            if not self.pending and self._take():
                return out
            key = coalesce_key(message)
            if key in self.pending:
                self.coalesced += 1
                self._count("replaced by a newer value")
                del self.pending[key]
            elif len(self.pending) >= MAX_PENDING:
                self.overflowed += 1
                self._count("too many kinds pending")
                continue
            self.pending[key] = out

    def _count(self, why: str) -> None:
        self.counts[why] = self.counts.get(why, 0) + 1

    def close(self) -> None:
        """Stop reading (the connection is done)."""
        if self._reading is not None:
            self._reading.cancel()
            self._reading = None
        self.pending.clear()


def _retrieve(task: asyncio.Future[Any]) -> None:
    """Mark a read's exception as seen (a closed connection's read ends in one)."""
    if not task.cancelled():
        task.exception()


class AddressBook:
    """Websockets open per client address; the addresses refused (each logged once)."""

    def __init__(self, limit: int | None = None) -> None:
        self.limit = int(MAX_PER_ADDRESS if limit is None else limit)
        self.open: collections.Counter[str] = collections.Counter()
        self.refused: collections.Counter[str] = collections.Counter()

    def full(self, address: str) -> bool:
        """True if ``address`` has its ``limit`` of websockets open; counts the refusal."""
        if self.open[address] < self.limit:
            return False
        if len(self.refused) < 4096 or address in self.refused:
            self.refused[address] += 1
        return True

    def first_refusal(self, address: str) -> bool:
        """True the first time ``address`` was refused (log it then only)."""
        return self.refused.get(address, 0) == 1

    def opened(self, address: str) -> None:
        self.open[address] += 1

    def closed(self, address: str) -> None:
        self.open[address] -= 1
        if self.open[address] <= 0:
            del self.open[address]


class QuietLog:
    """A logger's lines, each distinct ``key`` written once (at most :data:`LOG_KINDS`
    keys), the rest counted and summed up at most once every :data:`LOG_SUMMARY_SECONDS`."""

    def __init__(self, logger: logging.Logger, what: str, *, clock: Callable[[], float] = time.monotonic) -> None:
        self.logger = logger
        self.what = what
        self.clock = clock
        self.seen: set[Hashable] = set()
        self.unwritten = 0
        self.summed_at = clock()

    def __call__(self, level: int, key: Hashable, msg: str, *args: Any, exc_info: bool = False) -> None:
        if key not in self.seen and len(self.seen) < LOG_KINDS:
            self.seen.add(key)
            self.logger.log(level, msg, *args, exc_info=exc_info)
            return
        self.unwritten += 1
        now = self.clock()
        if now - self.summed_at >= LOG_SUMMARY_SECONDS:
            self.logger.log(level, "ejsrl: %d more %s (not written one by one)", self.unwritten, self.what)
            self.unwritten = 0
            self.summed_at = now
