"""A raw websocket client that speaks viser's wire format, for the hostile-client tests.

It does what a browser's viser client does (the ``viser-v<version>`` subprotocol,
msgpack messages, the viewer camera message that registers a client) and anything else
a hostile script might: any Origin or Host header, any message, any size.
"""

from __future__ import annotations

import asyncio
import threading
import time
from typing import Any

import msgspec
import viser
import zstandard
from websockets.asyncio.client import connect
from websockets.exceptions import ConnectionClosed

SUBPROTOCOL = f"viser-v{viser.__version__}"

CAMERA = {
    "type": "ViewerCameraMessage", "wxyz": [1.0, 0.0, 0.0, 0.0], "position": [3.0, 3.0, 3.0], "fov": 1.3,
    "near": 0.01, "far": 1000.0, "image_height": 800, "image_width": 1280, "look_at": [0.0, 0.0, 0.0],
    "up_direction": [0.0, 0.0, 1.0],
}


def run_async(coro: Any, timeout: float = 60.0) -> Any:
    """Run ``coro`` to completion on a fresh event loop in its own thread.

    The browser tests' sync playwright leaves an event loop running in the main thread of
    the xdist worker they share with these tests, where ``asyncio.run`` is refused.
    """
    out: dict[str, Any] = {}

    def target() -> None:
        try:
            out["value"] = asyncio.run(asyncio.wait_for(coro, timeout))
        except BaseException as exc:  # noqa: BLE001 - re-raised in the caller
            out["error"] = exc

    thread = threading.Thread(target=target, name="guard-client")
    thread.start()
    thread.join()
    if "error" in out:
        raise out["error"]
    return out.get("value")


def encode(message: dict[str, Any]) -> bytes:
    return msgspec.msgpack.encode(message)


def decode_frame(data: bytes) -> list[dict[str, Any]]:
    """The messages in one server frame: [8 B size][8 B compressed size][zstd msgpack][buffers]."""
    size = int.from_bytes(data[:8], "little")
    compressed = int.from_bytes(data[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(data[16:16 + compressed], max_output_size=size)
    return list(msgspec.msgpack.decode(inner)["messages"])


def gui_update(uuid: str, **updates: Any) -> dict[str, Any]:
    return {"type": "GuiUpdateMessage", "uuid": uuid, "updates": updates}


class Client:
    """One websocket connection to a served app, with everything it has received."""

    def __init__(self, ws: Any) -> None:
        self.ws = ws
        self.received: list[dict[str, Any]] = []
        self.closed: ConnectionClosed | None = None
        self._reader = asyncio.create_task(self._read())

    @classmethod
    async def open(cls, port: int, *, origin: str | None = None, host: str | None = None,
                   camera: bool = True, server: Any = None, path: str = "", cookie: str | None = None,
                   source: str | None = None) -> "Client":
        # with ``host``, the Host header names it while the TCP connection still goes to 127.0.0.1;
        # ``path``: the websocket's path (a classroom session's address, /s/<token>); ``cookie``:
        # the browser cookie a page would have set (ejsrl_browser=...); ``source``: the address to
        # connect from (another loopback address, 127.0.0.2, is another client address)
        uri = f"ws://{host or f'127.0.0.1:{port}'}{path}"
        headers = {"Cookie": f"ejsrl_browser={cookie}"} if cookie is not None else None
        extra = {"local_addr": (source, 0)} if source is not None else {}
        ws = await connect(uri, subprotocols=[SUBPROTOCOL], origin=origin, host="127.0.0.1", port=port,
                           max_size=None, open_timeout=10, additional_headers=headers, **extra)
        client = cls(ws)
        if camera:
            before = len(server.get_clients()) if server is not None else 0
            await client.send(CAMERA)
            if server is not None:
                await client.until(lambda: len(server.get_clients()) > before, "the client to be registered")
        return client

    async def _read(self) -> None:
        try:
            async for data in self.ws:
                if isinstance(data, bytes):
                    self.received.extend(decode_frame(data))
        except ConnectionClosed as exc:
            self.closed = exc
        if self.closed is None:
            self.closed = self.ws.close_exc if hasattr(self.ws, "close_exc") else ConnectionClosed(None, None)

    async def send(self, message: dict[str, Any] | bytes | str) -> None:
        await self.ws.send(message if isinstance(message, (bytes, str)) else encode(message))

    def seen(self, kind: str, **fields: Any) -> list[dict[str, Any]]:
        return [m for m in self.received if m.get("type") == kind and all(m.get(k) == v for k, v in fields.items())]

    def values_of(self, uuid: str) -> list[Any]:
        """Every value this client was sent for the control ``uuid`` (what its UI showed)."""
        return [m["updates"]["value"] for m in self.seen("GuiUpdateMessage", uuid=uuid) if "value" in m["updates"]]

    def texts(self) -> list[str]:
        """The Markdown and HTML this client's panel was sent."""
        out = []
        for m in self.received:
            if m.get("type") in ("GuiMarkdownMessage", "GuiHtmlMessage"):
                out.append(str(m.get("props", {}).get("_markdown", m.get("props", {}).get("content", ""))))
        return out

    def uuid_of(self, kind: str, label: str) -> str:
        """The uuid of the control of message type ``kind`` (e.g. GuiSliderMessage) labelled ``label``."""
        for m in self.received:
            if m.get("type") == kind and m.get("props", {}).get("label") == label:
                return m["uuid"]
        raise AssertionError(f"no {kind} labelled {label!r} was received")

    def shown(self, kind: str, label: str) -> Any:
        """The value the control of message type ``kind`` labelled ``label`` shows now."""
        uuid = self.uuid_of(kind, label)
        value = next(m.get("value") for m in self.received if m.get("uuid") == uuid and m.get("type") == kind)
        updates = self.values_of(uuid)
        return updates[-1] if updates else value

    def notifications(self) -> list[str]:
        return [f"{m['props']['title']}: {m['props']['body']}" for m in self.seen("NotificationShowMessage")]

    @staticmethod
    async def until(condition: Any, what: str, timeout: float = 10.0) -> None:
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                raise AssertionError(f"timed out after {timeout} s waiting for {what}")
            await asyncio.sleep(0.02)

    async def settle(self, seconds: float = 0.3) -> None:
        """Give the server time to act on what was sent (for asserting that nothing happened)."""
        await asyncio.sleep(seconds)

    async def close(self) -> None:
        await self.ws.close()
        await asyncio.gather(self._reader, return_exceptions=True)
