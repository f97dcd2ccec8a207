"""Live editing: a lab served from one process whose model is replaced while its tabs stay open.

``ejsgen run --watch`` builds the spec, loads the built ``app.py`` in its own process
(:func:`load_build`) and serves it with a :class:`LiveLab`: a simulation per tab, as a
served app does (:class:`ejsrl.app._sessions.Classroom`), from this one process.

- **A good rebuild** (:meth:`LiveLab.swap`): every session (an open tab, or one closed
  less than the grace period ago) gets a new ``App`` made from the new build. The values
  of the variables the author did not change are carried over (:func:`carry_over`), and
  so are the playing state and the tab's session token (its address). An open tab's panel
  and 3D scene are built again in place (``client.gui.reset()``, ``client.scene.reset()``,
  a new view), its camera kept where the user left it, and a strip chart whose
  expressions did not change keeps its points.
- **A failed build** (:meth:`LiveLab.show_error`): every tab shows the error (escaped: a
  spec may hold markup) instead of its lab, and so does a tab that connects meanwhile;
  the sessions wait, paused. The next good build brings every lab back.

Which variables keep their values is the tool's rule (``ejsgen._watch``); here a name
given as kept is carried over only if the new model declares it with the same value type
and its current value has the kind and shape of the new initial value.
"""

from __future__ import annotations

import html
import importlib.util
import itertools
import logging
import sys
import threading
import time
import warnings
from collections.abc import Collection
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ejsrl.app._loop import App, AppMeta, SimConfig
from ejsrl.sim.model import ModelBase

__all__ = ["Build", "LiveLab", "SwapReport", "load_build", "carry_over", "error_html"]

log = logging.getLogger("ejsrl.serve")

#: tabs served at once by default while live editing (an author's own tabs, not a class)
DEFAULT_SESSIONS = 16
_names = itertools.count(1)


@dataclass(frozen=True)
class Build:
    """What a built ``app.py`` defines, loaded in this process.

    ``model_cls``: its ``Model``; ``view``: its ``VIEW`` elements; ``sim``, ``meta``: its
    run settings and About text; ``base_dir``: the app folder (its assets);
    ``overrides``: ``--set`` values for this build's variables; ``module``: the module's
    name in ``sys.modules`` (error locations read its ``SPEC_LINES`` there).
    """

    model_cls: type[ModelBase]
    view: list[Any]
    sim: SimConfig
    meta: AppMeta
    base_dir: Path
    module: str
    overrides: dict[str, Any] = field(default_factory=dict)

    def make_app(self) -> App:
        """A new ``App`` of this build (initial state, paused)."""
        app = App(self.model_cls, self.view, sim=self.sim, meta=self.meta, base_dir=self.base_dir,
                  overrides=self.overrides)
        app.playing = False  # a swap or a tab's attach decides (an autoplaying lab plays on attach)
        return app


def load_build(app_dir: Path | str) -> Build:
    """Import ``app_dir/app.py`` under a name of its own and return what it defines.

    Each call loads a new module (a rebuilt ``Model`` class), registered in ``sys.modules``
    until :func:`forget_build`; an error while importing is raised as it is.
    """
    folder = Path(app_dir).resolve()
    name = f"ejs_live_app_{next(_names)}"
    spec = importlib.util.spec_from_file_location(name, folder / "app.py")
    if spec is None or spec.loader is None:
        raise FileNotFoundError(f"no app.py in {folder}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        sys.modules.pop(name, None)
        raise
    sim = getattr(module, "SIMULATION", SimConfig())
    return Build(module.Model, module.VIEW, sim, module.META, folder, name)


def forget_build(build: Build) -> None:
    """Drop a build's module from ``sys.modules`` (no session uses it any more)."""
    sys.modules.pop(build.module, None)


# -- carrying values over --------------------------------------------------------------------------


def _same_kind(old: Any, new: Any) -> bool:
    """Whether ``old`` may stand in for ``new``: arrays of the same shape and dtype kind,
    numbers for numbers (booleans apart), text for text, else values of the same type."""
    if isinstance(old, np.ndarray) or isinstance(new, np.ndarray):
        return (isinstance(old, np.ndarray) and isinstance(new, np.ndarray) and old.shape == new.shape
                and old.dtype.kind == new.dtype.kind)
    if isinstance(old, (bool, np.bool_)) or isinstance(new, (bool, np.bool_)):
        return isinstance(old, (bool, np.bool_)) and isinstance(new, (bool, np.bool_))
    if isinstance(old, (int, float, np.integer, np.floating)) and isinstance(new, (int, float, np.integer, np.floating)):
        return isinstance(old, (int, np.integer)) == isinstance(new, (int, np.integer)) or isinstance(new, (float, np.floating))
    if isinstance(old, (list, tuple)) and isinstance(new, (list, tuple)):
        return type(old) is type(new) and len(old) == len(new)
    return type(old) is type(new)


def _root(bind: str) -> str:
    """The variable a bind target names: ``q[2]`` -> ``q``, ``arm.q`` -> ``arm``."""
    for sep in ("[", "."):
        bind = bind.split(sep, 1)[0]
    return bind.strip()


def carry_over(old: App, new: App, kept: Collection[str]) -> list[str]:
    """Give ``new``'s model the current values of the variables ``kept`` of ``old``'s model.

    A name is carried over only if both models declare it with the same value type and
    its current value has the kind and shape of ``new``'s initial value (a changed array
    size gives the new array). The values the user set from the view (which
    ``initialize()`` keeps) follow their variables. Then ``new`` runs its fixed relations
    and restarts its solvers (their state was changed from outside). Returns the names
    carried over, in declaration order.
    """
    carried: list[str] = []
    with old.lock, new.lock:
        om, nm = old.model, new.model
        for name in nm.VARIABLES:
            if name not in kept or om.VARIABLES.get(name) != nm.VARIABLES[name]:
                continue
            try:
                value, fresh = getattr(om, name), getattr(nm, name)
            except AttributeError:
                continue
            if _same_kind(value, fresh):
                setattr(nm, name, value.copy() if isinstance(value, np.ndarray) else value)
                carried.append(name)
        names = set(carried)
        for key, (setter, value) in old.user_values.items():
            if _root(key) in names:
                new.user_values[key] = (setter, value)
        if new.error is None:
            new.guard(nm._fixed_relations)
            nm._ejs_restart_solvers()
    return carried


# -- the error page ---------------------------------------------------------------------------------

_ERROR_PAGE = (
    '<div style="padding:4px 2px">'
    '<div style="color:#c92a2a;font-weight:700;font-size:1.1em;margin-bottom:4px">The spec does not build</div>'
    '<div style="margin-bottom:8px">Fix it and save: the lab comes back on the next good build, '
    "with the values you did not change.</div>"
    '<pre class="ejs-build-error" style="white-space:pre-wrap;word-break:break-word;font-size:12px;'
    'background:#fff5f5;border:1px solid #ffc9c9;border-radius:4px;padding:8px;margin:0">{text}</pre></div>'
)
#: the panel's width while it shows a build error (pixels)
ERROR_WIDTH = 720.0


def error_html(text: str) -> str:
    """The error page's HTML: ``text`` (the build's error report) escaped, never markup."""
    return _ERROR_PAGE.format(text=html.escape(text, quote=True))


# -- the served lab ---------------------------------------------------------------------------------


@dataclass
class SwapReport:
    """What a swap did: ``seconds`` it took, ``tabs`` rebuilt in place, ``sessions``
    swapped in all (closed tabs' too), the names ``carried`` over (in the last session
    swapped; None when there was none)."""

    seconds: float
    tabs: int
    sessions: int
    carried: list[str] | None


class LiveLab:
    """A lab served from this process whose build can be replaced (see the module docstring).

    ``max_sessions``: tabs served at once; ``grace``: seconds a closed tab's session is kept.
    :meth:`start` serves; :meth:`swap` and :meth:`show_error` are called from the thread
    that watches the spec, any number of times; :meth:`stop` stops serving.
    """

    def __init__(self, *, max_sessions: int = DEFAULT_SESSIONS, grace: float | None = None) -> None:
        from ejsrl.app._sessions import GRACE_SECONDS

        self.max_sessions = max_sessions
        self.grace = GRACE_SECONDS if grace is None else grace
        self.build: Build | None = None
        #: the failed build's report while one is shown (None: the lab is shown)
        self.error: str | None = None
        self.server: Any = None
        self.classroom: Any = None
        #: tabs that connected while a build error was shown: they get a session on the next good build
        self._parked: dict[int, Any] = {}
        self._lock = threading.RLock()

    # -- serving ---------------------------------------------------------------------------
    def start(self, host: str = "127.0.0.1", port: int = 8080, *, allow_origins: Collection[str] = (),
              title: str = "ejsgen lab") -> Any:
        """Serve on ``host:port`` (the next free port if taken; 0: any); returns the viser server."""
        from ejsrl.app._sessions import Classroom
        from ejsrl.view.viser_view import make_server

        # a tab closing while its session draws a frame makes viser warn; ordinary here too
        warnings.filterwarnings("ignore", message=r"Queued a \w+ on a closed connection", category=UserWarning)
        server, _url = make_server(host, port, allow_origins=tuple(allow_origins), label=title, banner=False)
        self.server = server
        self.classroom = Classroom(self._make_app, server, max_sessions=self.max_sessions, grace=self.grace)
        self.classroom.admit = self._admit
        server.on_client_disconnect(self._gone)
        return server

    def stop(self) -> None:
        if self.classroom is not None:
            self.classroom.stop()
        if self.server is not None:
            import contextlib
            import io

            with contextlib.redirect_stdout(io.StringIO()):  # viser's "Server stopped"
                self.server.stop()

    def _make_app(self) -> App:
        build = self.build
        if build is None:  # _admit lets no tab through before the first good build
            raise RuntimeError("no build to serve yet")
        return build.make_app()

    def _admit(self, client: Any) -> bool:
        with self._lock:
            if self.error is None and self.build is not None:
                return True
            self._parked[client.client_id] = client
            text = self.error or "building..."
        _show_error_to(client, text)
        return False

    def _gone(self, client: Any) -> None:
        with self._lock:
            self._parked.pop(client.client_id, None)

    def _sessions(self) -> list[Any]:
        """The classroom's sessions now (open tabs' and closed tabs' kept for a reload)."""
        if self.classroom is None:
            return []
        with self.classroom._lock:
            return list(self.classroom.sessions.values())

    def _client(self, client_id: int | None) -> Any:
        if client_id is None or self.server is None:
            return None
        return self.server.get_clients().get(client_id)

    # -- a failed build ---------------------------------------------------------------------
    def show_error(self, text: str) -> int:
        """Show ``text`` (a build's error report) in every tab instead of its lab, until the
        next :meth:`swap`; the sessions are paused (their playing state kept for the swap).
        Returns the number of tabs told."""
        from ejsrl.app._sessions import Classroom

        with self._lock:
            self.error = text
            parked = list(self._parked.values())
        told = 0
        for session in self._sessions():
            with session.lock:
                view = session.view
                if view is not None and not view.closed and session.app is not None:
                    Classroom._close_view(session, view)
                self.classroom.scheduler.remove(session)
                client = self._client(session.client_id)
            if client is not None:
                _show_error_to(client, text)
                told += 1
        for client in parked:
            _show_error_to(client, text)
            told += 1
        return told

    # -- a good build -----------------------------------------------------------------------
    def swap(self, build: Build, kept: Collection[str]) -> SwapReport:
        """Serve ``build`` from now on: every session gets a new app of it, with the values of
        the variables ``kept`` carried over (:func:`carry_over`), its playing state and its
        token; open tabs show it at once. Tabs that waited on a build error get their lab."""
        start = time.perf_counter()
        with self._lock:
            self.build = build
            self.error = None
            parked = list(self._parked.values())
            self._parked.clear()
        tabs = sessions = 0
        carried: list[str] | None = None
        if self.classroom is not None:
            for session in self._sessions():
                try:
                    names, shown = self._swap_session(session, build, kept)
                except Exception:  # noqa: BLE001 - one tab's trouble must not stop the others
                    log.exception("ejsrl: reloading a session failed")
                    continue
                if names is not None:
                    sessions += 1
                    tabs += shown
                    carried = names
            for client in parked:  # a fresh session, or its own again (its address holds the token)
                _clear(client)
                self.classroom._connect(client)
                tabs += 1
        return SwapReport(time.perf_counter() - start, tabs, sessions, carried)

    def _swap_session(self, session: Any, build: Build, kept: Collection[str]) -> tuple[list[str] | None, int]:
        from ejsrl.app._sessions import Classroom

        classroom = self.classroom
        new_app = build.make_app()  # before anything of the old lab is undone (it could raise)
        with session.lock:
            old_app = session.app
            if old_app is None or session.freed:
                return None, 0
            old_view = session.view
            client = self._client(session.client_id)
            live = old_view is not None and not old_view.closed
            # the camera where the user left it (also while a build error was shown), unless
            # the author changed the camera the spec asks for: then the new one shows it
            keep_camera = old_view is not None and _camera_spec(old_app.view) == _camera_spec(build.view)
            camera = _camera_of(client) if client is not None and keep_camera else None
            if live:
                Classroom._close_view(session, old_view)  # pauses it, remembering whether it played
            classroom.scheduler.remove(session)
            names = carry_over(old_app, new_app, kept)
            with old_app.lock:
                old_app.on_wake = None
                old_app.views = []
                old_app.model._ejs_close()
            new_app.on_wake = session.wake
            session.app, session.view = new_app, None
            if client is None:  # a closed tab: its view is built when it comes back
                return names, 0
            _clear(client)
            try:
                classroom._attach(session, client, False)  # the new panel and scene, the token, playing again
            except Exception as exc:  # noqa: BLE001 - a view the runtime cannot build: say so in the tab
                log.exception("ejsrl: showing the new build failed")
                _show_error_to(client, f"internal error: the new lab could not be shown ({type(exc).__name__}: {exc}); "
                                       "please report it. The next save tries again.")
                return names, 0
            view = session.view
            if view is not None and not view.closed:
                if old_view is not None:
                    _keep_plots(view, old_view, new_app)
                if camera is not None and getattr(view, "_world", lambda: None)() is not None:
                    _restore_camera(client, camera)
        return names, 1


# -- a tab's page -------------------------------------------------------------------------------------


def _clear(client: Any) -> None:
    """Empty a tab's panel and scene (what it showed goes; its address stays)."""
    try:
        client.gui.reset()
        client.scene.reset()
    except Exception:  # noqa: BLE001 - a tab that closed meanwhile
        log.debug("clearing a tab failed", exc_info=True)


def _show_error_to(client: Any, text: str) -> None:
    try:
        _clear(client)
        with client.atomic():
            client.gui.set_panel_label("Build error")
            client.gui.main_panel.dock_right()
            client.gui.main_panel.set_width(ERROR_WIDTH)
            client.gui.add_html(error_html(text))
    except Exception:  # noqa: BLE001 - a tab that closed meanwhile
        log.debug("showing a build error failed", exc_info=True)


def _camera_of(client: Any) -> tuple[Any, ...] | None:
    try:
        cam = client.camera
        return (np.array(cam.position), np.array(cam.look_at), np.array(cam.up_direction), float(cam.fov))
    except Exception:  # noqa: BLE001 - a client that has not reported its camera yet
        return None


def _restore_camera(client: Any, camera: tuple[Any, ...]) -> None:
    position, look_at, up, fov = camera
    try:
        with client.atomic():  # viser moves look_at with the position: the position first
            client.camera.up_direction = up
            client.camera.position = position
            client.camera.look_at = look_at
            client.camera.fov = fov
    except Exception:  # noqa: BLE001
        log.debug("restoring a tab's camera failed", exc_info=True)


def _fingerprint(value: Any) -> Any:
    """A comparable digest of a view element's definition: expressions by their spec text
    (``Dynamic.source``), functions by name, containers and dataclasses field by field."""
    import dataclasses

    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return (type(value).__name__, tuple((f.name, _fingerprint(getattr(value, f.name)))
                                            for f in dataclasses.fields(value)))
    if hasattr(value, "source") and hasattr(value, "fn"):  # a Dynamic
        return ("dynamic", value.source)
    if isinstance(value, dict):
        return tuple(sorted((str(k), _fingerprint(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple)):
        return tuple(_fingerprint(v) for v in value)
    if isinstance(value, np.ndarray):
        return ("array", value.shape, value.tobytes())
    if callable(value):
        return ("function", getattr(value, "__qualname__", repr(type(value))))
    return repr(value)


def _camera_spec(view: Any) -> list[Any]:
    """The spec's camera of the 3D view: the fingerprints of its ``view`` elements (none: the
    framed first view)."""
    from ejsrl.world.binding import scene_elements

    found: list[Any] = []
    stack = list(scene_elements(list(view or [])))
    while stack:
        element = stack.pop()
        if getattr(element, "kind", None) == "view":
            found.append(_fingerprint(element))
        stack.extend(getattr(element, "children", None) or [])
    return found


def _plot_key(plot: Any) -> tuple[Any, ...]:
    """What a plot's recorded points depend on: its x, each series' data expressions and
    kind, its window and length (labels, colours and ranges do not change the points)."""

    def src(prop: Any) -> Any:
        return getattr(prop, "source", repr(prop))

    series = tuple((src(getattr(s, "y", None)), src(getattr(s, "x", None)), getattr(s, "kind", None),
                    getattr(s, "max_points", None)) for s in getattr(plot, "series", ()))
    return (type(plot).__name__, src(getattr(plot, "x", None)), series, getattr(plot, "window", None),
            getattr(plot, "max_points", None))


def _keep_plots(view: Any, old_view: Any, app: App) -> None:
    """Give the new view's plots the points of the old view's plots in the same places
    whose data expressions did not change (a plot whose data changed starts afresh)."""
    try:
        pairs = list(zip(view.panel.plots, old_view.panel.plots))
    except AttributeError:
        return
    with app.lock:
        for new, old in pairs:
            try:
                if _plot_key(new.plot) == _plot_key(old.plot):
                    new.adopt(old)
            except Exception:  # noqa: BLE001 - a plot of another kind: it starts afresh
                log.debug("keeping a plot's points failed", exc_info=True)
