"""viser's own server objects, running in a browser tab with no sockets and no threads.

A lab built with ``ejsgen build --web`` runs its Python in the student's browser (CPython for
WebAssembly). The view layer is the served app's (:class:`ejsrl.view.viser_view.ViserView`, with
viser's ``GuiApi``, ``SceneApi`` and handles); only the transport changes. :func:`web_server`
makes a real ``viser.ViserServer`` whose websocket server is a :class:`PageChannel`: messages
that viser queues are kept in order and handed to the page once a frame as one batch, in
viser's hybrid wire format without the compression (an 8-byte little-endian length, the
MessagePack of ``{"messages", "timestampSec", "binaryBufferLengths"}``, then each array's
bytes at an 8-byte aligned offset); messages from the page (MessagePack, as viser's client
sends them) go through ejsgen's message guard (:class:`ejsrl.view._guard.MessageGuard`:
kinds, values validated and clamped) and then to viser's handlers, as served.

Everything runs on the caller's thread: callbacks that viser would hand to its thread pool or
event loop run at once (:class:`Immediate`, :class:`ImmediateLoop`).
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import struct
import threading
import time
from collections.abc import Callable, Coroutine, Generator
from typing import Any

from ejsrl.web import _absent

_absent.install()

import viser  # noqa: E402 - after the stand-ins of what a browser lacks
from viser import _client_autobuild, _viser  # noqa: E402
from viser.infra import _infra  # noqa: E402
from viser.infra._messages import Message  # noqa: E402

from ejsrl.web import _msgpack, _png  # noqa: E402

_png.install()  # images as PNG written with zlib: the page has neither OpenCV nor Pillow

__all__ = ["PageChannel", "Immediate", "ImmediateLoop", "web_server", "encode_batch", "run_now"]

_LENGTH = struct.Struct("<Q")


def run_now(coro: Coroutine[Any, Any, Any]) -> Any:
    """Run ``coro`` to its end on this thread (viser's handlers await nothing that waits)."""
    try:
        while True:
            coro.send(None)
    except StopIteration as done:
        return done.value


class Immediate(concurrent.futures.Executor):
    """viser's thread pool, in a tab with no threads: ``submit`` runs the call at once."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> concurrent.futures.Future[Any]:
        future: concurrent.futures.Future[Any] = concurrent.futures.Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001 - reported through the future, as a pool does
            future.set_exception(exc)
        return future


class ImmediateLoop:
    """viser's event loop, in a tab: tasks and callbacks run at once, on this thread."""

    def create_task(self, coro: Coroutine[Any, Any, Any], **_kwargs: Any) -> concurrent.futures.Future[Any]:
        return Immediate().submit(run_now, coro)

    def call_soon_threadsafe(self, fn: Callable[..., Any], *args: Any, **_kwargs: Any) -> None:
        fn(*args)

    call_soon = call_soon_threadsafe

    def is_running(self) -> bool:
        return True

    def is_closed(self) -> bool:
        return False


class _Outbox:
    """viser's message buffer (broadcast or one client's): keeps what is queued, in order,
    until the page takes it. Every buffer of one channel shares one list, so the order of
    broadcast and per-client messages is the order they were queued in."""

    def __init__(self, messages: list[Message], loop: ImmediateLoop) -> None:
        self.messages = messages
        self.event_loop = loop
        # viser's garbage collector of persistent messages reads these: a page keeps none
        # (it is its one client, and it never replays), so they stay empty
        self.buffer_lock = threading.RLock()
        self.message_from_id: dict[int, Message] = {}
        self.generator_cursors: dict[int, int] = {}
        self.ids_from_entity_state_key: dict[tuple[str, str], list[int]] = {}

    def pop_message_locked(self, message_id: int) -> Message | None:
        return self.message_from_id.pop(message_id, None)

    def push(self, message: Message) -> None:
        self.messages.append(message)

    def atomic_start(self) -> None:
        return None

    def atomic_end(self) -> None:
        return None

    def flush(self) -> None:
        return None

    def set_done(self) -> None:
        return None

    def remove_from_buffer(self, match_fn: Callable[[Message], bool]) -> None:
        self.messages[:] = [m for m in self.messages if not match_fn(m)]

    def remove_entity_state_from_buffer(self, entity_type: str, entity_id: str) -> None:
        self.messages[:] = [m for m in self.messages if not m.targets_entity_state(entity_type, entity_id)]

    @contextlib.contextmanager
    def sanctioned_dead_writes(self) -> Generator[None, None, None]:
        yield


class PageChannel(_infra.WebsockMessageHandler):
    """Stands in for viser's ``infra.WebsockServer``: one page, one client (id 0), connected
    by :meth:`connect`; :meth:`receive` takes a message from the page, :meth:`take` the batch
    for it. Built by ``viser.ViserServer`` itself (see :func:`web_server`)."""

    CLIENT_ID = 0

    def __init__(self, host: str = "", port: int = 0, message_class: type[Message] = Message,
                 http_server_root: Any = None, verbose: bool = False, backlog_done_message: Message | None = None) -> None:
        super().__init__()
        self._message_class = message_class
        self._port = port
        self._server_thread = None
        self._backlog_done_message = backlog_done_message
        self._client_connect_cb: list[Callable[[Any], Any]] = []
        self._client_disconnect_cb: list[Callable[[Any], Any]] = []
        self.loop = ImmediateLoop()
        self.outgoing: list[Message] = []
        self._broadcast_buffer = _Outbox(self.outgoing, self.loop)
        self._client_state_from_id: dict[int, Any] = {}
        self._live_connections: dict[int, Any] = {}
        self.connection: _infra.WebsockClientConnection | None = None
        #: checks a client's message before viser decodes it: ``(connection, raw) -> (bytes, dict) | None``
        self.check: Callable[[Any, bytes], tuple[bytes, dict[str, Any]] | None] | None = None

    # -- what viser.ViserServer calls ------------------------------------------------------------
    def start(self) -> None:
        return None

    def stop(self) -> None:
        return None

    def on_client_connect(self, cb: Callable[[Any], Any]) -> None:
        self._client_connect_cb.append(cb)

    def on_client_disconnect(self, cb: Callable[[Any], Any]) -> None:
        self._client_disconnect_cb.append(cb)

    def get_message_buffer(self) -> Any:
        return self._broadcast_buffer

    def flush(self) -> None:
        return None

    def flush_client(self, client_id: int) -> None:
        return None

    def disconnect_all_clients(self) -> None:
        return None

    # -- the page's side ---------------------------------------------------------------------------
    def connect(self) -> _infra.WebsockClientConnection:
        """The page's client connects: viser's connect callbacks run (its ``ClientHandle`` is
        made), and the end-of-replay marker is queued, as the served server does."""
        state = _infra._ClientHandleState(_Outbox(self.outgoing, self.loop), self.loop)  # type: ignore[arg-type]
        connection = _infra.WebsockClientConnection(self.CLIENT_ID, state)
        self.connection = connection
        self._client_state_from_id[self.CLIENT_ID] = state
        self._live_connections[self.CLIENT_ID] = connection
        for cb in self._client_connect_cb:
            result = cb(connection)
            if result is not None and hasattr(result, "send"):
                run_now(result)
        if self._backlog_done_message is not None:
            self.outgoing.append(self._backlog_done_message)
        return connection

    def receive(self, raw: bytes) -> bool:
        """Handle one message from the page (MessagePack bytes); False if it was dropped."""
        connection = self.connection
        if connection is None:
            return False
        if self.check is not None:
            checked = self.check(connection, raw)
            if checked is None:
                return False
            raw = checked[0]
        try:
            message = self._message_class.deserialize(raw)
        except Exception:  # noqa: BLE001 - a malformed message is dropped, as viser's consumer does
            return False
        run_now(self._handle_incoming_message(self.CLIENT_ID, message))
        run_now(connection._handle_incoming_message(self.CLIENT_ID, message))
        return True

    def take(self) -> bytes | None:
        """The messages queued since the last call, as one batch for the page (None if none)."""
        if not self.outgoing:
            return None
        messages, self.outgoing[:] = list(self.outgoing), []
        return encode_batch(messages)


def encode_batch(messages: list[Message], timestamp: float | None = None) -> bytes:
    """``messages`` in viser's hybrid wire format without compression: an 8-byte length, the
    MessagePack of the batch, padding to 8 bytes, then each array's bytes 8-byte aligned."""
    buffers: list[memoryview] = []
    dicts = [m.as_serializable_dict(buffers) for m in messages]
    lengths = [b.nbytes for b in buffers]
    head = _msgpack.encode({"messages": dicts, "timestampSec": time.time() if timestamp is None else timestamp,
                            "binaryBufferLengths": lengths})
    out = bytearray(_LENGTH.pack(len(head)))
    out += head
    for b in buffers:
        out += bytes(-len(out) % 8)
        out += b.cast("B")
    return bytes(out)


def web_server() -> tuple[viser.ViserServer, PageChannel]:
    """A ``viser.ViserServer`` made by viser's own constructor, with a :class:`PageChannel`
    for its websocket server and :class:`Immediate` for its thread pool."""
    saved = (viser.infra.WebsockServer, _viser.ThreadPoolExecutor, _client_autobuild.ensure_client_is_built)
    viser.infra.WebsockServer = PageChannel  # type: ignore[misc]
    _viser.ThreadPoolExecutor = lambda **_k: Immediate()  # type: ignore[misc,assignment]
    _client_autobuild.ensure_client_is_built = lambda: None  # the page carries viser's client
    try:
        server = viser.ViserServer(host="", port=0, verbose=False)
    finally:
        viser.infra.WebsockServer, _viser.ThreadPoolExecutor, _client_autobuild.ensure_client_is_built = saved
    channel = server._websock_server
    assert isinstance(channel, PageChannel)
    return server, channel
