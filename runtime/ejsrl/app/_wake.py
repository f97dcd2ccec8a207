"""One wake of viser's event loop for the frames of many sessions.

A session's frame is sent inside one ``client.atomic()`` block; at its end viser 1.1 wakes
its event loop with ``call_soon_threadsafe`` (a write to the loop's self-pipe) for that one
client. With 80 sessions at 30 frames/s that is 2,400 wakes a second, each a system call
and a hand-over of the GIL to the loop's thread while the stepper threads still have frames
to draw: 8-14 % of a pendulum class's server time (``bench/classroom.py --spy``).

:class:`BatchedWake` replaces the wake at the end of a client's atomic block (nothing else
of viser's buffer): the client is put on a list, and the loop is woken only if no wake is
already on its way. The loop, when it runs, sets the event of every client on the list at
once. A lone frame is woken as before (no delay); frames that end while a wake is pending
(the loop waits for the GIL) ride on it. The messages, their order and viser's window are
unchanged. Thirty pendulum sessions served from one process (their clients in it too) ended
4,332 frames in 5 s on 1,803 wakes: 2.4 frames a wake.
"""

from __future__ import annotations

import asyncio
import threading
from typing import Any

__all__ = ["BatchedWake"]


class BatchedWake:
    """Wakes one event ``loop`` (viser's) once for the atomic blocks of any number of
    clients' message buffers (``viser.infra.AsyncMessageBuffer``) that ended meanwhile."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self.loop = loop
        #: id(buffer) -> buffer: the buffers whose atomic block ended since the last wake ran
        self._dirty: dict[int, Any] = {}
        self._lock = threading.Lock()
        self._pending = False
        #: wakes sent and atomic blocks ended (for tests and benchmarks)
        self.wakes = 0
        self.ends = 0

    def install(self, buffer: Any) -> bool:
        """Make the end of ``buffer``'s atomic blocks go through this wake; False (and nothing
        changed) when the buffer is not viser 1.1's or runs on another loop."""
        if getattr(buffer, "event_loop", None) is not self.loop or not hasattr(buffer, "atomic_counter") \
                or not hasattr(buffer, "buffer_lock") or not hasattr(buffer, "message_event"):
            return False

        def atomic_end() -> None:  # viser's AsyncMessageBuffer.atomic_end, with the wake batched
            with buffer.buffer_lock:
                buffer.atomic_counter -= 1
                flush = buffer.atomic_counter == 0
            if flush:
                self.mark(buffer)

        buffer.atomic_end = atomic_end
        return True

    def mark(self, buffer: Any) -> None:
        """``buffer`` has messages for its client: wake the loop for it (at once, unless a wake
        is already on its way, which then takes it too)."""
        with self._lock:
            self.ends += 1
            self._dirty[id(buffer)] = buffer
            if self._pending:
                return
            self._pending = True
            self.wakes += 1
        try:
            self.loop.call_soon_threadsafe(self._run)
        except RuntimeError:  # the loop is closed (the server stopped): nobody to wake
            with self._lock:
                self._pending = False
                self._dirty.clear()

    def _run(self) -> None:
        """On the loop's thread: set the message event of every buffer marked since the last run."""
        with self._lock:
            dirty, self._dirty = self._dirty, {}
            self._pending = False
        for buffer in dirty.values():
            if not buffer.done:
                buffer.message_event.set()
