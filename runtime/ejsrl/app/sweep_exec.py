"""Where a sweep's runs execute: this process, a local process pool, or a Dask cluster.

Every executor runs the same function (:func:`ejsrl.app.sweep_worker.run_batch`) on the
same batches, so a sweep's results do not depend on where it ran. SIGINT (Ctrl+C) and
SIGTERM stop a sweep: the runs not yet finished are dropped, the finished ones kept.
"""

from __future__ import annotations

import math
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, TextIO

from ejsrl._signals import SignalScope
from ejsrl.app.sweep_design import Run
from ejsrl.app.sweep_worker import AppRef, RunOptions, RunResult, loaded, run_batch

__all__ = ["Executor", "Progress", "SchedulerLost", "cpu_count", "execute", "batches", "DASK_HINT", "MAX_BATCH"]

DASK_HINT = "Dask is not installed: pip install 'ejsgen[sweep]' (or: pip install 'dask[distributed]')"


def cpu_count() -> int:
    """The cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


@dataclass
class Executor:
    """Where to run: ``workers`` processes (0: in this process) on this machine, or on Dask
    (``dask``: a LocalCluster of ``workers`` processes started here; ``scheduler``: the
    address of a running cluster's scheduler, ``tcp://host:8786``), or ``sandbox``: each run
    a process of its own in a sandbox, ``workers`` at a time
    (:class:`~ejsrl.app.sweep_sandbox.ContainedRuns`)."""

    workers: int
    dask: bool = False
    scheduler: str | None = None
    sandbox: Any = None

    def describe(self) -> str:
        if self.sandbox is not None:
            n = max(self.workers, 1)
            return f"{n} sandboxed process{'es' if n != 1 else ''} at a time (bubblewrap, one per run)"
        if self.scheduler:
            return f"the Dask cluster at {self.scheduler}"
        if self.dask:
            return f"a Dask LocalCluster of {self.workers} worker{'s' if self.workers != 1 else ''}"
        if self.workers == 0:
            return "this process"
        return f"{self.workers} local worker process{'es' if self.workers != 1 else ''}"


class Progress:
    """Runs done, rate and time left: a bar redrawn in place on a terminal, a line every 10 % elsewhere."""

    def __init__(self, total: int, stream: TextIO | None = None, *, tty: bool | None = None, clock: Callable[[], float] = time.monotonic) -> None:
        self.total = total
        self.stream = stream if stream is not None else sys.stderr
        self.tty = self.stream.isatty() if tty is None else tty
        self.clock = clock
        self.start = clock()
        self.done = 0
        self.skipped = 0  # of ``done``: runs a resumed sweep found finished (not in the rate)
        self.failed = 0
        self._last_draw = -1.0
        self._last_decile = 0

    def skip(self, runs: int) -> None:
        """Count ``runs`` finished before this start (``--resume``): in the bar, not in the rate."""
        self.done += runs
        self.skipped += runs
        self._last_decile = (10 * self.done) // max(self.total, 1)

    def text(self) -> str:
        elapsed = max(self.clock() - self.start, 1e-9)
        rate = (self.done - self.skipped) / elapsed
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        eta = "--:--" if not math.isfinite(left) else _clock_text(left)
        width = 24
        filled = int(width * self.done / self.total) if self.total else width
        bar = "#" * filled + "-" * (width - filled)
        failed = f"  {self.failed} failed" if self.failed else ""
        return f"[{bar}] {self.done}/{self.total} runs  {rate:.1f} runs/s  ETA {eta}{failed}"

    def update(self, results: Sequence[RunResult]) -> None:
        self.done += len(results)
        self.failed += sum(r.status == "error" for r in results)
        now = self.clock()
        if self.tty:
            if now - self._last_draw >= 0.1 or self.done == self.total:
                self._last_draw = now
                self.stream.write("\r" + self.text() + "\x1b[K")
                self.stream.flush()
        else:
            decile = (10 * self.done) // max(self.total, 1)
            if decile > self._last_decile:
                self._last_decile = decile
                print(self.text(), file=self.stream, flush=True)

    def close(self) -> None:
        if self.tty:
            self.stream.write("\n")
            self.stream.flush()


def _clock_text(seconds: float) -> str:
    s = int(round(seconds))
    h, rest = divmod(s, 3600)
    m, s = divmod(rest, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


MAX_BATCH = 32
"""Most runs in one batch: a batch's results are what the parent holds at a time (its memory
stays flat however many runs a sweep has) and what a SIGKILL can cost."""


def batches(runs: Sequence[Run], workers: int) -> list[list[Run]]:
    """The runs in batches: about 16 per worker (at most ``MAX_BATCH`` runs), so that the work
    balances and the progress moves, while each task carries enough runs to pay for its dispatch.

    A batch holds runs with contiguous numbers (the missing runs of a resumed sweep may have
    gaps), so the batches a sweep keeps on disk never overlap.
    """
    size = max(1, min(MAX_BATCH, len(runs) // (max(workers, 1) * 16)))
    out: list[list[Run]] = []
    for run in runs:
        if out and len(out[-1]) < size and out[-1][-1].run + 1 == run.run:
            out[-1].append(run)
        else:
            out.append([run])
    return out


class SchedulerLost(Exception):
    """The Dask scheduler at ``address`` stopped answering; the runs not yet back are not run."""

    def __init__(self, address: str) -> None:
        super().__init__(f"the Dask scheduler at {address} was lost")
        self.address = address


class _Stop(BaseException):  # not an Exception: spec code and the run guard catch those
    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


class _StopOnSignal(SignalScope):
    """The first SIGINT/SIGTERM raises :class:`_Stop` in the main thread; later ones are ignored."""

    def __init__(self) -> None:
        super().__init__()
        self.signum: int | None = None

    def _handle(self, signum: int, frame: object) -> None:
        if self.signum is None:
            self.signum = signum
            raise _Stop(signum)


def _failed_batch(batch: Sequence[Run], exc: BaseException) -> list[RunResult]:
    text = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
    return [RunResult(r.run, r.settings, "error", f"error: the worker failed: {text}") for r in batch]


# -- the local pool ------------------------------------------------------------------------------------

_POOL_REF: AppRef | None = None
_POOL_OPTIONS: RunOptions | None = None


def _pool_init(ref: AppRef, options: RunOptions) -> None:
    """A pool worker: Ctrl+C in the terminal is for the parent (which stops the pool); import the app now."""
    global _POOL_REF, _POOL_OPTIONS
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _POOL_REF, _POOL_OPTIONS = ref, options
    loaded(ref)


def _pool_task(batch: list[Run]) -> list[RunResult]:
    assert _POOL_REF is not None and _POOL_OPTIONS is not None
    try:
        return run_batch(_POOL_REF, batch, _POOL_OPTIONS)
    except Exception as exc:  # noqa: BLE001 - the app could not even be imported
        return _failed_batch(batch, exc)


def _run_pool(ref: AppRef, work: list[list[Run]], options: RunOptions, workers: int, on_results: Callable[[list[RunResult]], None]) -> None:
    import multiprocessing as mp

    # fork shares the parent's imported app at no cost; a parent with threads (Dask, a GUI) spawns
    method = "fork" if sys.platform.startswith("linux") and threading.active_count() == 1 else "spawn"
    pool = mp.get_context(method).Pool(workers, initializer=_pool_init, initargs=(ref, options))
    try:
        it = pool.imap_unordered(_pool_task, work)
        for _ in range(len(work)):
            while True:
                try:
                    out = it.next(timeout=0.25)
                    break
                except mp.TimeoutError:
                    continue
            on_results(out)
        pool.close()
    except BaseException:
        pool.terminate()
        raise
    finally:
        pool.join()


# -- Dask ----------------------------------------------------------------------------------------------


def _run_dask(ref: AppRef, work: list[list[Run]], options: RunOptions, ex: Executor, on_results: Callable[[list[RunResult]], None]) -> None:
    """Run the batches on Dask. Every loss of the scheduler -- while connecting, scattering the
    app, submitting, waiting or gathering -- raises :class:`SchedulerLost`, never Dask's own error
    (and Dask's loggers stay silent: the lost client logs its reconnections from its own thread)."""
    try:
        import logging

        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise RuntimeError(DASK_HINT) from None
    # the client logs each failed (re)connection with a traceback; a lost scheduler is said in one line instead
    quiet = [logging.getLogger(name) for name in ["distributed", *logging.root.manager.loggerDict] if name.startswith("distributed")]
    levels = [q.level for q in quiet]
    for q in quiet:
        q.setLevel(logging.CRITICAL)
    cluster = None
    client: Any = None
    futures: list[Any] = []
    lost = False
    address = str(ex.scheduler or "")
    try:
        if ex.scheduler:
            try:
                client = Client(ex.scheduler, timeout="30s")
            except Exception as exc:  # noqa: BLE001 - refused, timed out, closed while connecting
                if _scheduler_lost(None, exc, address):
                    lost = True
                    raise SchedulerLost(address) from None
                raise
            payload = ref.with_archive()  # the workers may be on other machines
        else:
            cluster = LocalCluster(
                n_workers=max(ex.workers, 1), threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.ERROR
            )
            client = Client(cluster)
            payload = ref
        try:
            address = str(client.scheduler.address if client.scheduler is not None else ex.scheduler)
            ref_future = client.scatter(payload, broadcast=True)
            futures = [client.submit(run_batch, ref_future, batch, options, pure=False) for batch in work]
            batch_of = {f.key: batch for f, batch in zip(futures, work)}
            finished = as_completed(futures)
        except Exception as exc:  # noqa: BLE001
            if _scheduler_lost(client, exc, address):
                lost = True
                raise SchedulerLost(address) from None
            raise
        while True:
            try:
                fut = next(finished, None)
                if fut is None:
                    break
                out = fut.result()
            except Exception as exc:  # noqa: BLE001 - a worker died, the app could not be imported, ...
                if _scheduler_lost(client, exc, address):
                    lost = True
                    raise SchedulerLost(address) from None
                if fut is None:
                    raise
                out = _failed_batch(batch_of[fut.key], exc)
            on_results(out)  # its own errors (CannotWrite) are not the scheduler's
    finally:
        for f in futures:
            try:
                f.cancel()
            except Exception:  # noqa: BLE001, S110 - a lost client cannot cancel; nothing runs on without its scheduler
                pass
        try:
            if client is not None:
                client.close(timeout=10)
        except Exception:  # noqa: BLE001, S110 - closing a client whose scheduler is gone
            pass
        if cluster is not None:
            cluster.close()
        if not lost:  # a lost client keeps logging its reconnections' tracebacks from its own thread
            for q, level in zip(quiet, levels):
                q.setLevel(level)


def _answers(address: str, timeout: float = 10.0) -> bool:
    """Whether the scheduler at ``tcp://host:port`` still accepts connections."""
    import socket
    from urllib.parse import urlsplit

    try:
        parts = urlsplit(address if "://" in address else f"tcp://{address}")
        if parts.hostname is None or parts.port is None:
            return True  # not an address this can check: let the client's state decide
        with socket.create_connection((parts.hostname, parts.port), timeout=timeout):
            return True
    except (OSError, ValueError):
        return False


def _scheduler_lost(client: Any, exc: BaseException, address: str = "") -> bool:
    """Whether a Dask call failed because the scheduler went away (not because its runs failed)."""
    from asyncio import CancelledError as TaskCancelled
    from concurrent.futures import CancelledError  # distributed's FutureCancelledError is one

    from distributed.comm.core import CommClosedError

    if isinstance(exc, (CancelledError, TaskCancelled, CommClosedError)):
        return True
    if client is not None and getattr(client, "status", "running") != "running":
        return True
    # refused, reset or timed out: the scheduler may be gone before the client has noticed
    if isinstance(exc, (OSError, TimeoutError)) or client is None:
        return bool(address) and not _answers(address)
    return False


# -- the whole sweep -----------------------------------------------------------------------------------


def execute(
    ref: AppRef,
    runs: Sequence[Run],
    options: RunOptions,
    ex: Executor,
    *,
    progress: Progress | None = None,
    on_batch: Callable[[list[RunResult]], None] | None = None,
) -> tuple[list[RunResult], int | None]:
    """Run every run; returns the results (by run number) and the signal that stopped the sweep, if one did.

    With ``on_batch``, each finished batch goes to it (to disk) and is not kept: the results
    returned are then empty. Exceptions of ``on_batch`` (``CannotWrite``) and
    ``SchedulerLost`` stop the sweep and propagate.
    """
    results: list[RunResult] = []

    def on_results(out: list[RunResult]) -> None:
        if on_batch is not None:
            on_batch(out)
        else:
            results.extend(out)
        if progress is not None:
            progress.update(out)

    work = batches(runs, ex.workers)
    if not work:  # a resumed sweep whose runs are all done
        if progress is not None:
            progress.close()
        return results, None
    stopper = _StopOnSignal()
    try:
        with stopper:
            if ex.sandbox is not None:
                ex.sandbox.execute(work, options, max(ex.workers, 1), on_results)
            elif ex.dask or ex.scheduler:
                _run_dask(ref, work, options, ex, on_results)
            elif ex.workers == 0:
                for batch in work:
                    on_results(run_batch(ref, batch, options))
            else:
                _run_pool(ref, work, options, min(ex.workers, len(work)), on_results)
    except _Stop:
        pass
    except KeyboardInterrupt:  # before the handlers were in place
        stopper.signum = stopper.signum or signal.SIGINT
    finally:
        if progress is not None:
            progress.close()
    results.sort(key=lambda r: r.run)
    return results, stopper.signum
