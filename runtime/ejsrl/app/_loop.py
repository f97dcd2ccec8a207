"""The app's model, its lock and its loop: stepping, realtime pacing, changes from the view, serving.

``App`` owns the model, one lock and one loop: the simulation runs in the loop's thread;
UI callbacks take the lock, apply their change, run ``on_change`` and the fixed
relations, and return. Errors in user code pause the simulation and are kept in
``app.error`` (message and spec location) for the UI to show; the server keeps serving.
An ``App`` holds no state shared with other apps of the process.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import threading
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from ejsrl.app._front import WorkerRole
from ejsrl.app._slow import watch_slow
from ejsrl.sim.model import Controller, ModelBase, SetValueError, UserCodeError, describe_error
from ejsrl.sim.world_access import WorldFunctionsAccess
from ejsrl.view.elements import Button, Control, Dynamic
from ejsrl.world.binding import SceneSync, scene_elements

__all__ = ["App", "SimConfig", "AppMeta", "load_app"]


@dataclass
class SimConfig:
    """The spec's ``simulation`` section."""

    fps: float = 30.0
    steps_per_display: int = 1
    autoplay: bool = False
    realtime: bool = False
    controls: bool = True
    panel_width: float | None = None


@dataclass
class AppMeta:
    """What the About panel shows: title, Markdown description, author, spec file name."""

    title: str
    description: str = ""
    author: str = ""
    spec: str = ""


class App(Controller):
    """A model, its world and its simulation loop; the view and headless runs drive it.

    ``model_cls``: the generated ``Model``; ``view``: its list of elements; ``base_dir``:
    where the app's assets are; ``overrides``: initial values replaced before ``init``;
    ``clock()``: monotonic seconds (default ``time.perf_counter``), the time of realtime
    pacing, of the loop's frame rate and of the view's timers (tests pass a fake one).
    ``run_init=False`` makes it without running ``init:`` (see :attr:`initialised`).
    """

    def __init__(
        self,
        model_cls: type[ModelBase],
        view: list[Any],
        *,
        sim: SimConfig | None = None,
        meta: AppMeta | None = None,
        base_dir: Path | str = ".",
        overrides: dict[str, Any] | None = None,
        clock: Callable[[], float] = time.perf_counter,
        run_init: bool = True,
    ) -> None:
        super().__init__()
        self.clock = clock
        self.model_cls = model_cls
        self.view = view
        self.sim = sim or SimConfig()
        self.meta = meta or AppMeta(title=model_cls.__name__)
        self.base_dir = Path(base_dir)
        self.overrides = overrides
        self.lock = threading.RLock()
        #: called after a change from the view (a control, a button, Play, Step, Reset): a
        #: classroom's scheduler then shows it (a paused session is otherwise not stepped)
        self.on_wake: Callable[[], None] | None = None
        #: the measured speed while playing: sim time per wall second over the nominal rate
        #: (1.0: as fast as the lab asks; None: not measured yet, or paused)
        self.speed: float | None = None
        self._speed_mark: tuple[float, float, int] | None = None
        self.error: UserCodeError | None = None
        self.error_rev = 0
        self.frame_count = 0
        self.views: list[Any] = []
        self._pending: str | None = None
        self._wall0: float | None = None
        self._t0: float = 0.0
        self._stopped = threading.Event()
        self._world_functions: Any = None
        self._camera_sources: Any = None  # this session's real camera sources (ejsrl.vision.sources.CameraSources)
        self._loop_thread: threading.Thread | None = None
        #: the sessions of a lab served with a simulation per browser tab (``serve(per_client=True)``)
        self.classroom: Any = None
        self.interrupted: int | None = None
        """A signal's number once SIGINT/SIGTERM asked a headless run to stop (set by ``main``)."""
        self.scene = SceneSync(scene_elements(view), base_dir=self.base_dir)
        self.model = model_cls(self, overrides, start=False)
        #: whether ``init:`` ran (``run_init=False``: a served class's template whose ``init:``
        #: did not end in time; its sessions run their own)
        self.initialised = run_init
        self.playing = False
        if not run_init:
            return
        try:
            with watch_slow(model_cls, "init:"):  # an endless init: is named with its spec line
                self.model._ejs_reset()
        except SetValueError:
            raise  # a --set value that does not fit its variable: the command line's error
        except Exception as exc:  # noqa: BLE001 - user code may raise anything
            self.fail(exc)
        if self.error is None:
            self.scene.update(self.model, self.safe_value, first=True)
        self.playing = bool(self.sim.autoplay) and self.error is None

    # -- errors ------------------------------------------------------------------------------
    def fail(self, exc: BaseException, where: str = "") -> None:
        """Record an error from user code and pause."""
        err = describe_error(exc, self.model_cls)
        if where and not err.where:
            err = UserCodeError(err.message, where)
        self.error = err
        self.error_rev += 1
        self.playing = False

    def guard(self, fn: Callable[[], Any], where: str = "") -> Any:
        """Run ``fn`` under the error guard: on an exception, record it, pause, return None."""
        try:
            return fn()
        except Exception as exc:  # noqa: BLE001 - user code may raise anything
            self.fail(exc, where)
            return None

    def safe_value(self, prop: Any, where: str = "") -> Any:
        """A constant or dynamic property's value, or None after an error (recorded)."""
        if not isinstance(prop, Dynamic):
            return prop
        if self.error is not None:
            return None
        return self.guard(lambda: prop(self.model), where)

    def pop_alerts(self) -> list[str]:
        """The messages from ``alert()`` since the last call."""
        out, self.alerts = self.alerts, []
        return out

    # -- controls (thread-safe) ---------------------------------------------------------------
    def play(self) -> None:
        with self.lock:
            if self.error is None:
                self.playing = True
                self._wall0 = None
        self._wake()

    def pause(self) -> None:
        with self.lock:
            self.playing = False
        self._wake()

    def _wake(self) -> None:
        if self.on_wake is not None:
            self.on_wake()

    def is_playing(self) -> bool:
        return self.playing

    def step_once(self) -> None:
        """Run one step (from the UI's Step button, or ``step()`` in user code)."""
        with self.lock:
            if self.error is None:
                self._run_steps(1)
                self._after_change()
        self._wake()

    def request_reset(self) -> None:
        self._pending = "reset"

    def request_initialize(self) -> None:
        self._pending = self._pending or "initialize"

    def reset(self) -> None:
        """Back to the initial state (the UI's Reset button): clears errors too."""
        with self.lock:
            self._pending = "reset"
            self._apply_pending()
            self._refresh_views()
        self._wake()

    def _tell_pages(self, title: str, body: str) -> list[Any]:
        """Show a slow ``init:``'s warning in the pages of this simulation (the handles, to remove)."""
        return [h for v in list(self.views) if hasattr(v, "notify") for h in v.notify(None, title, body, "yellow", loading=True)]

    def _apply_pending(self) -> None:
        """A reset (paused, the user's settings forgotten) or an initialize (the user's
        settings kept, playing on if it was) requested during the last change or step."""
        while self._pending is not None:
            what, self._pending = self._pending, None
            if what == "reset":
                self.playing = False
                self.user_values.clear()
            self.error = None
            self.error_rev += 1
            self.scene.reset()
            with watch_slow(self.model_cls, "init:", tell=self._tell_pages):  # also said in the tabs of this simulation
                self.guard(self.model._ejs_reset if what == "reset" else self.model._ejs_initialize)
            self._wall0 = None  # realtime pacing starts again from the new time
            for v in self.views:
                if hasattr(v, "on_reset"):
                    v.on_reset()

    def apply_control(self, control: Control, value: Any) -> None:
        """Write an already validated value from the UI, then ``on_change`` and the fixed relations."""
        with self.lock:
            if self.guard(lambda: control.set(self.model, value), control.where) is None and self.error is not None:
                self._wake()  # shows the error
                return
            self.remember_user_value(control.bind, control.set, value)
            if control.on_change is not None:
                self.guard(lambda: control.on_change(self.model), control.where)  # type: ignore[misc]
            self._after_change()
        self._wake()

    def run_action(self, button: Button) -> None:
        """Run a button's action, then the fixed relations."""
        with self.lock:
            self.guard(lambda: button.action(self.model), button.where)
            self._after_change()
        self._wake()

    def apply_gizmo(self, name: str, T_world: Any) -> None:
        """A gizmo was dragged: write its bound pose, run ``on_change`` and the fixed relations."""
        T = np.asarray(T_world, dtype=float)
        if T.shape != (4, 4) or not np.all(np.isfinite(T)):
            return
        for b in self.scene.bindings:
            if b.element.name == name and b.element.kind == "gizmo" and b.element.set is not None:
                with self.lock:
                    element = b.element
                    self.guard(lambda: element.set(self.model, T), element.where)  # type: ignore[misc]
                    self.remember_user_value(f"gizmo {name}", element.set, T)  # type: ignore[arg-type]
                    if element.on_change is not None:
                        self.guard(lambda: element.on_change(self.model), element.where)  # type: ignore[misc]
                    self._after_change()
                self._wake()
                return

    def _after_change(self) -> None:
        if self.error is None:
            self.guard(self.model._fixed_relations)
            self.model._ejs_restart_solvers()
        self._apply_pending()
        self._wall0 = None
        self._refresh_views()

    def _refresh_views(self) -> None:
        if self.error is None:
            self.scene.update(self.model, self.safe_value)

    # -- the world, for model code ---------------------------------------------------------------
    @property
    def world(self) -> Any:  # type: ignore[override]
        return self.scene.world

    def world_functions(self) -> WorldFunctionsAccess:
        """The implementation of the prelude's world functions (made on first use)."""
        if self._world_functions is None:
            from ejsrl.world.functions import WorldFunctions

            self._world_functions = WorldFunctions(self.scene, lambda: self.model)
        return self._world_functions

    def capture(self, name: str) -> np.ndarray:
        """Render what camera ``name`` sees now (the scene is brought up to date first); a camera
        with a ``source`` gives that source's frame instead (at the model's time: a video in step)."""
        from ejsrl.world import render

        source = self._real_source(name)
        if source is not None:
            node = self.scene.world[name]
            t = self.model._ejs_time() if self.model.INDEPENDENT is not None else None
            try:
                return self._camera_sources.frame(name, source, node.props.get("resolution", (320, 240)), t)
            except (ValueError, RuntimeError) as e:  # said at the camera element (its source:), not at the code that captured
                where = self.scene.where_of(name)
                if not where:
                    raise
                raise UserCodeError(f"{type(e).__name__}: {e}", where) from None
        self.scene.update(self.model, None)
        rgb, _depth = render(self.scene.world, name)
        return rgb

    def capture_depth(self, name: str) -> np.ndarray:
        """The depth image camera ``name`` sees now (Z in metres along its axis, inf where empty)."""
        from ejsrl.world.rendering import render_depth

        source = self._real_source(name)
        if source is not None:
            raise ValueError(f"camera '{name}' reads a real source ({source!r}): it has no depth image (only a rendered camera has)")
        self.scene.update(self.model, None)
        return render_depth(self.scene.world, name)

    def _real_source(self, name: str) -> Any:
        """The ``source`` of camera ``name`` (None: it renders the scene); this session's sources made on first use."""
        node = self.scene.world.nodes.get(name)
        source = None if node is None or getattr(node, "kind", None) != "camera" else node.props.get("source")
        if source is not None and self._camera_sources is None:
            from ejsrl.vision.sources import CameraSources

            self._camera_sources = CameraSources(self.base_dir)
        return source

    # -- stepping ---------------------------------------------------------------------------------
    def _run_steps(self, n: int) -> int:
        done = 0
        for _ in range(n):
            try:
                stop = self.model._ejs_step()
            except Exception as exc:  # noqa: BLE001
                self.fail(exc)
                break
            done += 1
            if self._pending is not None:
                self._apply_pending()
            if stop:
                self.playing = False
                break
            if not self.playing and n > 1:
                break
        return done

    def frame(self) -> None:
        """One display frame: the steps (when playing), then the world and the views."""
        with self.lock:
            if self.playing and self.error is None:
                if self.sim.realtime and self.model.INDEPENDENT is not None:
                    self._realtime_steps()
                else:
                    self._run_steps(int(self.sim.steps_per_display))
            self._apply_pending()
            self._refresh_views()
            self.frame_count += 1
            self._measure_speed()
            for v in self.views:
                v.on_frame()

    #: how long the speed is measured over (seconds of the clock)
    SPEED_WINDOW = 1.0

    def _measure_speed(self) -> None:
        """Update :attr:`speed`: over the last :data:`SPEED_WINDOW`, sim time per wall second
        (realtime labs) or frames per second (others) over what the lab asks for."""
        if not self.playing or self.error is not None:
            self.speed, self._speed_mark = None, None
            return
        now = self.clock()
        t = self.model._ejs_time() if self.model.INDEPENDENT is not None else None
        mark = (now, float(t) if t is not None else 0.0, self.frame_count)
        if self._speed_mark is None:
            self._speed_mark = mark
            return
        wall = now - self._speed_mark[0]
        if wall < self.SPEED_WINDOW:
            return
        if self.sim.realtime and t is not None:
            speed = (mark[1] - self._speed_mark[1]) / wall
        else:
            speed = (mark[2] - self._speed_mark[2]) / (wall * max(float(self.sim.fps), 1.0))
        self.speed = max(0.0, speed)
        self._speed_mark = mark

    def _realtime_steps(self) -> None:
        now = self.clock()
        t = self.model._ejs_time() or 0.0
        if self._wall0 is None:
            self._wall0, self._t0 = now, t
            self._run_steps(1)
            return
        target = self._t0 + (now - self._wall0)
        deadline = now + 0.8 / max(self.sim.fps, 1.0)
        while self.playing and self.error is None and (self.model._ejs_time() or 0.0) < target:
            if self._run_steps(1) == 0 or self.clock() > deadline:
                self._wall0 = None  # cannot keep up: pace from here
                break

    def run_loop(self, stop: threading.Event | None = None) -> None:
        """Run frames at ``sim.fps`` until ``stop`` is set."""
        stop = stop or self._stopped
        period = 1.0 / max(float(self.sim.fps), 1.0)
        next_time = self.clock()
        while not stop.is_set():
            self.frame()
            next_time += period
            delay = next_time - self.clock()
            if delay > 0:
                stop.wait(delay)
            else:
                next_time = self.clock()

    def stop(self) -> None:
        """Stop the loop (and a classroom's sessions); when it runs in its own thread
        (``serve(block=False)``), wait for it."""
        self._stopped.set()
        if self.classroom is not None:
            self.classroom.stop()
        thread = self._loop_thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=5.0)
        with self.lock:
            self.model._ejs_close()  # free what the model holds outside Python (its FMU instances)

    # -- serving ----------------------------------------------------------------------------------
    def serve(
        self,
        host: str = "127.0.0.1",
        port: int = 8080,
        *,
        block: bool = True,
        allow_origins: Sequence[str] = (),
        per_client: bool = False,
        max_sessions: int | None = None,
        grace: float | None = None,
        workers: int | None = None,
        role: WorkerRole | None = None,
    ) -> Any:
        """Start the viser server and the loop; returns the server (its real port: ``get_port()``).

        By default every browser tab shows this app's one simulation (``app.model``). With
        ``per_client`` (what a generated app does unless ``--shared``), every tab gets a
        simulation of its own, made like this one (see :mod:`ejsrl.app._sessions`;
        ``self.classroom`` keeps them): at most ``max_sessions`` tabs at once (default:
        what this machine's cores can step at full rate, measured on this app), a closed
        tab's session kept ``grace`` seconds for a reload, stepped by ``workers`` threads.

        Only pages served by the app itself may open its websocket (and ``allow_origins``;
        ``"*"``: any); a ``host`` other than this machine's loopback prints a warning.
        With ``role``, this app is one of the processes a class is served from (see
        :mod:`ejsrl.app._front`): it serves its share of the tabs and reports to its front.
        """
        from ejsrl.view.viser_view import ViserView, make_server

        if role is not None:  # one of a front's processes: on this machine only, answering to the front's address
            host, port, per_client = "127.0.0.1", 0, True
        server, _url = make_server(host, port, allow_origins=allow_origins, label=self.meta.title,
                                   answer_as=None if role is None else role.bind, banner=False)
        if per_client:
            self._start_classroom(server, max_sessions=max_sessions, grace=grace, workers=workers, role=role)
        else:
            view = ViserView(self, server)
            self.views.append(view)
        if role is not None:
            assert self.classroom is not None
            role.report(server.get_port(), self.classroom.max_sessions)
        else:
            announce(self.meta.title, host, server.get_port(), asked_port=port,
                     places=None if self.classroom is None else self.classroom.max_sessions)
        if self.classroom is not None:
            if not block:
                return server
            try:
                while not self._stopped.wait(0.5):
                    if role is not None and role.orphaned():
                        break
            except KeyboardInterrupt:
                pass
            finally:
                self.classroom.stop()
                _quietly(server.stop)
            return server
        if not block:
            self._loop_thread = threading.Thread(target=self.run_loop, name="ejsrl-loop", daemon=True)
            self._loop_thread.start()
            return server
        try:
            self.run_loop()
        except KeyboardInterrupt:
            pass
        finally:
            _quietly(server.stop)
        return server

    def _start_classroom(
        self, server: Any, *, max_sessions: int | None, grace: float | None, workers: int | None, role: WorkerRole | None
    ) -> None:
        from ejsrl.app._capacity import UNMEASURED_SESSIONS
        from ejsrl.app._sessions import GRACE_SECONDS, SWITCH_INTERVAL, Classroom, default_max_sessions, measure_frame_cost

        # the sessions already share the cores, in threads: SUSAN keeps to the calling one. Set where
        # SUSAN is loaded, else for when it is (importing it here loaded OpenCV into every lab: 0.16 s)
        susan = sys.modules.get("ejsrl.vision._susan")
        if susan is not None:
            susan.set_threads(1)
        else:
            os.environ["EJSRL_SUSAN_THREADS"] = "1"

        if sys.getswitchinterval() > SWITCH_INTERVAL:
            sys.setswitchinterval(SWITCH_INTERVAL)
        # a tab closing while its session draws a frame makes viser warn once that the frame
        # "will never be delivered": in a class that is ordinary, and a teacher reads it as an error
        warnings.filterwarnings("ignore", message=r"Queued a \w+ on a closed connection", category=UserWarning)

        if role is not None:
            max_sessions = role.max_sessions
        if max_sessions is None and not self.initialised:  # nothing to measure: its init: did not end
            max_sessions = UNMEASURED_SESSIONS
        if max_sessions is None:
            # a process runs Python on one core at a time (the GIL), however many the machine has
            cpus = role.cpus if role is not None else 1.0
            max_sessions = default_max_sessions(measure_frame_cost(self), self.sim.fps, cpus=cpus)
            susan = sys.modules.get("ejsrl.vision._susan")
            if susan is not None:  # a measured frame started compiling SUSAN's kernels: done before the class comes
                susan.finish_compile()

        def make_app() -> App:
            return type(self)(self.model_cls, self.view, sim=self.sim, meta=self.meta, base_dir=self.base_dir,
                              overrides=self.overrides, clock=self.clock)

        self.classroom = Classroom(make_app, server, max_sessions=max_sessions,
                                   grace=GRACE_SECONDS if grace is None else grace, workers=workers,
                                   token_prefix="" if role is None else role.token_prefix)
        if role is not None:
            self.classroom.class_places = role.class_places

    # -- headless -----------------------------------------------------------------------------------
    def run_headless(
        self,
        duration: float,
        *,
        csv_file: TextIO | None = None,
        variables: Sequence[str] | None = None,
        every: int = 1,
        log: TextIO | None = None,
    ) -> int:
        """Run for ``duration`` units of the independent variable; returns the exit status
        (see :func:`ejsrl.app.headless.run_headless`; ``log`` defaults to standard error)."""
        from ejsrl.app.headless import run_headless

        return run_headless(self, duration, csv_file=csv_file, variables=variables, every=every, log=log)


def load_app(
    app_dir: Path | str, *, overrides: dict[str, Any] | None = None, clock: Callable[[], float] = time.perf_counter
) -> App:
    """Import a built app folder's ``app.py`` and make its ``App`` (not serving, not playing).

    For scripting a lab from Python (notebooks, tests, benchmarks): ``app.model`` is the
    model, ``app.step_once()`` steps it, ``app.serve(block=False)`` serves it.
    """
    import importlib.util

    folder = Path(app_dir).resolve()
    name = f"ejs_app_{abs(hash(str(folder)))}"
    spec = importlib.util.spec_from_file_location(name, folder / "app.py")
    if spec is None or spec.loader is None:
        raise FileNotFoundError(f"no app.py in {folder}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # so tracebacks and SPEC_LINES find the module
    spec.loader.exec_module(module)
    sim = getattr(module, "SIMULATION", SimConfig())  # app.py leaves it out when every setting is the default
    return App(module.Model, module.VIEW, sim=sim, meta=module.META, base_dir=folder, overrides=overrides, clock=clock)


def _quietly(stop: Callable[[], Any]) -> None:
    """``stop()`` without viser's "Server stopped" line: the app says it stopped (and why)."""
    with contextlib.redirect_stdout(io.StringIO()):
        stop()


def announce(title: str, host: str, port: int, *, places: int | None, processes: int = 1, asked_port: int | None = None) -> None:
    """Print where a lab is served (and a warning when that is beyond this machine):
    ``places``: tabs served at once, each with its own simulation (None: one shared
    simulation); ``processes``: how many processes serve them; ``asked_port``: the port
    asked for, when the one served on may differ (it was taken)."""
    from ejsrl.view._guard import is_loopback

    url_host = "127.0.0.1" if host in ("127.0.0.1", "0.0.0.0", "", "::") else host
    taken = f" (port {asked_port} was taken)" if asked_port and asked_port != port else ""
    print(f"{title}: serving on http://{url_host}:{port}{taken} (Ctrl+C to stop)", flush=True)
    if host in ("0.0.0.0", "", "::"):
        others = ", ".join(f"http://{name}:{port}" for name in network_names())
        if others:
            print(f"  from other machines on the network: {others}", flush=True)
    if places is None:
        print("  every browser tab shows and drives this one simulation (--shared)", flush=True)
    else:
        by, change = (f" from {processes} processes", "--max-sessions N, --processes N") if processes > 1 else ("", "--max-sessions N")
        print(
            f"  every browser tab gets its own simulation, up to {places} at once{by} "
            f"({change} to change; --shared: one simulation for everyone)",
            flush=True,
        )
    if not is_loopback(host):
        where = "every network this machine is on" if host in ("0.0.0.0", "", "::") else f"the network at {host}"
        print(
            f"warning: --host {host or '0.0.0.0'} opens this lab to {where}: anyone who can reach this "
            f"machine on port {port} can open it, watch it and change the simulation. "
            "Leave --host out (127.0.0.1) to keep the lab on this machine.",
            file=sys.stderr,
            flush=True,
        )


def network_names() -> list[str]:
    """This machine's name and its non-loopback IPv4 addresses: what other machines on the
    network type to reach a lab served on every interface (from the resolver, no traffic)."""
    import socket

    try:
        hostname = socket.gethostname()
        infos = socket.getaddrinfo(hostname, None, socket.AF_INET)
    except OSError:
        return []
    addresses = sorted({info[4][0] for info in infos if not info[4][0].startswith("127.")})
    return ([hostname] if hostname and hostname != "localhost" else []) + addresses
