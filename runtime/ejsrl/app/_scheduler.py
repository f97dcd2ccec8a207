"""A bounded pool of stepper threads that runs the frames of many simulations fairly.

Each task (a classroom session) asks for its next frame at a time; the workers always run
the task whose frame is the most overdue. When the machine keeps up, every task gets its
frames on time. When it cannot, the tasks take turns (a task that ran goes to the back
of the queue) and every simulation slows by the same factor; a task that fell behind does
not try to catch up the frames it missed. A task that asks for no next frame (a paused,
idle simulation) costs nothing until :meth:`Scheduler.wake` is called for it.
"""

from __future__ import annotations

import heapq
import itertools
import logging
import threading
import time
from collections.abc import Callable
from typing import Protocol

__all__ = ["Scheduler", "Task", "default_workers"]

log = logging.getLogger("ejsrl.serve")


class Task(Protocol):
    def tick(self, due: float) -> float | None:
        """Run one frame that was due at ``due``; return when the next one is due, or None."""


def default_workers(cpus: int | None = None) -> int:
    """Stepper threads for ``cpus`` cores: one per core (NumPy releases the GIL while it
    works), at least two so that one slow frame never holds up every session, at most 8.
    The environment variable ``EJSRL_STEPPERS`` overrides it (for benchmarks)."""
    import os

    forced = os.environ.get("EJSRL_STEPPERS", "")
    if forced.isdigit() and int(forced) > 0:
        return int(forced)
    n = cpus if cpus is not None else (os.cpu_count() or 1)
    return max(2, min(8, n))


class _Entry:
    __slots__ = ("generation", "running", "wake_pending", "frames", "busy_seconds")

    def __init__(self) -> None:
        self.generation = 0
        self.running = False
        self.wake_pending = False
        self.frames = 0
        self.busy_seconds = 0.0


class Scheduler:
    """Runs the frames of :class:`Task` objects on ``workers`` threads; ``clock()``: seconds."""

    def __init__(self, workers: int | None = None, *, clock: Callable[[], float] = time.monotonic, name: str = "ejsrl-stepper") -> None:
        self.clock = clock
        self.workers = workers or default_workers()
        self._heap: list[tuple[float, int, int, Task]] = []
        self._entries: dict[int, _Entry] = {}
        self._seq = itertools.count()
        self._cv = threading.Condition()
        self._stopped = False
        self._threads = [threading.Thread(target=self._work, name=f"{name}-{i}", daemon=True) for i in range(self.workers)]
        for t in self._threads:
            t.start()

    # -- asking for frames -----------------------------------------------------------------------
    def wake(self, task: Task, at: float | None = None) -> None:
        """Run a frame of ``task`` at ``at`` (default now), unless one is already due sooner."""
        with self._cv:
            entry = self._entries.setdefault(id(task), _Entry())
            if entry.running:
                entry.wake_pending = True
                return
            self._push(task, entry, self.clock() if at is None else at)

    def remove(self, task: Task) -> None:
        """Run no more frames of ``task`` (a frame already running finishes)."""
        with self._cv:
            entry = self._entries.pop(id(task), None)
            if entry is not None:
                entry.generation += 1

    def stats(self, task: Task) -> tuple[int, float]:
        """``(frames, seconds)``: how many frames of ``task`` ran and the wall time they took."""
        with self._cv:
            entry = self._entries.get(id(task))
            return (entry.frames, entry.busy_seconds) if entry is not None else (0, 0.0)

    def pending(self) -> int:
        """How many tasks wait for a frame."""
        with self._cv:
            return len({g for _d, _s, g, t in self._heap if self._current(t, g)})

    def stop(self) -> None:
        with self._cv:
            self._stopped = True
            self._heap.clear()
            self._cv.notify_all()
        for t in self._threads:
            if t is not threading.current_thread():
                t.join(timeout=5.0)

    # -- internals ----------------------------------------------------------------------------------
    def _push(self, task: Task, entry: _Entry, due: float) -> None:
        entry.generation += 1
        heapq.heappush(self._heap, (due, next(self._seq), entry.generation, task))
        self._cv.notify()

    def _current(self, task: Task, generation: int) -> bool:
        entry = self._entries.get(id(task))
        return entry is not None and entry.generation == generation and not entry.running

    def _next(self) -> tuple[Task, float, _Entry] | None:
        """The most overdue task once it is due (marked running), or None when stopped."""
        with self._cv:
            while not self._stopped:
                while self._heap and not self._current(self._heap[0][3], self._heap[0][2]):
                    heapq.heappop(self._heap)  # superseded by a later wake, or removed
                if not self._heap:
                    self._cv.wait()
                    continue
                due, _seq, _gen, task = self._heap[0]
                delay = due - self.clock()
                if delay > 0:
                    self._cv.wait(delay)
                    continue
                heapq.heappop(self._heap)
                entry = self._entries[id(task)]
                entry.running = True
                entry.wake_pending = False
                return task, due, entry
        return None

    def _work(self) -> None:
        while True:
            picked = self._next()
            if picked is None:
                return
            task, due, entry = picked
            start = self.clock()
            try:
                next_due = task.tick(due)
            except Exception:  # noqa: BLE001 - one session's bug must not stop the pool
                log.exception("ejsrl: a session's frame failed")
                next_due = None
            end = self.clock()
            with self._cv:
                entry.running = False
                entry.frames += 1
                entry.busy_seconds += end - start
                if self._entries.get(id(task)) is not entry:
                    continue  # removed while it ran
                if entry.wake_pending:
                    next_due = end if next_due is None else min(next_due, end)
                if next_due is not None:
                    self._push(task, entry, next_due)
