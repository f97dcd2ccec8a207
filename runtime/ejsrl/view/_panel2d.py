"""A 2D canvas panel in viser's control panel: the engine of drawing panels and plots.

:class:`Panel2D` adds a canvas to viser's GUI at the current place (inside folders and
tabs) and draws *frames* on it: JSON-able dicts of world bounds, axes, a legend and items
(polylines, markers, circles, segments, arrows, rects, text, images; see the contract in
``specs/reference.md``, "2D panels"). The client engine (``_panel2d.js``, installed once
per page as ``window.__ejs2d``) draws vectors on a canvas sized to CSS px x
devicePixelRatio, so a panel is crisp at any zoom; text is drawn with ``fillText``, so
nothing in a frame can become markup.

Three viser GUI elements make one panel:

- the canvas: an HTML element that never changes (React may remount it when a folder or
  tab is closed and opened again: the engine then binds the new canvas and redraws);
- the frame: an HTML element whose content is the last frame as JSON (``<``, ``>``, ``&``
  escaped as ``\\u003c`` ...) in an inert ``<script type="application/json">``, with an
  ``<img onerror>`` that hands it to the engine; only a frame that differs from the last
  one sent is sent;
- the events: a hidden text input that the engine writes (at most one message per 60 ms,
  ``{"s": seq, "e": [event, ...]}``). :func:`parse_events` checks a message strictly
  (size, JSON, exact keys, finite numbers, allow-listed keys) and drops anything else;
  valid events reach ``on_event`` in the order they were sent, outside any app lock.

Each browser tab has its own page, engine and GUI (``client.gui``), so panels, frames and
events are per session.
"""

from __future__ import annotations

import base64
import collections
import html
import json
import logging
import math
import re
import threading
import time
from collections.abc import Callable
from importlib import resources
from typing import Any

import numpy as np

__all__ = [
    "Panel2D",
    "encode_xy",
    "parse_events",
    "frame_json",
    "engine_js",
    "ALLOWED_KEYS",
    "MAX_MESSAGE_CHARS",
    "MAX_EVENTS",
    "MAX_ABS",
]

log = logging.getLogger("ejsrl.view")

#: the longest events message accepted (characters); longer ones are dropped whole
MAX_MESSAGE_CHARS = 4096
#: the most events one message may carry (the engine sends at most 24)
MAX_EVENTS = 32
#: the largest |coordinate| an event may carry (world units)
MAX_ABS = 1e9
#: the events a panel accepts per second at most (a burst of this many, refilled over a second)
MAX_EVENTS_PER_SECOND = 200.0
#: the keys a panel reports: letters, digits, arrows, space, Enter, Escape, + and -
ALLOWED_KEYS = frozenset(
    [chr(c) for c in range(ord("a"), ord("z") + 1)]
    + [chr(c) for c in range(ord("A"), ord("Z") + 1)]
    + [str(d) for d in range(10)]
    + ["ArrowUp", "ArrowDown", "ArrowLeft", "ArrowRight", " ", "Enter", "Escape", "+", "-"]
)
#: a panel of automatic height is at least this high (CSS px) ...
AUTO_MIN_HEIGHT = 120
#: ... and at most the window's height less this (CSS px: the panel's header and a margin)
AUTO_HEIGHT_RESERVE = 100
_ID = re.compile(r"[A-Za-z0-9_.:\-]{1,64}")
_DRAG_PHASES = ("start", "move", "release")
_KEY_PHASES = ("down", "up")


def encode_xy(array: Any) -> str:
    """``array`` ((N, 2) or (N, 4) numbers) as base64 of little-endian float32, row-major.

    Rows with NaN stay NaN (a polyline breaks there). Raises ``ValueError`` for another shape.
    """
    a = np.asarray(array, dtype="<f4")
    if a.ndim == 1 and a.size in (0, 2, 4):
        a = a.reshape(-1, max(a.size, 2))
    if a.ndim != 2 or a.shape[1] not in (2, 4):
        raise ValueError(f"encode_xy needs an (N, 2) or (N, 4) array, got shape {a.shape}")
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def _finite_json(obj: Any) -> Any:
    """``obj`` with non-finite floats as None (JSON has no NaN) and NumPy scalars as Python's."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k): _finite_json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite_json(v) for v in obj]
    if isinstance(obj, np.generic):
        return _finite_json(obj.item())
    if isinstance(obj, np.ndarray):
        return _finite_json(obj.tolist())
    return obj


def frame_json(frame: dict[str, Any]) -> str:
    """``frame`` as JSON safe inside HTML: ``<``, ``>``, ``&`` written ``\\u003c`` ``\\u003e`` ``\\u0026``."""
    try:
        text = json.dumps(frame, separators=(",", ":"), allow_nan=False)
    except (ValueError, TypeError):
        text = json.dumps(_finite_json(frame), separators=(",", ":"), allow_nan=False, default=str)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


_ENGINE: str | None = None


def engine_js() -> str:
    """The client engine's source (``_panel2d.js``), read with importlib.resources (works from a .pyz)."""
    global _ENGINE
    if _ENGINE is None:
        _ENGINE = resources.files("ejsrl.view").joinpath("_panel2d.js").read_text(encoding="utf-8")
    return _ENGINE


def _number(v: Any) -> float | None:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    x = float(v)
    return x if math.isfinite(x) and abs(x) <= MAX_ABS else None


def _reject_constant(name: str) -> Any:
    raise ValueError(f"non-finite number {name}")


def _event(raw: Any) -> dict[str, Any] | None:
    """One event rebuilt from its allowed fields, or None."""
    if not isinstance(raw, dict):
        return None
    kind = raw.get("k")
    if kind == "drag":
        if not set(raw) <= {"k", "id", "phase", "x", "y", "i"} or not {"k", "id", "phase", "x", "y"} <= set(raw):
            return None
        ident, phase = raw["id"], raw["phase"]
        x, y = _number(raw["x"]), _number(raw["y"])
        if not isinstance(ident, str) or not _ID.fullmatch(ident) or phase not in _DRAG_PHASES or x is None or y is None:
            return None
        out: dict[str, Any] = {"k": "drag", "id": ident, "phase": phase, "x": x, "y": y}
        if "i" in raw:
            i = raw["i"]
            if isinstance(i, bool) or not isinstance(i, int) or not 0 <= i < 1_000_000:
                return None
            out["i"] = i
        return out
    if kind == "key":
        if set(raw) != {"k", "key", "phase"}:
            return None
        key, phase = raw["key"], raw["phase"]
        if not isinstance(key, str) or key not in ALLOWED_KEYS or phase not in _KEY_PHASES:
            return None
        return {"k": "key", "key": key, "phase": phase}
    if kind == "click":
        if set(raw) != {"k", "x", "y"}:
            return None
        x, y = _number(raw["x"]), _number(raw["y"])
        if x is None or y is None:
            return None
        return {"k": "click", "x": x, "y": y}
    return None


def parse_events(raw: Any) -> tuple[int, list[dict[str, Any]]] | None:
    """A message of the engine, checked: ``(seq, events)``, or None to drop it whole.

    The message must be a string of at most :data:`MAX_MESSAGE_CHARS` characters holding
    JSON ``{"s": seq, "e": [event, ...]}`` (no NaN or Infinity, at most :data:`MAX_EVENTS`
    events). Each event is rebuilt from its allowed fields; an event with an unknown kind
    or key, a missing or extra field, a non-finite or huge number, or a key outside
    :data:`ALLOWED_KEYS` is left out. Events (world coordinates):
    ``{"k": "drag", "id", "phase": start|move|release, "x", "y"[, "i": row of a set]}``,
    ``{"k": "key", "key", "phase": down|up}``, ``{"k": "click", "x", "y"}``.
    """
    if not isinstance(raw, str) or len(raw) > MAX_MESSAGE_CHARS:
        return None
    try:
        msg = json.loads(raw, parse_constant=_reject_constant)
    except (ValueError, RecursionError):
        return None
    if not isinstance(msg, dict) or set(msg) != {"s", "e"}:
        return None
    seq, events = msg["s"], msg["e"]
    if isinstance(seq, bool) or not isinstance(seq, int) or not 0 <= seq < 2**53 or not isinstance(events, list):
        return None
    if len(events) > MAX_EVENTS:
        return None
    out = [e for e in (_event(ev) for ev in events) if e is not None]
    return seq, out


def _canvas_html(dom_id: str, key: str, input_uuid: str, height: int, scene_keys: bool = False,
                 keys: list[str] | None = None, auto_height: bool = False) -> str:
    """The canvas (and the engine, installed once per page), never changed afterwards;
    ``scene_keys``: no canvas to see (height 0), the keys of the 3D view instead; ``keys``:
    the only keys reported (browser names), None for all of :data:`ALLOWED_KEYS`;
    ``auto_height``: the engine sets the height from each frame's bounds (equal aspect: the
    requested window fills the plot area; within :data:`AUTO_MIN_HEIGHT` and the window's
    height less :data:`AUTO_HEIGHT_RESERVE`), ``height`` being the first guess."""
    only = "" if keys is None else f' data-keys="{html.escape(json.dumps(sorted(k for k in keys if k in ALLOWED_KEYS)))}"'
    engine = html.escape(engine_js() + ";window.__ejs2d.mount(this);", quote=True)
    hide = f'div:has(> div > div > p > label[for="{input_uuid}"]){{display:none!important}}'
    return (
        # the frame's element changes every frame: contained, so the panel around it is not laid out again
        f"<style>{hide}.ejs2d-c:focus{{outline:2px solid #4dabf7;outline-offset:-2px}}"
        "div:has(> script[data-ejs2d-frame]){contain:strict;height:0;overflow:hidden}</style>"
        f'<div data-ejs2d="{html.escape(dom_id)}" data-key="{html.escape(key)}" data-ev="{html.escape(input_uuid)}"'
        f'{" data-scene-keys=1" if scene_keys else ""}{only}'
        f'{f" data-auto-height={AUTO_MIN_HEIGHT},{AUTO_HEIGHT_RESERVE}" if auto_height else ""} '
        f'style="width:100%;height:{int(height)}px;position:relative">'
        f'<canvas class="{"ejs2d-k" if scene_keys else "ejs2d-c"}" tabindex="{-1 if scene_keys else 0}" '
        f'style="width:100%;height:100%;display:block;touch-action:none"></canvas></div>'
        f'<img alt="" style="display:none" src="data:," onerror="{engine}">'
    )


_FRAME_HOOK = "(window.__ejs2dq=window.__ejs2dq||[]).push(this);window.__ejs2d&&window.__ejs2d.drain()"


def _frame_html(dom_id: str, payload: str) -> str:
    return (
        f'<script type="application/json" data-ejs2d-frame="{html.escape(dom_id)}">{payload}</script>'
        f'<img alt="" style="display:none" src="data:," onerror="{_FRAME_HOOK}">'
    )


class Panel2D:
    """A canvas panel in ``gui`` (viser's ``server.gui`` or a tab's ``client.gui``), added at
    the current place.

    ``key``: a name for the panel, unique in its GUI (the canvas carries it as
    ``data-key``); ``height``: CSS pixels; ``on_event(event)``: called with each valid
    event (see :func:`parse_events`), in order, with no app lock held;
    ``max_rate``: the most frames a second sent, on average (a frame refused by the rate is
    kept and sent by the next :meth:`show` or :meth:`flush`); ``clock``: monotonic seconds;
    ``scene_keys``: a panel of height 0 that reports the keys pressed while the 3D view has
    the focus (the 3D view was clicked last) instead of its own; ``keys``: the only keys the
    browser reports and takes from the page (browser names, ``" "`` for Space; None: every
    allowed key), so that the 3D view's own keys (its camera's) keep working;
    ``auto_height``: the browser sets the panel's height from each frame (see :func:`_canvas_html`).
    """

    def __init__(
        self,
        gui: Any,
        key: str,
        height: int = 240,
        on_event: Callable[[dict[str, Any]], None] | None = None,
        *,
        max_rate: float = 60.0,
        clock: Callable[[], float] = time.monotonic,
        scene_keys: bool = False,
        keys: list[str] | None = None,
        auto_height: bool = False,
    ) -> None:
        self.gui = gui
        self.key = str(key)
        self.height = int(height)
        self.on_event = on_event
        self.max_rate = float(max_rate)
        self.clock = clock
        self.sent = 0
        #: events dropped (malformed message, unknown kind or field, over the rate)
        self.dropped = 0
        self._last_text: str | None = None
        self._pending: str | None = None
        self._last_push = clock()
        self._budget = 1.0
        self._seq = -1
        self._tokens = MAX_EVENTS_PER_SECOND
        self._token_time = clock()
        self._queue: collections.deque[dict[str, Any]] = collections.deque()
        self._lock = threading.Lock()
        self._deliver_lock = threading.Lock()
        self._visible = True
        # the events input first: the canvas names its uuid (the engine writes it, a style hides it)
        self.events = gui.add_text("ejs2d events", "")
        self.dom_id = f"{_slug(self.key)}-{self.events._impl.uuid[:8]}"
        self.canvas = gui.add_html(_canvas_html(self.dom_id, self.key, self.events._impl.uuid, self.height, scene_keys, keys, auto_height))
        self.frame = gui.add_html(_frame_html(self.dom_id, "null"))
        self.events.on_update(self._on_message)

    # -- frames ---------------------------------------------------------------------------------
    def show(self, frame: dict[str, Any]) -> bool:
        """Send ``frame`` if it differs from the last one sent and the rate allows (else keep
        it for the next call); returns True if sent."""
        text = frame_json(frame)
        if text == self._last_text:
            self._pending = None
            return False
        self._pending = text
        return self.flush()

    def flush(self) -> bool:
        """Send the frame kept back by the rate, if its time has come; True if sent."""
        text = self._pending
        if text is None:
            return False
        now = self.clock()
        # a budget of frames refilled at max_rate a second (at most 2 kept): frames that come at
        # the rate but a little early (a 60 frames/s lab's ticks jitter) are not refused
        refill = math.inf if math.isinf(self.max_rate) else (now - self._last_push) * self.max_rate  # no 0 * inf
        self._budget = min(2.0, self._budget + refill)
        self._last_push = now
        if self._budget < 1.0:
            return False
        self._budget -= 1.0
        self.frame.content = _frame_html(self.dom_id, text)
        self._last_text, self._pending = text, None
        self.sent += 1
        return True

    @property
    def last_frame(self) -> dict[str, Any] | None:
        """The last frame sent, as the client got it (None before the first)."""
        return None if self._last_text is None else json.loads(self._last_text)

    @property
    def visible(self) -> bool:
        return self._visible

    @visible.setter
    def visible(self, value: bool) -> None:
        self._visible = bool(value)
        self.canvas.visible = self._visible
        self.frame.visible = self._visible

    def remove(self) -> None:
        """Take the panel out of the GUI."""
        for h in (self.frame, self.canvas, self.events):
            try:
                h.remove()
            except Exception:  # noqa: BLE001 - already gone
                pass

    # -- events -----------------------------------------------------------------------------------
    async def _on_message(self, event: Any) -> None:
        """viser's callback (on its event loop, in the order messages arrive): parse, queue, deliver."""
        if getattr(event, "client", None) is None:
            return
        import asyncio  # here, on viser's loop: a lab's start (headless, in a browser) does not load it

        self.receive(self.events._impl.value, deliver=False)
        await asyncio.get_running_loop().run_in_executor(None, self.deliver)

    def receive(self, raw: Any, *, deliver: bool = True) -> list[dict[str, Any]]:
        """Check a message (as the engine sends it) and queue its valid events; with
        ``deliver`` (tests, scripted input) hand them to ``on_event`` now. Returns the events kept."""
        parsed = parse_events(raw)
        if parsed is None:
            self.dropped += 1
            return []
        seq, events = parsed
        with self._lock:
            if seq <= self._seq:  # a replay, or an older message
                self.dropped += 1
                return []
            self._seq = seq
            now = self.clock()
            self._tokens = min(MAX_EVENTS_PER_SECOND, self._tokens + (now - self._token_time) * MAX_EVENTS_PER_SECOND)
            self._token_time = now
            kept = []
            for ev in events:
                if self._tokens < 1.0:
                    self.dropped += 1
                    continue
                self._tokens -= 1.0
                kept.append(ev)
            self._queue.extend(kept)
        if deliver:
            self.deliver()
        return kept

    def deliver(self) -> None:
        """Hand the queued events to ``on_event``, oldest first (one caller at a time)."""
        with self._deliver_lock:
            self._deliver()

    def _deliver(self) -> None:
        while True:
            with self._lock:
                if not self._queue:
                    return
                ev = self._queue.popleft()
                handler = self.on_event
            if handler is None:
                continue
            try:
                handler(ev)
            except Exception:  # noqa: BLE001 - a broken handler must not stop the panel
                log.exception("ejsrl.view: handling a 2D panel event failed")


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_-]+", "-", text)[:40] or "panel"
