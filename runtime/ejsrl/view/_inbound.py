"""What a client of a served app may send: every message is checked before viser decodes it.

Only the kinds the UI sends are let through (the viewer camera, a control's new
``value``, a gizmo drag), each with its fields checked and rebuilt; a control's value is
validated, clamped and typed by ejsgen's own rules (:class:`Verdict` from the control's
check) before viser stores or broadcasts it. A refused value is dropped, its sender told
why (at most once per control every :data:`ejsrl.view._fair.NOTIFY_SECONDS`) and its
control shows the server's value again. :func:`ejsrl.view._guard.start_server` puts a
:class:`MessageGuard` in front of every connection (and re-exports these names).
"""

from __future__ import annotations

import logging
import math
import time
import weakref
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from ejsrl.view import _fair

__all__ = ["MAX_COORDINATE", "Check", "MessageGuard", "Notify", "Verdict", "generic_check"]

log = logging.getLogger("ejsrl.serve")

#: the largest |coordinate| a client may send for a camera or gizmo position (metres)
MAX_COORDINATE = 1e6


@dataclass(frozen=True)
class Verdict:
    """What to do with one control value: ``ok`` with ``value`` (what the handle stores
    and every client shows), or refused with ``message`` for the user."""

    ok: bool
    value: Any = None
    message: str = ""


#: ``check(raw) -> Verdict`` for one control
Check = Callable[[Any], Verdict]


def _finite_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _vector(x: Any, n: int, bound: float = MAX_COORDINATE) -> tuple[float, ...] | None:
    if not isinstance(x, (list, tuple)) or len(x) != n:
        return None
    if not all(_finite_number(v) and abs(v) <= bound for v in x):
        return None
    return tuple(float(v) for v in x)


def _short_text(x: Any, limit: int = 1024) -> bool:
    return isinstance(x, str) and len(x) <= limit


def _unit_quaternion(x: Any) -> tuple[float, ...] | None:
    q = _vector(x, 4, 10.0)
    if q is None:
        return None
    norm = math.sqrt(sum(v * v for v in q))
    if not 0.5 <= norm <= 2.0:
        return None
    return tuple(v / norm for v in q)


def _camera(msg: dict[str, Any]) -> dict[str, Any] | None:
    """The viewer camera, rebuilt from its known fields, or None. Lenient (a hidden canvas
    has size 0): a browser whose first camera message is dropped is never registered."""
    wxyz = _unit_quaternion(msg.get("wxyz"))
    position = _vector(msg.get("position"), 3, 1e9)
    look_at = _vector(msg.get("look_at"), 3, 1e9)
    up = _vector(msg.get("up_direction"), 3, 1e9)
    fov, near, far = msg.get("fov"), msg.get("near"), msg.get("far")
    height, width = msg.get("image_height"), msg.get("image_width")
    if None in (wxyz, position, look_at, up):
        return None
    if not all(_finite_number(v) and 0 <= v <= 1e12 for v in (fov, near, far, height, width)):
        return None
    return {"type": "ViewerCameraMessage", "wxyz": wxyz, "position": position, "fov": float(fov),
            "near": float(near), "far": float(far), "image_height": int(round(height)),
            "image_width": int(round(width)),
            "look_at": look_at, "up_direction": up}


def _gizmo(msg: dict[str, Any]) -> dict[str, Any] | None:
    name, owner = msg.get("name"), msg.get("owner", "")
    if not _short_text(name) or not _short_text(owner, 64):
        return None
    if msg["type"] != "TransformControlsUpdateMessage":
        return {"type": msg["type"], "name": name, "owner": owner}
    wxyz = _unit_quaternion(msg.get("wxyz"))
    position = _vector(msg.get("position"), 3)
    if wxyz is None or position is None:
        return None
    return {"type": msg["type"], "name": name, "wxyz": wxyz, "position": position, "owner": owner}


_GIZMO_MESSAGES = ("TransformControlsUpdateMessage", "TransformControlsDragStartMessage",
                   "TransformControlsDragEndMessage")
_KNOWN = ("ViewerCameraMessage", "GuiUpdateMessage", *_GIZMO_MESSAGES)


def generic_check(handle: Any) -> Check:
    """The rules for a viser input that ejsgen did not register a check for: the value must
    already have the control's type (no casting), numbers finite and within the control's
    range, text at most :data:`ejsrl.view._validate.MAX_TEXT_LENGTH` characters, a dropdown
    one of its options; a button only takes a click."""
    import viser

    from ejsrl.view._validate import MAX_TEXT_LENGTH

    label = str(getattr(handle, "label", "") or "control")

    def refuse(why: str) -> Verdict:
        return Verdict(False, message=f"{label}: {why}; the value was not applied.")

    def check(raw: Any) -> Verdict:
        current = handle._impl.value
        if handle._impl.is_button:
            return Verdict(True, True) if raw is True else refuse("not a click")
        if isinstance(handle, viser.GuiDropdownHandle):
            return Verdict(True, raw) if isinstance(raw, str) and raw in handle.options else refuse("not one of the options")
        if isinstance(current, bool):
            return Verdict(True, raw) if isinstance(raw, bool) else refuse("not true or false")
        if isinstance(current, str):
            if not isinstance(raw, str) or len(raw) > MAX_TEXT_LENGTH:
                return refuse(f"not a text of at most {MAX_TEXT_LENGTH} characters")
            return Verdict(True, raw)
        if isinstance(current, (int, float)):
            if not _finite_number(raw):
                return refuse("not a finite number")
            x = float(raw)
            lo = getattr(handle._impl.props, "min", None)
            hi = getattr(handle._impl.props, "max", None)
            if lo is not None:
                x = max(x, float(lo))
            if hi is not None:
                x = min(x, float(hi))
            return Verdict(True, int(round(x)) if isinstance(current, int) else x)
        return refuse("this kind of control takes no value from the browser")

    return check


#: ``notify(client, title, body)``: tell one client (a ``viser.ClientHandle``) something
Notify = Callable[[Any, str, str], Any]


class MessageGuard:
    """Checks every message a client sends to ``server`` (a ``viser.ViserServer``) before
    viser decodes it; see the module docstring. ``checks`` maps a GUI input's uuid to the
    ejsgen check of its value (:meth:`watch`); other inputs get :func:`generic_check`.
    """

    def __init__(self) -> None:
        self.server: Any = None
        self.checks: dict[str, Check] = {}
        self.notify: Notify = _default_notify
        #: how many messages were dropped, by reason (for tests and logs)
        self.dropped: dict[str, int] = {}
        self._ready: weakref.WeakSet[Any] = weakref.WeakSet()
        self._log = _fair.QuietLog(log, "dropped client messages")
        #: per connection and control: when its sender was last told of a refusal (time.monotonic())
        self._notified: weakref.WeakKeyDictionary[Any, dict[str, float]] = weakref.WeakKeyDictionary()
        self._clients: weakref.WeakKeyDictionary[Any, Any] = weakref.WeakKeyDictionary()

    def forget(self, connection: Any) -> None:
        """``connection`` has closed: drop what was kept about it (its client handle holds
        the connection, so a weak key alone would never go)."""
        self._clients.pop(connection, None)
        self._notified.pop(connection, None)
        self._ready.discard(connection)

    def registered(self, connection: Any) -> bool:
        """True once ``connection`` has sent its first camera message."""
        return connection in self._ready

    def watch(self, handle: Any, check: Check) -> None:
        """Validate values sent for ``handle`` (a viser GUI input) with ``check``."""
        self.checks[handle._impl.uuid] = check

    def unwatch(self, handles: Iterable[Any]) -> None:
        """Forget the checks of ``handles`` (a closed tab's controls)."""
        for handle in handles:
            self.checks.pop(handle._impl.uuid, None)

    # -- called on viser's event loop, for every message ---------------------------------------
    def filter(self, connection: Any, raw: Any) -> bytes | None:
        """The message to hand to viser (possibly rewritten), or None to drop it."""
        checked = self.check(connection, raw)
        return None if checked is None else checked[0]

    def check(self, connection: Any, raw: Any) -> tuple[bytes, dict[str, Any]] | None:
        """The message to hand to viser as ``(bytes, message)`` (possibly rewritten), or None
        to drop it."""
        import msgspec

        if not isinstance(raw, (bytes, bytearray, memoryview)):
            return self._drop("not binary")
        try:
            msg = msgspec.msgpack.decode(raw)
        except (msgspec.DecodeError, RecursionError, ValueError):  # garbage, bad UTF-8, 64 kB of nested arrays
            return self._drop("not msgpack")
        if not isinstance(msg, dict) or not isinstance(msg.get("type"), str):
            return self._drop("no type")
        kind = msg["type"]
        if kind == "ViewerCameraMessage":
            out = _camera(msg)
            if out is None:
                return self._drop("bad camera")
            self._ready.add(connection)
        elif kind == "GuiUpdateMessage":
            if connection not in self._ready:
                return self._drop("before the first camera message")
            out = self._gui_update(connection, msg)
        elif kind in _GIZMO_MESSAGES:
            if connection not in self._ready:
                return self._drop("before the first camera message")
            out = _gizmo(msg)
        else:
            return self._drop(f"kind {kind[:60]}", kind="kind")
        if out is None:
            return self._drop(kind if kind in _KNOWN else "kind")
        return msgspec.msgpack.encode(out), out

    def _drop(self, why: str, *, kind: str | None = None) -> None:
        """Count a dropped message by ``why``; the first of each ``kind`` of reason (default
        ``why``) is logged, escaped (``why`` may carry a client's text)."""
        self._log(logging.INFO, kind or why, "ejsrl: dropped a client message (%s)", ascii(why))
        if why in self.dropped or len(self.dropped) < 256:
            self.dropped[why] = self.dropped.get(why, 0) + 1
        return None

    def _gui_update(self, connection: Any, msg: dict[str, Any]) -> dict[str, Any] | None:
        uuid, updates = msg.get("uuid"), msg.get("updates")
        if not isinstance(uuid, str) or not isinstance(updates, dict) or set(updates) != {"value"}:
            return None
        handle = self.server.gui._gui_input_handle_from_uuid.get(uuid) if self.server is not None else None
        if handle is None:  # a control of this tab's own panel (a simulation per tab)
            owner = self._client(connection)
            handle = owner.gui._gui_input_handle_from_uuid.get(uuid) if owner is not None else None
        if handle is None:
            return None
        check = self.checks.get(uuid) or generic_check(handle)
        raw = updates["value"]
        try:
            verdict = check(raw)
        except Exception:  # noqa: BLE001 - a broken check must refuse, not crash the connection
            self._log(logging.ERROR, "check failed", "ejsrl: checking a value for %s failed", uuid, exc_info=True)
            verdict = Verdict(False, message="the value could not be checked; it was not applied.")
        if not verdict.ok:
            client = self._client(connection)
            if client is not None:
                self._show(client, uuid, handle._impl.value)
                now, notified = time.monotonic(), self._notified.setdefault(connection, {})
                if now - notified.get(uuid, -math.inf) >= _fair.NOTIFY_SECONDS and len(notified) < 256:
                    notified[uuid] = now
                    try:
                        self.notify(client, "Value refused", verdict.message)
                    except Exception:  # noqa: BLE001
                        log.debug("notifying a client failed", exc_info=True)
            return self._drop("refused value")
        if not (type(verdict.value) is type(raw) and verdict.value == raw):
            client = self._client(connection)
            if client is not None:  # viser echoes to the others only: show the sender the clamped value
                self._show(client, uuid, verdict.value)
        return {"type": "GuiUpdateMessage", "uuid": uuid, "updates": {"value": verdict.value}}

    def _client(self, connection: Any) -> Any:
        server = self.server
        if server is None:
            return None
        known = self._clients.get(connection)
        if known is not None:
            return known
        for client_id, conn in list(server._websock_server._live_connections.items()):
            if conn is connection:
                client = server._connected_clients.get(client_id)
                if client is not None:
                    self._clients[connection] = client
                return client
        return None

    @staticmethod
    def _show(client: Any, uuid: str, value: Any) -> None:
        """Make ``client``'s control ``uuid`` show ``value`` (only that client)."""
        from viser._messages import GuiUpdateMessage

        client._websock_connection.queue_message(GuiUpdateMessage(uuid, {"value": value}))


def _default_notify(client: Any, title: str, body: str) -> Any:
    return client.add_notification(title, body, color="red")
