"""The web UI of a generated app: a viser control panel and a 3D view of the world.

The app creates the server and the view, then calls :meth:`ViserView.on_frame` after
every display frame (with ``app.lock`` held) and :meth:`ViserView.on_reset` after a reset.

What the view needs from the app (``ejsrl.app.App`` provides it):

- ``model``, ``lock`` (an ``RLock`` guarding the model), ``world``, ``view`` (elements),
  ``meta`` (``title``, ``description``, ``author``), ``sim`` (``controls``, ...);
- ``play()``, ``pause()``, ``step_once()``, ``reset()``, ``is_playing()``;
- ``apply_control(control, value)`` (value already validated), ``run_action(button)``,
  ``apply_gizmo(name, T_world)``;
- ``safe_value(prop, where)`` (None on a user-code error), ``error`` / ``error_rev``,
  ``pop_alerts()``;
- optionally ``clock()`` (monotonic seconds; default ``time.monotonic``): the time of the
  view's own timers (a user's hold on a control, the plots' and images' rates, gizmo drags).

On a server made by :func:`make_server` every value a browser sends for a control is
checked by :func:`ejsrl.view._validate.validate_control` before viser stores or broadcasts
it (see :mod:`ejsrl.view._guard`); the panel checks it again before applying it.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from ejsrl.view._guard import Verdict, guard_of, start_server
from ejsrl.view._gui import ControlBinding, Panel
from ejsrl.view._framing import frame_camera
from ejsrl.view._scene_mirror import SceneMirror
from ejsrl.view._validate import validate_control

__all__ = ["ViserView", "make_server", "control_check"]

log = logging.getLogger("ejsrl.view")


def make_server(
    host: str = "127.0.0.1",
    port: int = 8080,
    *,
    allow_origins: Sequence[str] = (),
    label: str | None = None,
    verbose: bool = False,
) -> tuple[Any, str]:
    """Start a viser server on ``host:port`` (the next free port if taken; 0: any free one)
    behind ejsgen's guards (:mod:`ejsrl.view._guard`): same-origin websockets only (plus
    ``allow_origins``), small messages, checked values.

    Returns ``(server, url)`` with the port actually bound.
    """
    server = start_server(host, port, allow_origins=allow_origins, label=label, verbose=verbose)
    shown_host = "127.0.0.1" if host in ("0.0.0.0", "", "::") else host
    if ":" in shown_host:
        shown_host = f"[{shown_host}]"
    return server, f"http://{shown_host}:{server.get_port()}"


def control_check(b: ControlBinding) -> Any:
    """The check of a value sent for ``b``'s control: ejsgen's validation (typing,
    clamping, options), then the form the control's handle shows."""
    name = b.control.title

    def check(raw: Any) -> Verdict:
        checked = validate_control(b.control, raw)
        if not checked.ok:
            return Verdict(False, message=checked.message)
        shown = b.display(checked.value)
        if shown is None:
            return Verdict(False, message=f"{name}: {checked.value!r} cannot be shown; the value was not applied.")
        return Verdict(True, shown)

    return check


class ViserView:
    """Shows ``app`` in the browser through ``server`` (a ``viser.ViserServer``).

    Builds the control panel and the 3D scene at construction; afterwards
    :meth:`on_frame` sends only what changed.
    """

    def __init__(self, app: Any, server: Any) -> None:
        self.app = app
        self.server = server
        self.frames = 0
        self._broken: set[str] = set()
        server.scene.set_up_direction("+z")
        with server.atomic():
            clock = getattr(app, "clock", time.monotonic)
            self.panel = Panel(app, server.gui, self.notify, clock=clock)
            self.scene = SceneMirror(server.scene, on_gizmo=self._on_gizmo, clock=clock)
            world = self._world()
            if world is not None:
                with app.lock:
                    self.scene.sync(world)
        guard = guard_of(server)
        if guard is not None:
            guard.notify = lambda client, title, body: self.notify(client, title, body, "red")
            for b in self.panel.controls:
                guard.watch(b.handle, control_check(b))

        @server.on_client_connect
        def _(client: Any) -> None:
            # a first view that frames the scene's content (metres, z up)
            try:
                frame_camera(client.camera, self._world(), app.lock)
            except Exception:
                log.debug("framing the camera failed", exc_info=True)

    # -- called by the app's loop -------------------------------------------------------
    def on_frame(self) -> None:
        """Send this frame's changes (the caller holds ``app.lock``)."""
        self.frames += 1
        with self.server.atomic():
            self._guarded("panel", self.panel.refresh)
            world = self._world()
            if world is not None:
                self._guarded("scene", lambda: self.scene.sync(world))
            self._guarded("alerts", self._show_alerts)

    def on_reset(self) -> None:
        """Forget accumulated data (plot points, cached images) after a reset."""
        self._guarded("reset", self.panel.on_reset)

    # -- helpers ----------------------------------------------------------------------------
    def notify(self, client: Any, title: str, body: str, color: str = "blue") -> list[Any]:
        """Show a notification to ``client``, or to every connected client if None.

        Red ones (errors) stay until closed; returns the notification handles.
        """
        clients = [client] if client is not None else list(self.server.get_clients().values())
        auto_close = None if color == "red" else 6.0
        handles = []
        for c in clients:
            try:
                handles.append(c.add_notification(title, body, color=color, auto_close_seconds=auto_close))
            except Exception:
                log.debug("notification to a client failed", exc_info=True)
        return handles

    def _show_alerts(self) -> None:
        pop = getattr(self.app, "pop_alerts", None)
        if pop is None:
            return
        for text in pop():
            self.notify(None, "Alert", str(text), "yellow")

    def _world(self) -> Any:
        """The app's world, or None for an app without a scene."""
        try:
            return getattr(self.app, "world", None)
        except RuntimeError:
            return None

    def _on_gizmo(self, name: str, T_world: np.ndarray) -> None:
        self.app.apply_gizmo(name, T_world)

    def _guarded(self, what: str, fn: Any) -> None:
        """Run one part of the refresh; a bug in one part must not stop the others or the app."""
        try:
            fn()
        except Exception:
            if what not in self._broken:
                self._broken.add(what)
                log.exception("ejsrl.view: updating the %s failed", what)
