"""The lab of a web build, inside the browser's Python: what the page's worker calls.

The worker (``templates/web/worker.js``) keeps one interpreter alive and calls, once per display
frame, ``lab.frame()`` (a *turn*: a short piece of code run by the interpreter's ``turn``
export). Data crosses through two files of the in-memory file system:

- :data:`INBOX`: the messages the page's viser client sent since the last turn, each a 4-byte
  little-endian length and the MessagePack bytes;
- :data:`OUTBOX`: what :meth:`WebLab.frame` wrote back, one batch in the format of
  :func:`ejsrl.web._server.encode_batch`, or nothing.

A lab is the served app's, with the served app's view: :class:`ejsrl.app.App` steps the model,
:class:`ejsrl.view.viser_view.ViserView` shows it through a real ``viser.ViserServer`` whose
websocket is the page (:mod:`ejsrl.web._server`), and every value a student sends is checked by
the same :class:`ejsrl.view._guard.MessageGuard` as served.
"""

from __future__ import annotations

import contextlib
import importlib
import io
import struct
import sys
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

from ejsrl.web._server import web_server


def _without_threads() -> None:
    """A browser tab's Python starts no thread: the watcher that names a slow ``init:`` (a
    thread, :func:`ejsrl.app._slow.watch_slow`) is left out there; the page shows that the lab
    is busy instead."""
    if sys.platform != "wasi":
        return
    from ejsrl.app import _loop

    _loop.watch_slow = lambda *_a, **_k: contextlib.nullcontext()  # type: ignore[assignment]


_without_threads()

__all__ = ["WebLab", "INBOX", "OUTBOX", "CSV", "open_lab"]

INBOX = "/io/inbox"
OUTBOX = "/io/outbox"
CSV = "/io/run.csv"
_LEN = struct.Struct("<I")


class WebLab:
    """One lab in one browser tab: its app (made when the page's client first shows itself,
    as a served tab's), the viser server standing in for the websocket, and the guard."""

    def __init__(self, module: ModuleType, *, base_dir: str | Path = ".") -> None:
        from ejsrl.app import App, SimConfig
        from ejsrl.view import _guard
        from ejsrl.view.viser_view import ViserView

        self.module = module
        self.base_dir = Path(base_dir)
        self.sim: SimConfig = getattr(module, "SIMULATION", SimConfig())
        self.app = App(module.Model, module.VIEW, sim=self.sim, meta=module.META, base_dir=self.base_dir)
        server, channel = web_server()
        guard = _guard.MessageGuard()
        guard.server = server
        _guard._GUARDS[server] = guard  # guard_of(server): the view registers its controls' checks
        channel.check = guard.check
        server.gui.configure_theme(show_share_button=False)  # as start_server does
        self.server, self.channel, self.guard = server, channel, guard
        self.view: Any = None
        app = self.app

        @server.on_client_connect
        def _(client: Any) -> None:  # the page's client sent its first camera: the panel, as served
            self.view = ViserView(app, server, client=client)
            app.views = [self.view]

        channel.connect()

    @property
    def fps(self) -> float:
        """The display frames per second the lab asks for."""
        return max(float(self.sim.fps), 1.0)

    def receive(self, data: bytes) -> int:
        """Hand the page's messages (``INBOX``'s format) to the server; how many were taken."""
        taken, pos = 0, 0
        while pos + 4 <= len(data):
            (n,) = _LEN.unpack_from(data, pos)
            raw = data[pos + 4 : pos + 4 + n]
            pos += 4 + n
            if len(raw) == n and self.channel.receive(raw):
                taken += 1
        return taken

    def frame(self, *, step: bool = True) -> bytes | None:
        """Read :data:`INBOX`, run one display frame (when ``step`` and the panel exists),
        write the outgoing batch to :data:`OUTBOX` and return it."""
        data = _read(INBOX)
        if data:
            self.receive(data)
        if step and self.view is not None:
            self.app.frame()
        out = self.channel.take()
        _write(OUTBOX, out or b"")
        return out

    def state(self, names: Sequence[str] = ()) -> dict[str, Any]:
        """The model's time, playing state, frame count, error and the values of the model
        variables ``names`` (floats, or lists for arrays), for the page and its tests."""
        model = self.app.model
        t = model._ejs_time() if model.INDEPENDENT is not None else None
        values = {}
        for name in names:
            if name in getattr(model, "VARIABLES", {}):
                value = getattr(model, name)
                values[name] = value.tolist() if hasattr(value, "tolist") else value
        return {"t": t, "playing": self.app.is_playing(), "frames": self.app.frame_count,
                "error": None if self.app.error is None else str(self.app.error.message), "values": values}


def headless_csv(module: ModuleType, duration: float, *, variables: Sequence[str] | None = None,
                 every: int = 1, path: str = CSV) -> int:
    """A headless run of the lab (a fresh app, as ``python app.py --headless --duration T --csv``
    makes it) written as CSV to ``path``; returns the run's exit status."""
    from ejsrl.app import App, SimConfig

    sim = getattr(module, "SIMULATION", SimConfig())
    base_dir = Path(getattr(module, "__file__", None) or ".").resolve().parent  # the lab's assets, as app.py finds them
    app = App(module.Model, module.VIEW, sim=sim, meta=module.META, base_dir=base_dir)
    log = io.StringIO()
    with open(path, "w", newline="") as f:
        return app.run_headless(duration, csv_file=f, variables=variables, every=every, log=log)


def open_lab(app_module: str = "app", *, lab_dir: str = "/lab") -> WebLab:
    """Import the built lab's ``app.py`` (found on ``sys.path``) and make its :class:`WebLab`."""
    module = importlib.import_module(app_module)
    return WebLab(module, base_dir=lab_dir)


def _read(path: str) -> bytes:
    try:
        with open(path, "rb") as f:
            return f.read()
    except FileNotFoundError:
        return b""
    finally:
        with contextlib.suppress(OSError):
            _write(path, b"") if path == INBOX else None


def _write(path: str, data: bytes) -> None:
    with open(path, "wb") as f:
        f.write(data)

