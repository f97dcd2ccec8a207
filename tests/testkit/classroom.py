"""A served class for the tests: the browser lab with a simulation per tab, a student's raw
websocket joining it, the session address the server gave it, and the time readouts it was sent
(tests/serve, tests/browser/test_classroom_browser.py and bench/classroom.py share them)."""

from __future__ import annotations

import contextlib
import re
from collections.abc import Iterator
from typing import Any

from testkit.guard_client import Client

__all__ = ["FULL", "join", "readouts", "served_classroom", "token_of"]

#: what the page of a full lab says
FULL = "This lab is full"
_TOKEN = re.compile(r"s/([A-Za-z0-9_-]{8,64})/'")
_READOUT = re.compile(r"^\*\*\w+\*\* = ([-+0-9.eE]+|nan|inf)")


@contextlib.contextmanager
def served_classroom(**options: Any) -> Iterator[tuple[Any, Any]]:
    """``(app, server)``: testkit.browser_lab's lab served on a free port with a simulation per
    client; ``options``: ``App.serve``'s (``max_sessions``, ``grace``, ...). Stopped after."""
    from testkit.browser_lab import make_app

    app = make_app()
    server = app.serve("127.0.0.1", 0, block=False, per_client=True, **options)
    try:
        yield app, server
    finally:
        app.stop()
        server.stop()


def token_of(client: Client) -> str | None:
    """The session token the server wrote into the client's address (its panel's script), or None."""
    for text in client.texts():
        match = _TOKEN.search(text)
        if match:
            return match.group(1)
    return None


async def join(port: int, path: str = "", cookie: str | None = None, *, timeout: float = 30.0, **open_kw: Any) -> Client:
    """A student's websocket on ``port`` (``path``: a session address, ``cookie``: its browser's),
    once it has its panel or the page saying the lab is full; ``open_kw``: ``Client.open``'s."""
    client = await Client.open(port, path=path, cookie=cookie, **open_kw)
    await client.until(lambda: token_of(client) is not None or FULL in " ".join(client.texts()), "the panel", timeout=timeout)
    return client


def readouts(client: Client) -> list[float]:
    """Every simulated time the client's time readout (``**t** = ...``) was sent: one per display frame."""
    out = []
    for m in client.received:
        if m.get("type") in ("GuiUpdateMessage", "GuiMarkdownMessage"):
            data = m.get("updates", m.get("props", {}))
            match = _READOUT.match(str(data.get("_markdown", data.get("content", ""))))
            if match:
                out.append(float(match.group(1)))
    return out
