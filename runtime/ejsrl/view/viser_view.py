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

import contextlib
import logging
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from ejsrl.view._guard import Verdict, guard_of, start_server
from ejsrl.view._gui import ControlBinding, Panel
from ejsrl.view._camera import ViewCamera
from ejsrl.view._scene_mirror import SceneMirror
from ejsrl.view._shared_camera import SharedCamera
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
    answer_as: str | None = None,
    banner: bool = True,
) -> tuple[Any, str]:
    """Start a viser server on ``host:port`` (the next free port if taken; 0: any free one)
    behind ejsgen's guards (:mod:`ejsrl.view._guard`): same-origin websockets only (plus
    ``allow_origins``), small messages, checked values.

    ``answer_as``, ``banner``: see :func:`ejsrl.view._guard.start_server`. Returns ``(server, url)`` with
    the port actually bound.
    """
    server = start_server(host, port, allow_origins=allow_origins, label=label, verbose=verbose, answer_as=answer_as,
                          banner=banner)
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


def _notify_red(client: Any, title: str, body: str) -> list[Any]:
    """The guard's notification of a refused value: to the client that sent it, kept until closed."""
    try:
        return [client.add_notification(title, body, color="red", auto_close_seconds=None)]
    except Exception:
        log.debug("notification to a client failed", exc_info=True)
        return []


class ViserView:
    """Shows ``app`` in the browser through ``server`` (a ``viser.ViserServer``).

    With ``client`` (a ``viser.ClientHandle``), the panel and the scene are that tab's own
    (``client.gui``, ``client.scene``): a simulation per browser tab. Without, they are
    the server's, which every tab shares. Builds the control panel and the 3D scene at
    construction; afterwards :meth:`on_frame` sends only what changed.
    """

    def __init__(self, app: Any, server: Any, *, client: Any = None) -> None:
        self.app = app
        self.server = server
        #: the one browser tab this view shows ``app`` to (a ``viser.ClientHandle``), or None:
        #: every tab sees the same panel and scene (``--shared``)
        self.client = client
        self.frames = 0
        #: frames not sent because the client had not yet received the previous ones
        self.skipped = 0
        #: set by a classroom while the client has not taken the last frames: frames are then
        #: not sent (plots still record their points)
        self.hold = False
        self._broken: set[str] = set()
        self._shared_camera: SharedCamera | None = None
        self._closed = False
        target = client if client is not None else server
        self._target = target
        target.scene.set_up_direction("+z")
        with target.atomic():
            clock = getattr(app, "clock", time.monotonic)
            self.panel = Panel(app, target.gui, self.notify, clock=clock)
            self.scene = SceneMirror(target.scene, on_gizmo=self._on_gizmo, clock=clock)
            #: the browser's camera: the spec's ``view``, ``set_view()``, follow (ejsrl.view._camera)
            self.camera = ViewCamera(app)
            self.reset_view_button: Any = None
            world = self._world()
            if world is not None:
                with app.lock:
                    self.scene.sync(world)
                if self.panel.has_scene:
                    self._add_reset_view(target.gui)
        self._guard = guard = guard_of(server)
        if guard is not None:
            guard.notify = _notify_red
            for b in self.panel.controls:
                guard.watch(b.handle, control_check(b))

        if client is not None:
            self._frame(client)
        else:

            @server.on_client_connect
            def _(client: Any) -> None:
                self._frame(client)
                for p in self.panel.plots:  # a new tab makes the shared charts with their points in
                    p.reshow()

    def _frame(self, client: Any) -> None:
        """The camera of a tab that connects: the spec's ``view`` with what code asked since, or
        a first view that frames the scene's content (metres, z up)."""
        try:
            with self.app.lock:
                self.camera.show([client.camera])
        except Exception:
            log.debug("framing the camera failed", exc_info=True)

    def _add_reset_view(self, gui: Any) -> None:
        """The panel's Restore view button: the camera back where the spec puts it, for every tab
        of this simulation (what ``set_view()`` asked is forgotten; the simulation goes on)."""
        self.reset_view_button = button = gui.add_button("Restore view", hint="Put the 3D view's camera back where the lab sets it")

        @button.on_click
        def _(_e: Any) -> None:
            from ejsrl.world.view3d import drop_commanded

            with self.app.lock:
                world = self._world()
                if world is not None:
                    drop_commanded(world)
                with self._target.atomic():
                    self.camera.show(self._frame_cameras())

    def _frame_cameras(self) -> list[Any]:
        """The cameras a frame (a followed object, ``set_view``) or Restore view moves: a tab's own;
        for a shared view, every tab's at once through the server's queue, with the frame's poses,
        so that a tab opened later is replayed the camera it now has (ejsrl.view._shared_camera)."""
        if self.client is not None:
            return self._cameras()
        if self._shared_camera is None:
            self._shared_camera = SharedCamera(self.server, self._cameras)
        return [self._shared_camera] if self.server.get_clients() else []

    def _cameras(self) -> list[Any]:
        """The cameras of every tab this view shows the app to."""
        if self.client is not None:
            return [] if self._closed else [self.client.camera]
        return [c.camera for c in self.server.get_clients().values() if hasattr(c, "camera")]

    @property
    def closed(self) -> bool:
        """True once :meth:`close` was called: the view sends nothing more."""
        return self._closed

    def close(self) -> None:
        """Forget this view's controls (its client is gone): the guard stops checking them."""
        if self._closed:
            return
        self._closed = True
        if self._guard is not None:
            self._guard.unwatch(b.handle for b in self.panel.controls)

    # -- called by the app's loop -------------------------------------------------------
    def on_frame(self) -> None:
        """Send this frame's changes (the caller holds ``app.lock``)."""
        if self._closed:
            return
        if self.hold:
            self.skipped += 1
            self._guarded("plots", self._record_plots)
            return
        self.frames += 1
        with contextlib.ExitStack() as held:
            held.enter_context(self._target.atomic())
            if self.client is None:  # a shared view: the tabs' cameras (their own queues) are held with the scene
                for c in list(self.server.get_clients().values()):
                    if hasattr(c, "atomic"):
                        held.enter_context(c.atomic())
            self._guarded("panel", self.panel.refresh)
            world = self._world()
            if world is not None:
                self._guarded("scene", lambda: self.scene.sync(world))
                self._guarded("camera", lambda: self.camera.on_frame(self._frame_cameras()))
            self._guarded("alerts", self._show_alerts)

    def adopt(self, old: ViserView) -> None:
        """Take over the plot data of ``old``, the same app's view in a tab that was reloaded."""
        for new, previous in zip(self.panel.plots, old.panel.plots):
            new.adopt(previous)

    def _record_plots(self) -> None:
        app = self.app
        for p in self.panel.plots:
            p.record(app)

    def on_reset(self) -> None:
        """Forget accumulated data (plot points, cached images) after a reset."""
        self._guarded("reset", self.panel.on_reset)

    # -- helpers ----------------------------------------------------------------------------
    def notify(self, client: Any, title: str, body: str, color: str = "blue", *, loading: bool = False) -> list[Any]:
        """Show a notification to ``client``, or to everyone this view shows the app to if
        None (its own client, or every connected client for a shared view).

        Red ones (errors) and ``loading`` ones (a spinner: something still going on, removed
        by its handle when it ends) stay until closed; returns the notification handles.
        """
        if client is not None:
            clients = [client]
        elif self.client is not None:
            clients = [] if self._closed else [self.client]
        else:
            clients = list(self.server.get_clients().values())
        auto_close = None if color == "red" or loading else 6.0
        handles = []
        for c in clients:
            try:
                handles.append(c.add_notification(title, body, color=color, auto_close_seconds=auto_close, loading=loading))
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
