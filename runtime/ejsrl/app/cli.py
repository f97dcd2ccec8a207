"""The generated app's command line: ``main(Model, VIEW, ...)``, ``--set``, and stopping on signals.

``main`` parses the command line of the language's last section (``--host``, ``--port``,
``--headless --duration T | --steps N [--csv FILE] [--vars a,b,q[0]] [--every N] [--set NAME=VALUE ...]``)
and serves the app in the browser or runs it headless. Served, every browser tab gets a
simulation of its own (``--max-sessions N``, ``--grace SECONDS``, served from one process
per core: ``--processes N``), or, with ``--shared``, every tab shows the same one.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import math
import os
import signal
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ejsrl._signals import SignalScope
from ejsrl.app._capacity import UNMEASURED_SESSIONS
from ejsrl.app._front import (
    WORKER_ENV,
    WorkerRole,
    default_processes,
    serve_front,
    worker_command,
)
from ejsrl.app._loop import App, AppMeta, SimConfig, announce
from ejsrl.app._slow import Overran, run_within
from ejsrl.app.headless import csv_columns, refusal, run_headless, split_vars
from ejsrl.sim._console import quiet_prints
from ejsrl.sim.model import ModelBase, SetValueError, UserCodeError

__all__ = ["main", "parse_set"]


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
        from ejsrl._suggest import did_you_mean

        raise ValueError(f"--set: unknown variable '{name}'{did_you_mean(name, types)}")
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


#: seconds a served lab's ``init:`` may take before the server starts without it: per tab
#: (the template only measures the lab), and ``--shared`` (the one simulation: paused with
#: the error, Reset runs it again); ``EJSRL_INIT_WAIT`` / ``EJSRL_SHARED_INIT_WAIT`` override
INIT_WAIT = float(os.environ.get("EJSRL_INIT_WAIT", "10"))
SHARED_INIT_WAIT = float(os.environ.get("EJSRL_SHARED_INIT_WAIT", "30"))


def _served_app(model_cls: type[ModelBase], view: list[Any], *, shared: bool, **kw: Any) -> App:
    """The app ``serve`` starts from. Served per tab it is only the template the sessions are
    made like: what its ``init:`` prints or alerts is nobody's (each tab's session prints its
    own), and an ``init:`` that does not end within :data:`INIT_WAIT` is stopped so the class
    is served anyway (each tab's own ``init:`` then says in its page where it is), unmeasured.
    An endless ``init:`` used to keep the port closed for good, said only in the terminal."""

    def make() -> App:
        with contextlib.nullcontext() if shared else quiet_prints():
            return App(model_cls, view, **kw)

    wait = SHARED_INIT_WAIT if shared else INIT_WAIT
    finished, made = run_within(make, wait, name="ejsrl-init")
    if finished:
        return made
    app = App(model_cls, view, run_init=False, **kw)
    stopped = Overran(f"init: did not end within {wait:g} s (an endless loop?) and was stopped")
    if made is not None:
        stopped = stopped.with_traceback(made.__traceback__)
    app.fail(stopped)
    place = f"{app.error.where}: " if app.error is not None and app.error.where else ""
    if shared:
        print(f"{place}warning: init: did not end within {wait:g} s and was stopped: serving the simulation paused with "
              "this error in its page (Reset runs init: again)", file=sys.stderr, flush=True)
    else:
        app.error, app.error_rev = None, 0  # the template: nobody sees it; each tab runs its own init:
        print(f"{place}warning: init: did not end within {wait:g} s and was stopped: serving without measuring the lab "
              f"({UNMEASURED_SESSIONS} places a process; --max-sessions sets them); each tab runs its own init: and its "
              "page says where it is", file=sys.stderr, flush=True)
    return app


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
    p.add_argument(
        "--shared", action="store_true",
        help="one simulation for everyone: every browser tab shows and drives the same one (a lecture demo). "
        "By default every tab (every student) gets a simulation of its own",
    )
    p.add_argument(
        "--max-sessions", type=int, metavar="N",
        help="serve at most N tabs at once, each with its own simulation; the next one is told the lab is full "
        "(default: as many as this machine's cores can run at full speed, measured on this lab at start)",
    )
    p.add_argument(
        "--processes", type=int, metavar="N",
        help="serve the tabs from N processes, so that a class uses every core: one process runs Python on one "
        "core at a time (default: one per core, up to 8; 1: a single process)",
    )
    p.add_argument(
        "--grace", type=float, default=60.0, metavar="SECONDS",
        help="keep a closed tab's simulation this long, so that a reload finds it again (default 60); at most "
        "--max-sessions closed tabs' simulations are kept, the oldest freed first when more tabs close",
    )
    p.add_argument("--headless", action="store_true", help="run without a server")
    p.add_argument("--duration", type=float, help="headless: how long to run, in units of the independent variable")
    p.add_argument("--steps", type=int, metavar="N",
                   help="headless: run N steps (each: the evolution, then the fixed relations); with --duration, "
                        "whichever ends first. A model with no independent variable runs for --steps only")
    p.add_argument("--csv", metavar="FILE", help="headless: write variables to this CSV file ('-' for standard output)")
    p.add_argument("--vars", metavar="a,b,q", help="headless: the variables to write (default: every numeric variable); "
                                                   "array elements as the CSV header names them: q[0], m[1][2], q[1:3]")
    p.add_argument("--every", type=int, default=1, metavar="N", help="headless: write a row every N steps (default 1)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="replace a variable's initial value (repeatable)")
    p.add_argument("--sweep", action="store_true", help="run many headless runs over parameter values (--sweep --help lists its options)")
    return p


class _Interrupted(KeyboardInterrupt):
    """Raised in the main thread by SIGINT/SIGTERM (a ``KeyboardInterrupt``, so a served app stops as on Ctrl+C)."""


class _StopSignals(SignalScope):
    """SIGINT and SIGTERM as a clean stop, while ``main`` runs (in the main thread only).

    The first signal raises :class:`_Interrupted` (serving stops its server), or, once a
    headless ``App`` is given to :meth:`defer_to`, sets its ``interrupted`` so that the run
    ends between two steps with its rows written; a second signal then raises, in case a
    step never ends. Further signals while stopping are ignored.
    """

    def __init__(self) -> None:
        super().__init__()
        self.signum: int | None = None
        self._app: App | None = None
        self._raised = False

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
    sim: SimConfig | None = None,
    meta: AppMeta,
    base_dir: Path | str | None = None,
    argv: Sequence[str] | None = None,
) -> int:
    """The generated app's entry point; returns the process exit status.

    ``sim``: the spec's run settings (default: the runtime's); ``base_dir``: where the app's
    assets are (default: the folder of the module that defines ``model_cls``, i.e. app.py's).
    SIGINT (Ctrl+C) and SIGTERM stop the app cleanly, with a one-line message and no
    traceback: a served app stops its server, a headless run keeps the rows written so
    far. The status is then 128 + the signal's number (130 for SIGINT, 143 for SIGTERM).
    """
    sim = SimConfig() if sim is None else sim
    if base_dir is None:
        app_file = getattr(sys.modules.get(model_cls.__module__), "__file__", None)
        base_dir = Path(app_file).resolve().parent if app_file else Path.cwd()
    args = list(sys.argv[1:] if argv is None else argv)
    if "--sweep" in args:  # many headless runs: ejsrl.app.sweep has its own options and signal handling
        from ejsrl.app.sweep import app_sweep

        return app_sweep(model_cls, view, sim=sim, meta=meta, base_dir=base_dir, argv=args)
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
        # a headless run reports its own stop, and a front reports its processes' stop
        if status != 128 + stop.signum and WORKER_ENV not in os.environ:
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
        if args.duration is not None and (not math.isfinite(args.duration) or args.duration < 0):
            print("error: --duration must be a number >= 0", file=sys.stderr)
            return 2
        if args.steps is not None and args.steps < 0:
            print("error: --steps must be at least 0", file=sys.stderr)
            return 2
        if args.every < 1:
            print("error: --every must be at least 1", file=sys.stderr)
            return 2
        app = App(model_cls, view, sim=sim, meta=meta, base_dir=base_dir, overrides=overrides)
        stop.defer_to(app)
        names = split_vars(args.vars) if args.vars else None
        duration, steps = args.duration, args.steps
        try:
            if app.error is not None or refusal(app.model, duration, steps) is not None:
                return run_headless(app, duration, steps=steps)  # says what is wrong; no file is written
            csv_columns(app.model, names)  # refuse bad --vars before any file is written
            if args.csv is None:
                return run_headless(app, duration, steps=steps, variables=names, every=args.every)
            if args.csv == "-":
                try:
                    return run_headless(app, duration, steps=steps, csv_file=sys.stdout, variables=names, every=args.every)
                except BrokenPipeError:
                    # the reader (head, a pager) stopped reading: stop quietly, as command-line
                    # tools do, with the status of a SIGPIPE; later flushes go nowhere
                    os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
                    return 128 + signal.SIGPIPE
            try:
                fh = open(args.csv, "w", newline="")  # noqa: SIM115 - closed below
            except OSError as exc:
                print(f"error: cannot write {args.csv}: {exc.strerror or exc}", file=sys.stderr)
                return 2
            with fh:
                return run_headless(app, duration, steps=steps, csv_file=fh, variables=names, every=args.every)
        except UserCodeError as exc:
            print(f"error: {exc.message}", file=sys.stderr)
            return 2
    if any(v is not None for v in (args.duration, args.steps, args.csv, args.vars)):
        print("error: --duration, --steps, --csv and --vars go with --headless", file=sys.stderr)
        return 2
    try:
        from ejsrl.view._guard import parse_origin

        origins = [parse_origin(o) for o in args.allow_origin]
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.max_sessions is not None and args.max_sessions < 1:
        print("error: --max-sessions must be at least 1", file=sys.stderr)
        return 2
    if not math.isfinite(args.grace) or args.grace < 0:
        print("error: --grace must be a number of seconds >= 0", file=sys.stderr)
        return 2
    if args.processes is not None and args.processes < 1:
        print("error: --processes must be at least 1", file=sys.stderr)
        return 2
    if args.processes is not None and args.processes > 1 and args.shared:
        print("error: --shared serves one simulation from one process; leave --processes out", file=sys.stderr)
        return 2
    role = WorkerRole.from_env()
    count = args.processes if args.processes is not None else default_processes()
    if args.max_sessions is not None:
        count = min(count, args.max_sessions)  # a process with no place would serve nobody
    if role is None and not args.shared and count > 1:
        command = worker_command() if argv is None else None
        if command is not None:
            return serve_front(
                command, args.host, args.port, count=count, max_sessions=args.max_sessions,
                announce=lambda port, places: announce(meta.title, args.host, port, places=places, processes=count,
                                                       asked_port=args.port),
            )
        if args.processes is not None:
            print(f"warning: --processes {count}: this app was not started as a script (python app.py), so it cannot "
                  "start copies of itself; serving from one process", file=sys.stderr, flush=True)
    app = _served_app(model_cls, view, sim=sim, meta=meta, base_dir=base_dir, overrides=overrides, shared=args.shared)
    app.serve(args.host, args.port, allow_origins=origins, per_client=not args.shared,
              max_sessions=args.max_sessions, grace=args.grace, role=role)
    return 0
