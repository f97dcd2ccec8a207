"""Serving a class from several processes: a front that relays each tab to a worker.

One Python process runs Python on one core at a time (the GIL): a class served by one
process cannot use a lab machine's other cores, however many it has. With
``--processes N`` (by default one per core, up to :data:`MAX_PROCESSES`) a served app is a
*front* and N *workers*:

- **The workers** are the same app, started with the same command line and told their
  role through the environment (:data:`WORKER_ENV`). Each serves its share of the class
  on 127.0.0.1 at a free port, with everything a single process does (sessions, grace
  period, guards). It answers to the front's address (Host and Origin are checked against
  it), names its sessions' tokens after itself (``<index>x<random>``), reports its port and
  its number of places through a pipe, and stops when the front is gone.
- **The front** listens on the address the teacher gave and relays every connection to a
  worker, bytes as they come: a page or websocket at ``/s/<token>/`` goes to the worker
  named in the token (a reload finds its session again), a new tab's websocket to the
  least full worker, anything else (the page's files) in turn. When every
  place is taken, the worker a new tab reaches tells it the lab is full. A worker that
  stops is started again (its students' sessions are lost, with a line in the terminal).

The front reads nothing but the request's first line and headers, and never what a
client sends afterwards; every check of what clients send stays in the workers. It counts
the connections of each client address (the workers see only the front's): at most
:data:`ejsrl.view._fair.MAX_PER_ADDRESS` websockets and :data:`CONNECTIONS_PER_WEBSOCKET`
times as many connections in all; more are answered 429 (logged once per address).
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import json
import logging
import os
import re
import select
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import asyncio  # imported where the front runs: a headless or in-browser lab never loads it

__all__ = ["WORKER_ENV", "MAX_PROCESSES", "WorkerRole", "Front", "default_processes", "worker_command", "split_places"]

log = logging.getLogger("ejsrl.serve")

#: the environment variable that makes an app a worker of a front (JSON: see WorkerRole)
WORKER_ENV = "EJSRL_SERVE_WORKER"
#: the most processes a class is served from by default
MAX_PROCESSES = 8
#: seconds a worker may take to start (imports, and measuring the lab's cost)
START_SECONDS = 180.0
#: seconds a client may take to send its request's first line and headers
HEAD_SECONDS = 15.0
#: the longest request head relayed (bytes)
HEAD_LIMIT = 64 * 1024
#: seconds between tries to start again a worker that failed to start
RETRY_SECONDS = 10.0
#: seconds the workers get to stop before they are killed
STOP_SECONDS = 5.0
#: connections of any kind one address may have open, per websocket it may have (a page
#: loads its files over a few connections of its own)
CONNECTIONS_PER_WEBSOCKET = 4

_TOKEN = re.compile(r"/s/(\d{1,3})x[A-Za-z0-9_-]{8,64}(?:/|\?|$)")
_UPGRADE = re.compile(rb"(?im)^upgrade:[ \t]*websocket[ \t]*\r?$")


def default_processes(cpus: int | None = None) -> int:
    """One process per core, at most :data:`MAX_PROCESSES`."""
    n = cpus if cpus is not None else (os.cpu_count() or 1)
    return max(1, min(MAX_PROCESSES, n))


def split_places(total: int, count: int) -> list[int]:
    """``total`` places shared as evenly as possible by ``count`` workers (``count`` <= ``total``)."""
    if not 1 <= count <= total:
        raise ValueError(f"{total} places cannot be shared by {count} processes")
    return [total // count + (1 if i < total % count else 0) for i in range(count)]


def worker_command() -> list[str] | None:
    """The command line that starts this app again (interpreter options, script, arguments),
    or None when it was not started as a script or a ``.pyz`` (``-m``, ``-c``, embedded)."""
    argv, orig = list(sys.argv), list(getattr(sys, "orig_argv", []))
    if not argv or not argv[0] or not Path(argv[0]).is_file() or len(orig) < len(argv):
        return None
    options = orig[1 : len(orig) - len(argv)]
    if any(o in ("-m", "-c") or o.startswith(("-m", "-c")) for o in options):
        return None
    if orig[len(orig) - len(argv) :][1:] != argv[1:]:
        return None
    return [sys.executable, *options, *argv]


@dataclasses.dataclass(frozen=True)
class WorkerRole:
    """What a worker is told by its front (through :data:`WORKER_ENV`).

    ``index``: its number, which its tokens carry; ``bind``: the front's address (the names
    the worker answers to); ``cpus``: the cores it may count on when it works out its
    places; ``max_sessions``: its places, and ``class_places`` the class's, if the teacher
    gave a number; ``report_fd``: where it writes its port and places; ``parent``: the
    front's process id.
    """

    index: int
    bind: str
    cpus: float
    max_sessions: int | None
    class_places: int | None
    report_fd: int
    parent: int

    @classmethod
    def from_env(cls) -> WorkerRole | None:
        text = os.environ.get(WORKER_ENV)
        if not text:
            return None
        return cls(**json.loads(text))

    def to_env(self) -> str:
        return json.dumps(dataclasses.asdict(self))

    @property
    def token_prefix(self) -> str:
        return f"{self.index}x"

    def report(self, port: int, max_sessions: int) -> None:
        """Tell the front where this worker serves and how many places it has."""
        with os.fdopen(self.report_fd, "w") as fh:
            fh.write(json.dumps({"port": int(port), "max_sessions": int(max_sessions)}) + "\n")

    def orphaned(self) -> bool:
        """True once the front is gone."""
        return os.getppid() != self.parent


class Worker:
    """The front's record of one worker process."""

    def __init__(self, index: int) -> None:
        self.index = index
        self.proc: subprocess.Popen[bytes] | None = None
        self.port = 0
        self.places = 0
        #: websockets relayed to it now (its tabs, and tabs it told the lab is full)
        self.tabs = 0
        self.ready = False
        #: when a worker that failed to start may be tried again (time.monotonic())
        self.retry_at = 0.0


class Front:
    """Serves ``host:port`` from ``count`` worker processes started with ``command``
    (see the module docstring); ``max_sessions``: places in all (None: each worker works
    out its own from the lab's measured cost and its share of the cores)."""

    def __init__(self, command: Sequence[str], host: str, port: int, *, count: int, max_sessions: int | None) -> None:
        self.command = list(command)
        self.host = host
        self.port = port
        self.workers = [Worker(i) for i in range(count)]
        self.asked = max_sessions
        #: each worker's share of the asked places (None: it works out its own)
        self.shares = split_places(max_sessions, count) if max_sessions is not None else [None] * count
        self.cpus = min(1.0, (os.cpu_count() or 1) / count)  # a process runs Python on one core at most
        self._turn = itertools.count()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._server: asyncio.base_events.Server | None = None
        self._thread: threading.Thread | None = None
        self._stopping = False
        from ejsrl.view._fair import AddressBook

        #: websockets, and connections of any kind, open per client address
        self.websockets = AddressBook()
        self.connections = AddressBook(self.websockets.limit * CONNECTIONS_PER_WEBSOCKET)

    # -- the workers ---------------------------------------------------------------------------------
    def start(self) -> None:
        """Start the workers (in parallel) and wait for each to report; raises RuntimeError
        if one does not start."""
        pending = [self._spawn(w) for w in self.workers]
        for worker, read_fd in zip(self.workers, pending):
            self._await_report(worker, read_fd)

    def _spawn(self, worker: Worker) -> int:
        read_fd, write_fd = os.pipe()
        role = WorkerRole(worker.index, self.host, self.cpus, self.shares[worker.index], self.asked, write_fd, os.getpid())
        env = dict(os.environ, **{WORKER_ENV: role.to_env()})
        try:
            # its own process group: Ctrl+C reaches the front, which stops the workers
            worker.proc = subprocess.Popen(self.command, env=env, pass_fds=(write_fd,), stdin=subprocess.DEVNULL,
                                           process_group=0)
        finally:
            os.close(write_fd)
        worker.ready = False
        return read_fd

    def _await_report(self, worker: Worker, read_fd: int) -> None:
        data = b""
        deadline = time.monotonic() + START_SECONDS
        try:
            while not data.endswith(b"\n"):
                left = deadline - time.monotonic()
                if left <= 0 or not select.select([read_fd], [], [], min(left, 0.5))[0]:
                    if left <= 0 or (worker.proc is not None and worker.proc.poll() is not None):
                        break
                    continue
                chunk = os.read(read_fd, 4096)
                if not chunk:
                    break
                data += chunk
        finally:
            os.close(read_fd)
        try:
            report = json.loads(data)
            worker.port, worker.places = int(report["port"]), int(report["max_sessions"])
        except (ValueError, KeyError, TypeError):
            status = None
            if worker.proc is not None:  # it closed the pipe: give it a moment to end
                with contextlib.suppress(subprocess.TimeoutExpired):
                    status = worker.proc.wait(2.0)
            raise RuntimeError(f"serving process {worker.index} did not start"
                               + (f" (it ended with status {status})" if status is not None else "")) from None
        worker.tabs = 0
        worker.ready = True

    def supervise(self) -> None:
        """Start again a worker that has stopped (called every half second); after a
        failed start, the next try waits :data:`RETRY_SECONDS`."""
        for worker in self.workers:
            proc = worker.proc
            if self._stopping or proc is None or proc.poll() is None or time.monotonic() < worker.retry_at:
                continue
            if worker.ready:
                log.warning("ejsrl: serving process %d stopped (status %s); starting a new one (the sessions "
                            "it served are lost: their tabs reload to a new one)", worker.index, proc.returncode)
            worker.ready = False
            try:
                self._await_report(worker, self._spawn(worker))
            except RuntimeError as exc:
                worker.retry_at = time.monotonic() + RETRY_SECONDS
                log.error("ejsrl: %s; trying again in %.0f s", exc, RETRY_SECONDS)

    def stop(self) -> None:
        """Stop relaying and stop the workers (SIGTERM, then SIGKILL after STOP_SECONDS)."""
        self._stopping = True
        loop, server = self._loop, self._server
        if loop is not None and server is not None:
            with contextlib.suppress(RuntimeError):  # the loop has ended already
                loop.call_soon_threadsafe(server.close)
        procs = [w.proc for w in self.workers if w.proc is not None]
        for proc in procs:
            with contextlib.suppress(ProcessLookupError):
                proc.send_signal(signal.SIGTERM)
        deadline = time.monotonic() + STOP_SECONDS
        for proc in procs:
            try:
                proc.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        if loop is not None:
            with contextlib.suppress(RuntimeError):
                loop.call_soon_threadsafe(loop.stop)
        if self._thread is not None:
            self._thread.join(STOP_SECONDS)

    @property
    def max_sessions(self) -> int:
        return sum(w.places for w in self.workers)

    # -- relaying ------------------------------------------------------------------------------------
    def listen(self) -> int:
        """Listen on ``host:port`` (the next free port if taken; 0: any) in a thread of its
        own; returns the port."""
        ready = threading.Event()
        failure: list[BaseException] = []

        def run() -> None:
            import asyncio

            loop = asyncio.new_event_loop()
            asyncio.set_event_loop(loop)
            try:
                self._server = loop.run_until_complete(self._bind())
            except BaseException as exc:  # noqa: BLE001 - reported to listen()
                failure.append(exc)
                ready.set()
                loop.close()
                return
            self._loop = loop
            ready.set()
            try:
                loop.run_forever()
            finally:  # stopped: end the relays still open, then the loop
                pending = asyncio.all_tasks(loop)
                for task in pending:
                    task.cancel()
                if pending:
                    loop.run_until_complete(asyncio.gather(*pending, return_exceptions=True))
                loop.close()

        self._thread = threading.Thread(target=run, name="ejsrl-front", daemon=True)
        self._thread.start()
        ready.wait()
        if failure:
            raise failure[0]
        assert self._server is not None
        return int(self._server.sockets[0].getsockname()[1])

    async def _bind(self) -> asyncio.base_events.Server:
        import asyncio

        host = None if self.host in ("", "0.0.0.0") else self.host
        tries = 1 if self.port == 0 else 100
        for port in range(self.port, self.port + tries):
            try:
                return await asyncio.start_server(self._relay, host, port, limit=HEAD_LIMIT)
            except OSError:
                if port == self.port + tries - 1:
                    raise
        raise AssertionError("unreachable")

    def route(self, path: str, websocket: bool) -> Worker | None:
        """The worker a request for ``path`` goes to (None if none is ready)."""
        ready = [w for w in self.workers if w.ready]
        if not ready:
            return None
        match = _TOKEN.match(path)
        if match is not None:
            index = int(match.group(1))
            if index < len(self.workers) and self.workers[index].ready:
                return self.workers[index]
        if websocket:  # a new tab: the least full (shares the cores evenly), then the most free places
            return min(ready, key=lambda w: (w.tabs / max(w.places, 1), w.tabs - w.places, w.index))
        return ready[next(self._turn) % len(ready)]

    async def _relay(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        peer = writer.get_extra_info("peername")
        address = str(peer[0]) if isinstance(peer, tuple) and peer else ""
        if self.connections.full(address):
            self._refuse(address, self.connections.limit, "connections")
            writer.close()
            return
        self.connections.opened(address)
        try:
            await self._relay_one(reader, writer, address)
        except (ConnectionError, OSError):  # a client or a worker went away mid-way: nothing to tell
            writer.close()
        except Exception:  # noqa: BLE001 - one connection's failure must not reach the others
            log.debug("ejsrl: relaying a connection failed", exc_info=True)
            writer.close()
        finally:
            self.connections.closed(address)

    def _refuse(self, address: str, limit: int, what: str) -> None:
        """Log, once per address, that ``address`` was refused for having ``limit`` ``what`` open."""
        book = self.connections if what == "connections" else self.websockets
        if book.first_refusal(address):
            log.warning("ejsrl: refused %s from %s: it has %d open (the most from one address)", what, address, limit)

    async def _relay_one(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, address: str) -> None:
        import asyncio

        try:
            head = await asyncio.wait_for(reader.readuntil(b"\r\n\r\n"), HEAD_SECONDS)
        except (asyncio.IncompleteReadError, asyncio.LimitOverrunError, asyncio.TimeoutError, ConnectionError, ValueError):
            writer.close()
            return
        parts = head.split(b"\r\n", 1)[0].split(b" ")
        path = parts[1].decode("latin-1") if len(parts) == 3 else ""
        websocket = _UPGRADE.search(head) is not None
        if websocket and self.websockets.full(address):
            self._refuse(address, self.websockets.limit, "websockets")
            body = b"Too many connections from your address: close some tabs of this lab.\n"
            writer.write(b"HTTP/1.1 429 Too Many Requests\r\nContent-Type: text/plain; charset=utf-8\r\n"
                         b"Connection: close\r\nContent-Length: %d\r\n\r\n%s" % (len(body), body))
            with contextlib.suppress(ConnectionError):
                await writer.drain()
            writer.close()
            return
        worker = self.route(path, websocket)
        upstream: tuple[asyncio.StreamReader, asyncio.StreamWriter] | None = None
        if worker is not None:
            try:
                upstream = await asyncio.open_connection("127.0.0.1", worker.port)
            except OSError:
                upstream = None
        if worker is None or upstream is None:
            body = b"This lab is starting again: reload the page in a few seconds.\n"
            writer.write(b"HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain; charset=utf-8\r\n"
                         b"Retry-After: 5\r\nConnection: close\r\nContent-Length: %d\r\n\r\n%s" % (len(body), body))
            with contextlib.suppress(ConnectionError):
                await writer.drain()
            writer.close()
            return
        up_reader, up_writer = upstream
        up_writer.write(head)
        if websocket:
            worker.tabs += 1
            self.websockets.opened(address)
        try:
            to_worker = asyncio.ensure_future(_pipe(reader, up_writer, half_close=True))
            to_client = asyncio.ensure_future(_pipe(up_reader, writer, half_close=False))
            done, _ = await asyncio.wait({to_worker, to_client}, return_when=asyncio.FIRST_COMPLETED)
            if to_client in done or to_worker.exception() is not None:
                to_worker.cancel()
                to_client.cancel()
            else:  # the client said all it had to say: the worker's answer may still be coming
                await to_client
        finally:
            if websocket:
                worker.tabs -= 1
                self.websockets.closed(address)
            for w in (writer, up_writer):
                w.close()


async def _pipe(reader: asyncio.StreamReader, writer: asyncio.StreamWriter, *, half_close: bool) -> None:
    """Copy ``reader`` to ``writer`` until the end; ``half_close``: pass the end on."""
    try:
        while True:
            data = await reader.read(1 << 16)
            if not data:
                break
            writer.write(data)
            await writer.drain()
        if half_close and writer.can_write_eof():
            writer.write_eof()
    except (ConnectionError, OSError):
        pass


def serve_front(
    command: Sequence[str], host: str, port: int, *, count: int, max_sessions: int | None, announce: Any
) -> int:
    """Serve a class from ``count`` processes until a KeyboardInterrupt (a stop signal)
    arrives; ``announce(port, places)`` prints the start-up lines."""
    front = Front(command, host, port, count=count, max_sessions=max_sessions)
    try:
        front.start()
        bound = front.listen()
        announce(bound, front.max_sessions)
        while True:
            time.sleep(0.5)
            front.supervise()
    except RuntimeError as exc:
        print(f"error: {exc}", file=sys.stderr, flush=True)
        return 1
    except OSError as exc:
        print(f"error: cannot serve on {host}:{port}: {exc.strerror or exc}", file=sys.stderr, flush=True)
        return 1
    finally:
        front.stop()
