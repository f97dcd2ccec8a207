"""Running a generated app: in the browser (viser) or headless.

``App`` owns the model, one lock and one loop: the simulation runs in the loop's thread;
UI callbacks take the lock, apply their change, run ``on_change`` and the fixed
relations, and return. Errors in user code pause the simulation and are kept in
``app.error`` (message and spec location) for the UI to show; the server keeps serving.

``main(Model, VIEW, ...)`` is what a generated ``app.py`` calls: it parses the command
line of the language's last section (``--host``, ``--port``, ``--headless --duration T
[--csv FILE] [--vars a,b,q] [--every N] [--set NAME=VALUE ...]``).
"""

from __future__ import annotations

import argparse
import ast
import csv
import math
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from ejsrl.sim.model import Controller, ModelBase, SetValueError, UserCodeError, describe_error
from ejsrl.view.elements import Button, Control, Dynamic
from ejsrl.world.binding import SceneSync, scene_elements

__all__ = ["App", "SimConfig", "AppMeta", "main", "parse_set", "csv_columns", "load_app"]


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
    where the app's assets are; ``overrides``: initial values replaced before ``init``.
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
    ) -> None:
        super().__init__()
        self.model_cls = model_cls
        self.view = view
        self.sim = sim or SimConfig()
        self.meta = meta or AppMeta(title=model_cls.__name__)
        self.base_dir = Path(base_dir)
        self.lock = threading.RLock()
        self.error: UserCodeError | None = None
        self.error_rev = 0
        self.frame_count = 0
        self.views: list[Any] = []
        self._pending: str | None = None
        self._wall0: float | None = None
        self._t0: float = 0.0
        self._stopped = threading.Event()
        self._world_functions: Any = None
        self._loop_thread: threading.Thread | None = None
        self.interrupted: int | None = None
        """A signal's number once SIGINT/SIGTERM asked a headless run to stop (set by ``main``)."""
        self.scene = SceneSync(scene_elements(view), base_dir=self.base_dir)
        self.model = model_cls(self, overrides, start=False)
        try:
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

    def pause(self) -> None:
        with self.lock:
            self.playing = False

    def is_playing(self) -> bool:
        return self.playing

    def step_once(self) -> None:
        """Run one step (from the UI's Step button, or ``step()`` in user code)."""
        with self.lock:
            if self.error is None:
                self._run_steps(1)
                self._after_change()

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
            self.guard(self.model._ejs_reset if what == "reset" else self.model._ejs_initialize)
            self._wall0 = None  # realtime pacing starts again from the new time
            for v in self.views:
                if hasattr(v, "on_reset"):
                    v.on_reset()

    def apply_control(self, control: Control, value: Any) -> None:
        """Write an already validated value from the UI, then ``on_change`` and the fixed relations."""
        with self.lock:
            if self.guard(lambda: control.set(self.model, value), control.where) is None and self.error is not None:
                return
            self.remember_user_value(control.bind, control.set, value)
            if control.on_change is not None:
                self.guard(lambda: control.on_change(self.model), control.where)  # type: ignore[misc]
            self._after_change()

    def run_action(self, button: Button) -> None:
        """Run a button's action, then the fixed relations."""
        with self.lock:
            self.guard(lambda: button.action(self.model), button.where)
            self._after_change()

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

    def world_functions(self) -> Any:
        """The implementation of the prelude's world functions (made on first use)."""
        if self._world_functions is None:
            from ejsrl.world.functions import WorldFunctions

            self._world_functions = WorldFunctions(self.scene, lambda: self.model)
        return self._world_functions

    def capture(self, name: str) -> np.ndarray:
        """Render what camera ``name`` sees now (the scene is brought up to date first)."""
        from ejsrl.world import render

        self.scene.update(self.model, None)
        rgb, _depth = render(self.scene.world, name)
        return rgb

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
            for v in self.views:
                v.on_frame()

    def _realtime_steps(self) -> None:
        now = time.perf_counter()
        t = self.model._ejs_time() or 0.0
        if self._wall0 is None:
            self._wall0, self._t0 = now, t
            self._run_steps(1)
            return
        target = self._t0 + (now - self._wall0)
        deadline = now + 0.8 / max(self.sim.fps, 1.0)
        while self.playing and self.error is None and (self.model._ejs_time() or 0.0) < target:
            if self._run_steps(1) == 0 or time.perf_counter() > deadline:
                self._wall0 = None  # cannot keep up: pace from here
                break

    def run_loop(self, stop: threading.Event | None = None) -> None:
        """Run frames at ``sim.fps`` until ``stop`` is set."""
        stop = stop or self._stopped
        period = 1.0 / max(float(self.sim.fps), 1.0)
        next_time = time.perf_counter()
        while not stop.is_set():
            self.frame()
            next_time += period
            delay = next_time - time.perf_counter()
            if delay > 0:
                stop.wait(delay)
            else:
                next_time = time.perf_counter()

    def stop(self) -> None:
        """Stop the loop; when it runs in its own thread (``serve(block=False)``), wait for it."""
        self._stopped.set()
        thread = self._loop_thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=5.0)

    # -- serving ----------------------------------------------------------------------------------
    def serve(
        self, host: str = "127.0.0.1", port: int = 8080, *, block: bool = True, allow_origins: Sequence[str] = ()
    ) -> Any:
        """Start the viser server and the loop; returns the server (its real port: ``get_port()``).

        Only pages served by the app itself may open its websocket (and ``allow_origins``;
        ``"*"``: any); a ``host`` other than this machine's loopback prints a warning.
        """
        from ejsrl.view._guard import is_loopback
        from ejsrl.view.viser_view import ViserView, make_server

        server, _url = make_server(host, port, allow_origins=allow_origins, label=self.meta.title)
        view = ViserView(self, server)
        self.views.append(view)
        url_host = "localhost" if host in ("127.0.0.1", "0.0.0.0", "::") else host
        print(f"{self.meta.title}: serving on http://{url_host}:{server.get_port()} (Ctrl+C to stop)", flush=True)
        if not is_loopback(host):
            where = "every network this machine is on" if host in ("0.0.0.0", "", "::") else f"the network at {host}"
            print(
                f"warning: --host {host or '0.0.0.0'} opens this lab to {where}: anyone who can reach this "
                f"machine on port {server.get_port()} can open it, watch it and change the simulation. "
                "Leave --host out (127.0.0.1) to keep the lab on this machine.",
                file=sys.stderr,
                flush=True,
            )
        if not block:
            self._loop_thread = threading.Thread(target=self.run_loop, name="ejsrl-loop", daemon=True)
            self._loop_thread.start()
            return server
        try:
            self.run_loop()
        except KeyboardInterrupt:
            pass
        finally:
            server.stop()
        return server

    # -- headless -----------------------------------------------------------------------------------
    def run_headless(
        self,
        duration: float,
        *,
        csv_file: TextIO | None = None,
        variables: Sequence[str] | None = None,
        every: int = 1,
        log: TextIO = sys.stderr,
    ) -> int:
        """Run for ``duration`` units of the independent variable; returns the exit status.

        When ``interrupted`` becomes a signal's number (``main`` sets it on SIGINT/SIGTERM),
        the run stops after the step in progress, with every row written so far flushed,
        and returns 128 + that number.
        """
        model = self.model
        if self.error is not None:
            print(_format_error(self.error), file=log)
            return 1
        if model.INDEPENDENT is None:
            print("error: this model has no independent variable (no ODE page and no variable 't')", file=log)
            return 2
        columns = csv_columns(model, variables)
        writer = csv.writer(csv_file) if csv_file is not None else None
        if writer is not None:
            writer.writerow([name for name, _ in columns])
            writer.writerow(_row(model, columns))
        t_start = model._ejs_time() or 0.0
        t_end = t_start + duration
        steps = 0
        self.playing = True
        last_t = t_start
        while True:
            if self.interrupted is not None:
                return self._report_interrupt(csv_file, log)
            t = model._ejs_time() or 0.0
            if t >= t_end - 1e-9 * max(1.0, abs(t_end)):
                break
            if self._run_steps(1) == 0:
                break
            steps += 1
            t_new = model._ejs_time() or 0.0
            if writer is not None and steps % every == 0:
                writer.writerow(_row(model, columns))
            for text in self.pop_alerts():
                print(f"alert: {text}", file=log)
            if self.error is not None or not self.playing:
                break
            if t_new <= last_t:
                print(f"error: the independent variable '{model.INDEPENDENT}' did not advance in a step (t = {t_new:g})", file=log)
                return 2
            last_t = t_new
        for text in self.pop_alerts():
            print(f"alert: {text}", file=log)
        if self.error is not None:
            print(_format_error(self.error), file=log)
            return 1
        if not self.playing:
            print(f"stopped at {model.INDEPENDENT} = {model._ejs_time():g} (the simulation paused itself)", file=log)
        return 0


    def _report_interrupt(self, csv_file: TextIO | None, log: TextIO) -> int:
        signum = self.interrupted or signal.SIGTERM
        if csv_file is not None:
            csv_file.flush()
        t = self.model._ejs_time()
        print(
            f"stopped by {signal.Signals(signum).name} at {self.model.INDEPENDENT} = {t:g}"
            + ("; the CSV holds the rows written so far" if csv_file is not None else ""),
            file=log,
        )
        return 128 + int(signum)


def load_app(app_dir: Path | str, *, overrides: dict[str, Any] | None = None) -> App:
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
    return App(module.Model, module.VIEW, sim=module.SIMULATION, meta=module.META, base_dir=folder, overrides=overrides)


def _format_error(err: UserCodeError) -> str:
    return f"{err.where}: error: {err.message}" if err.where else f"error: {err.message}"


# -- CSV ---------------------------------------------------------------------------------------------


def csv_columns(model: ModelBase, names: Sequence[str] | None = None) -> list[tuple[str, Callable[[], Any]]]:
    """The CSV columns: (header, getter). Arrays are spread as ``q[0]``, ``q[1]``, ...

    With no ``names``, every numeric variable (numbers and arrays of numbers, ``expr:``
    variables included; not booleans or text) in declaration order. Named variables may
    also be booleans (written 0/1), arrays of booleans and text; naming any other kind of
    value (a robot, say) raises ``UserCodeError``.
    """
    types = model.VARIABLES
    if names is None:
        names = [n for n, kind in types.items() if kind in ("float", "int", "array", "auto") and _is_numeric(getattr(model, n))]
    else:
        for n in names:
            if n not in types:
                import difflib

                close = difflib.get_close_matches(n, list(types), n=1)
                hint = f"; did you mean '{close[0]}'?" if close else ""
                raise UserCodeError(f"--vars: unknown variable '{n}'{hint}")
    columns: list[tuple[str, Callable[[], Any]]] = []
    for n in names:
        value = getattr(model, n)
        if isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
            for idx in np.ndindex(value.shape):
                label = f"{n}[{']['.join(str(i) for i in idx)}]"
                columns.append((label, (lambda n=n, idx=idx: getattr(model, n)[idx])))
        elif isinstance(value, (bool, int, float, str, np.bool_, np.integer, np.floating)):
            columns.append((n, (lambda n=n: getattr(model, n))))
        else:
            what = f"an array of {value.dtype}" if isinstance(value, np.ndarray) else f"a {type(value).__name__}"
            raise UserCodeError(
                f"--vars: '{n}' holds {what}; the CSV takes numbers, booleans, text and arrays of numbers"
            )
    return columns


def _is_numeric(value: Any) -> bool:
    """A number (not a boolean) or an array of numbers."""
    if isinstance(value, np.ndarray):
        return value.dtype.kind in "iuf"
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def _row(model: ModelBase, columns: list[tuple[str, Callable[[], Any]]]) -> list[str]:
    out = []
    for _, get in columns:
        v = get()
        if isinstance(v, (bool, np.bool_)):
            out.append("1" if v else "0")
        elif isinstance(v, (int, np.integer)):
            out.append(str(int(v)))
        elif isinstance(v, str):
            out.append(v)  # the csv writer quotes it if it needs quotes
        else:
            out.append(repr(float(v)))
    return out


# -- the command line ----------------------------------------------------------------------------------


def parse_set(text: str, types: dict[str, str]) -> tuple[str, Any]:
    """Parse ``NAME=VALUE`` for ``--set``: the value is a literal of the variable's type.

    Raises ``ValueError`` with a message for the user. Nothing is evaluated: numbers,
    booleans, strings and (nested) lists of numbers only. For an ``expr:`` variable (type
    ``"auto"``) the value is a function of the declared value, which parses the literal
    for the type the expression gave when the model declares it (``SetValueError`` if it
    does not fit).
    """
    if "=" not in text:
        raise ValueError(f"--set takes NAME=VALUE, got {text!r}")
    name, raw = (s.strip() for s in text.split("=", 1))
    if name not in types:
        import difflib

        close = difflib.get_close_matches(name, list(types), n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise ValueError(f"--set: unknown variable '{name}'{hint}")
    kind = types[name]
    if kind == "auto":
        return name, _DeclaredSet(name, raw)
    return name, _parse_value(name, raw, kind)


class _DeclaredSet:
    """A ``--set`` value for an ``expr:`` variable, parsed for the type of its declared value."""

    def __init__(self, name: str, raw: str) -> None:
        self.name, self.raw = name, raw

    def __call__(self, declared: Any) -> Any:
        if isinstance(declared, (bool, np.bool_)):
            kind = "bool"
        elif isinstance(declared, (int, np.integer)):
            kind = "int"
        elif isinstance(declared, (float, np.floating)):
            kind = "float"
        elif isinstance(declared, str):
            kind = "str"
        elif isinstance(declared, np.ndarray) and declared.dtype.kind in "iuf":
            kind = "array"
        else:
            raise SetValueError(
                f"--set {self.name}: its expression gives a {type(declared).__name__}, which cannot be set "
                "from the command line (numbers, booleans, text and arrays of numbers can)"
            )
        try:
            return _parse_value(self.name, self.raw, kind)
        except ValueError as exc:
            raise SetValueError(str(exc)) from None

    def __repr__(self) -> str:
        return f"<--set {self.name}={self.raw} (for an expr: variable)>"


def _parse_value(name: str, raw: str, kind: str) -> Any:
    """The literal ``raw`` as a value of type ``kind`` (``ValueError`` if it is not one)."""
    if kind == "str":
        try:
            value = ast.literal_eval(raw)
            if not isinstance(value, str):
                value = raw
        except (ValueError, SyntaxError):
            value = raw
        return value
    if kind == "bool":
        low = raw.lower()
        if low in ("true", "1", "yes", "on"):
            return True
        if low in ("false", "0", "no", "off"):
            return False
        raise ValueError(f"--set {name}: expected true or false, got {raw!r}")
    try:
        value = ast.literal_eval(raw)
    except (ValueError, SyntaxError):
        raise ValueError(f"--set {name}: {raw!r} is not a number or a list of numbers") from None
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"--set {name}: expected an integer, got {raw!r}")
        return value
    if kind == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ValueError(f"--set {name}: expected a finite number, got {raw!r}")
        return float(value)
    if kind == "array":
        try:
            arr = np.array(value, dtype=float)
        except (ValueError, TypeError):
            raise ValueError(f"--set {name}: expected a list of numbers, got {raw!r}") from None
        if arr.ndim == 0 or not np.all(np.isfinite(arr)):
            raise ValueError(f"--set {name}: expected a list of finite numbers, got {raw!r}")
        return arr
    raise ValueError(f"--set {name}: this variable's type cannot be set from the command line")


def _parser(title: str) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=f"{title} (an ejsgen app). Serves the UI in the browser, or runs headless.")
    p.add_argument("--host", default="127.0.0.1", help="address to serve on (default 127.0.0.1: this machine only)")
    p.add_argument("--port", type=int, default=8080, help="port (default 8080; the next free one if taken)")
    p.add_argument(
        "--allow-origin", action="append", default=[], metavar="ORIGIN",
        help="also accept the lab's websocket from pages at ORIGIN, e.g. https://labs.example.org behind a proxy "
        "(repeatable; '*' accepts any page and any Host: only behind a proxy you trust). By default only the "
        "lab's own page may connect",
    )
    p.add_argument("--headless", action="store_true", help="run without a server")
    p.add_argument("--duration", type=float, help="headless: how long to run, in units of the independent variable")
    p.add_argument("--csv", metavar="FILE", help="headless: write variables to this CSV file ('-' for standard output)")
    p.add_argument("--vars", metavar="a,b,q", help="headless: the variables to write (default: every numeric variable)")
    p.add_argument("--every", type=int, default=1, metavar="N", help="headless: write a row every N steps (default 1)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="replace a variable's initial value (repeatable)")
    return p


class _Interrupted(KeyboardInterrupt):
    """Raised in the main thread by SIGINT/SIGTERM (a ``KeyboardInterrupt``, so a served app stops as on Ctrl+C)."""


class _StopSignals:
    """SIGINT and SIGTERM as a clean stop, while ``main`` runs (in the main thread only).

    The first signal raises :class:`_Interrupted` (serving stops its server), or, once a
    headless ``App`` is given to :meth:`defer_to`, sets its ``interrupted`` so that the run
    ends between two steps with its rows written; a second signal then raises, in case a
    step never ends. Further signals while stopping are ignored.
    """

    def __init__(self) -> None:
        self.signum: int | None = None
        self._app: App | None = None
        self._raised = False
        self._old: dict[int, Any] = {}

    def __enter__(self) -> _StopSignals:
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._old[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, old in self._old.items():
            signal.signal(sig, old)

    def defer_to(self, app: App) -> None:
        self._app = app
        if self.signum is not None:
            app.interrupted = self.signum

    def _handle(self, signum: int, frame: object) -> None:
        first = self.signum is None
        if first:
            self.signum = signum
        if first and self._app is not None:
            self._app.interrupted = signum
            return
        if not self._raised:
            self._raised = True
            raise _Interrupted(signum)


def main(
    model_cls: type[ModelBase],
    view: list[Any],
    *,
    sim: SimConfig,
    meta: AppMeta,
    base_dir: Path | str,
    argv: Sequence[str] | None = None,
) -> int:
    """The generated app's entry point; returns the process exit status.

    SIGINT (Ctrl+C) and SIGTERM stop the app cleanly, with a one-line message and no
    traceback: a served app stops its server, a headless run keeps the rows written so
    far. The status is then 128 + the signal's number (130 for SIGINT, 143 for SIGTERM).
    """
    stop = _StopSignals()
    status = 1
    with stop:
        try:
            status = _main(model_cls, view, sim=sim, meta=meta, base_dir=base_dir, argv=argv, stop=stop)
        except SetValueError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        except KeyboardInterrupt:  # _Interrupted, or Ctrl+C before the handlers were installed
            if stop.signum is None:
                stop.signum = signal.SIGINT
    if stop.signum is not None:
        if status != 128 + stop.signum:  # a headless run reports its own stop
            print(f"{meta.title}: stopped by {signal.Signals(stop.signum).name}", file=sys.stderr, flush=True)
        return 128 + int(stop.signum)
    return status


def _main(
    model_cls: type[ModelBase],
    view: list[Any],
    *,
    sim: SimConfig,
    meta: AppMeta,
    base_dir: Path | str,
    argv: Sequence[str] | None,
    stop: _StopSignals,
) -> int:
    args = _parser(meta.title).parse_args(argv)
    # NumPy's overflow/invalid warnings would point at app.py; a state that becomes
    # non-finite is reported instead, with the spec location of its equations.
    np.seterr(all="ignore")
    overrides: dict[str, Any] = {}
    try:
        for item in args.set:
            name, value = parse_set(item, model_cls.VARIABLES)
            overrides[name] = value
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.headless:
        if args.duration is None or not math.isfinite(args.duration) or args.duration < 0:
            print("error: --headless needs --duration T (a number >= 0)", file=sys.stderr)
            return 2
        if args.every < 1:
            print("error: --every must be at least 1", file=sys.stderr)
            return 2
        app = App(model_cls, view, sim=sim, meta=meta, base_dir=base_dir, overrides=overrides)
        stop.defer_to(app)
        names = [n.strip() for n in args.vars.split(",") if n.strip()] if args.vars else None
        try:
            if app.error is None:
                csv_columns(app.model, names)  # refuse bad --vars before any file is written
            if args.csv is None:
                return app.run_headless(args.duration, variables=names, every=args.every)
            if args.csv == "-":
                return app.run_headless(args.duration, csv_file=sys.stdout, variables=names, every=args.every)
            try:
                fh = open(args.csv, "w", newline="")  # noqa: SIM115 - closed below
            except OSError as exc:
                print(f"error: cannot write {args.csv}: {exc.strerror or exc}", file=sys.stderr)
                return 2
            with fh:
                return app.run_headless(args.duration, csv_file=fh, variables=names, every=args.every)
        except UserCodeError as exc:
            print(f"error: {exc.message}", file=sys.stderr)
            return 2
    if any(v is not None for v in (args.duration, args.csv, args.vars)):
        print("error: --duration, --csv and --vars go with --headless", file=sys.stderr)
        return 2
    try:
        from ejsrl.view._guard import parse_origin

        origins = [parse_origin(o) for o in args.allow_origin]
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    app = App(model_cls, view, sim=sim, meta=meta, base_dir=base_dir, overrides=overrides)
    app.serve(args.host, args.port, allow_origins=origins)
    return 0
