"""The ``ejsgen`` command: new, validate, build, run, schema, docs, sweep.

User errors (bad specs, missing files) print as ``FILE:LINE:COL: error: message`` without a
traceback and exit with status 1; bad command lines exit with 2.
"""

from __future__ import annotations

import argparse
import json
import shlex
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

from ejsgen import __version__
from ejsgen.errors import EjsError
from ejsrl._signals import SignalScope

__all__ = ["main", "load_plan", "build"]

STARTER = '''\
# {title}: a starter spec made by `ejsgen new`. Build and serve it with
#   ejsgen run {file}
# The language: `ejsgen docs` (specs/language.md); a step-by-step tutorial: `ejsgen docs tutorial`.
ejs: 1
title: {title}
description: |
  A mass on a spring with damping. Move the sliders, press **Play**, and watch
  the energy decay.

model:
  variables:
    t: 0.0
    dt: 0.01
    x: {{value: 1.0, unit: m, doc: displacement}}
    v: {{value: 0.0, unit: m/s}}
    k: {{value: 4.0, unit: N/m}}
    m: {{value: 1.0, unit: kg}}
    c: {{value: 0.2, unit: N s/m, doc: damping}}
    E: 0.0
  evolution:
    - ode:
        method: rk4
        equations:
          x: v
          v: -(k*x + c*v)/m
  fixed_relations: |
    E = 0.5*m*v**2 + 0.5*k*x**2

view:
  - slider: {{bind: k, min: 0.5, max: 20, label: "Stiffness k (N/m)"}}
  - slider: {{bind: c, min: 0, max: 2, label: "Damping c (N s/m)"}}
  - label: {{text: "t = {{t:.2f}} s   E = {{E:.4f}} J"}}
  - plot: {{title: Displacement, x: t, series: [{{y: x, label: x}}], window: 10}}
  - scene:
      - box: {{position: [x, 0, 0.1], size: [0.2, 0.2, 0.2], color: steelblue}}
      - line: {{points: "[[-1.5, 0, 0.1], [x, 0, 0.1]]", width: 3, color: darkorange}}
      - grid: {{size: 4, cell: 0.5}}

simulation:
  fps: 30
  steps_per_display: 2
'''


def load_plan(spec_path: str | Path):  # -> AppPlan
    """Load, validate and compile a spec (raises ``EjsError`` subclasses for the user)."""
    from ejsgen._lab_needs import uses_opencv
    from ejsgen.compiler import compile_spec
    from ejsgen.validate import validate
    from ejsgen.yamlload import load_yaml

    path = Path(spec_path)
    doc = load_yaml(path, display_name=str(spec_path))
    checked = validate(doc)
    plan = compile_spec(checked, path.resolve())
    plan.uses_opencv = uses_opencv(checked, path.resolve())  # its requirements list OpenCV only then
    return plan


def default_out_dir(spec_path: Path) -> Path:
    name = spec_path.name
    for suffix in (".ejs.yaml", ".ejs.yml", ".yaml", ".yml"):
        if name.endswith(suffix):
            name = name[: -len(suffix)]
            break
    return Path("dist") / name


def build(spec_path: str | Path, out_dir: str | Path | None = None, *, bundle: bool = False) -> Path:
    """Build an app folder from a spec; returns the folder."""
    from ejsgen.generate import write_app

    path = Path(spec_path)
    plan = load_plan(path)
    out = Path(out_dir) if out_dir is not None else default_out_dir(path)
    write_app(plan, out, bundle=bundle)
    _warm_susan(out / "app.py")
    return out


def _warm_susan(app: Path) -> None:
    """A lab that uses SUSAN: its compiled kernels go into numba's cache in the background now,
    so the app finds them ready (``ejsrl.vision.warm.start_in_background``)."""
    from ejsrl.vision.warm import start_in_background, uses_susan

    if uses_susan(app.read_text(encoding="utf-8")):
        start_in_background()


def _cmd_new(args: argparse.Namespace) -> int:
    name = args.name
    file = Path(name if name.endswith((".ejs.yaml", ".ejs.yml")) else f"{name}.ejs.yaml")
    if file.exists() and not args.force:
        raise EjsError(f"{file} already exists (use --force to overwrite)")
    title = file.name.split(".")[0].replace("_", " ").replace("-", " ").strip().capitalize() or "New simulation"
    file.parent.mkdir(parents=True, exist_ok=True)
    shown = shlex.quote(str(file))  # a name with spaces still pastes into a shell
    file.write_text(STARTER.format(title=title, file=shown), encoding="utf-8")
    print(f"wrote {file}; try: ejsgen run {shown}")
    return 0


def _cmd_validate(args: argparse.Namespace) -> int:
    failed = 0
    for spec in args.specs:
        try:
            load_plan(spec)
        except EjsError as exc:
            print(exc, file=sys.stderr)
            failed += 1
        else:
            print(f"{spec}: ok")
    return 1 if failed else 0


def _cmd_build(args: argparse.Namespace) -> int:
    if args.web:  # a static web page that runs the lab in the browser (ejsgen._web_build, specs/web.md)
        from ejsgen._web_build import build_web

        site = build_web(args.spec, args.output or f"{default_out_dir(Path(args.spec))}-web")
        parts = {"Python": "python.wasm", "its library": next((k for k in site.sizes if k.endswith(".zip")), ""), "the lab": "lab.bin"}
        split = ", ".join(f"{label} {site.sizes[k][1] / 1e6:.1f}" for label, k in parts.items() if k in site.sizes)
        print(f"built {site.out} in {site.seconds:.1f} s: a web page, {site.download_bytes / 1e6:.1f} MB for a first "
              f"visit ({split}, the page {(site.download_bytes - sum(gz for _r, gz in site.sizes.values())) / 1e6:.1f}); "
              f"try it: python -m http.server -d {shlex.quote(str(site.out))} 8000")
        return 0
    start = time.perf_counter()
    out = build(args.spec, args.output, bundle=args.bundle)
    took = time.perf_counter() - start
    extra = f" and {out / (out.name + '.pyz')}" if args.bundle else ""
    print(f"built {out}{extra} in {took:.2f} s; run: python {out / 'app.py'}")
    return 0


class _Stopped(Exception):
    """SIGINT or SIGTERM arrived before the app was started."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


class _AppRunner(SignalScope):
    """Runs the built app as a child process and stops it on SIGINT/SIGTERM.

    The child has its own process group, so a Ctrl+C in the terminal reaches only this
    process. On the first signal the child gets the same signal once it handles stops (it
    catches SIGTERM: :func:`_catches`): the app stops cleanly (its server stopped, or its
    rows written) and prints the one line naming that signal. While the child is still
    starting up it gets SIGTERM, which ends it silently, where a SIGINT would print
    Python's KeyboardInterrupt traceback, and this process prints the line. The child is
    then waited for; a second signal, or a child still running after ``grace`` seconds,
    kills it. A signal before the child starts raises :class:`_Stopped`, so the temporary
    folder is removed on the way out.
    """

    def __init__(self, grace: float = 10.0) -> None:
        super().__init__()
        self.grace = grace
        self.proc: subprocess.Popen[bytes] | None = None
        self.signum: int | None = None

    def _handle(self, signum: int, frame: object) -> None:
        proc = self.proc
        if self.signum is None:
            self.signum = signum
            if proc is None:
                raise _Stopped(signum)
            _signal_child(proc, signum if _catches(proc.pid, signal.SIGTERM) else signal.SIGTERM)
        elif proc is not None:
            _signal_child(proc, signal.SIGKILL)

    def run(self, cmd: list[str]) -> int:
        """Start ``cmd``, wait for it; its exit status (128 + n if signal n stopped it)."""
        if self.signum is not None:
            raise _Stopped(self.signum)
        self.proc = proc = subprocess.Popen(cmd, process_group=0)
        if self.signum is not None:  # arrived while starting
            _signal_child(proc, signal.SIGTERM)
        while True:
            try:
                code = proc.wait(timeout=None if self.signum is None else self.grace)
                break
            except subprocess.TimeoutExpired:
                _signal_child(proc, signal.SIGKILL)
        if self.signum is not None:
            if code != 128 + int(self.signum):  # the app did not stop on it, and report it, itself
                print(f"ejsgen run: stopped by {signal.Signals(self.signum).name}", file=sys.stderr, flush=True)
            return 128 + int(self.signum)
        return 128 - code if code < 0 else code


def _catches(pid: int, signum: int) -> bool:
    """Whether process ``pid`` has a handler of its own for ``signum`` (Linux's
    ``/proc/PID/status``, ``SigCgt``); False where that cannot be read."""
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("SigCgt:"):
                    return bool(int(line.split()[1], 16) >> (signum - 1) & 1)
    except (OSError, ValueError):
        pass
    return False


def _signal_child(proc: subprocess.Popen[bytes], signum: int) -> None:
    try:
        proc.send_signal(signum)
    except ProcessLookupError:
        pass


def _cmd_run(args: argparse.Namespace, app_args: list[str]) -> int:
    """Build, then run the app until it ends; SIGINT/SIGTERM stop it and remove the temporary folder.

    The status is the app's, or 128 + the signal's number (130 for SIGINT, 143 for SIGTERM).
    """
    if getattr(args, "watch", False):
        from ejsgen._watch import cmd_watch

        return cmd_watch(args.spec, app_args, output=args.output, temporary=_temporary_folder)
    with _AppRunner() as runner:
        try:
            if args.output:
                out = build(args.spec, args.output)
                return runner.run([sys.executable, str(out / "app.py"), *app_args])
            with _temporary_folder("ejsgen-run-") as tmp:
                out = build(args.spec, Path(tmp) / "app")
                return runner.run([sys.executable, str(out / "app.py"), *app_args])
        except Exception:
            # _Stopped, or what an import in C (NumPy's) made of it when the signal came
            # there (an ImportError of its own): the stop that was asked for, not a failure
            if runner.signum is None or runner.proc is not None:
                raise
            print(f"ejsgen run: stopped by {signal.Signals(runner.signum).name}", file=sys.stderr)
            return 128 + int(runner.signum)


def _temporary_folder(prefix: str) -> tempfile.TemporaryDirectory[str]:
    """``tempfile.TemporaryDirectory(prefix=prefix)``, made with SIGINT and SIGTERM held back.

    Python's first look for the temporary folder writes a file there and removes it again; a
    stop signal between the two (its handler raises) left that file behind. Held back, a
    signal arrives once the folder exists, and the folder is removed on the way out."""
    stops = {signal.SIGINT, signal.SIGTERM}
    held = signal.pthread_sigmask(signal.SIG_BLOCK, stops)
    try:
        return tempfile.TemporaryDirectory(prefix=prefix)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


def _cmd_schema(args: argparse.Namespace) -> int:
    from ejsgen.schema import json_schema

    print(json.dumps(json_schema(), indent=2))
    return 0


def _parser(sweep: bool = True) -> argparse.ArgumentParser:
    """The command line; ``sweep=False`` leaves out the sweep's options (they load the runtime)."""
    p = argparse.ArgumentParser(prog="ejsgen", description="Turn .ejs.yaml simulation specs into interactive apps.")
    p.add_argument("--version", action="version", version=f"ejsgen {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    n = sub.add_parser("new", help="write a starter spec that builds and runs")
    n.add_argument("name", help="file name (NAME.ejs.yaml)")
    n.add_argument("--force", action="store_true", help="overwrite an existing file")
    v = sub.add_parser("validate", help="check specs without building")
    v.add_argument("specs", nargs="+", metavar="SPEC")
    b = sub.add_parser("build", help="build an app folder from a spec")
    b.add_argument("spec", metavar="SPEC")
    b.add_argument("-o", "--output", metavar="DIR", help="output folder (default dist/NAME)")
    b.add_argument("--bundle", action="store_true", help="also write a single-file NAME.pyz that carries the runtime")
    b.add_argument("--web", action="store_true",
                   help="build a static web page that runs the lab in the browser, no server (needs ejsgen[web]; default DIR dist/NAME-web)")
    r = sub.add_parser(
        "run",
        help="build a spec and run the app; other options go to the app",
        description="Build SPEC into a temporary folder (or -o DIR) and run the app. Every other option goes "
        "to the app, before or after SPEC: --port N, --host ADDR (0.0.0.0 opens the lab to the network), "
        "--shared (one simulation for every browser tab instead of one each), --max-sessions N, --processes N, --grace S, "
        "--allow-origin URL, --headless --duration T --csv FILE --vars a,b --set NAME=VALUE, --sweep ...; "
        "`python app.py --help` in a built app lists them all.",
    )
    r.add_argument("spec", metavar="SPEC")
    r.add_argument("-o", "--output", metavar="DIR", help="keep the built app in this folder")
    r.add_argument(
        "--watch", action="store_true",
        help="live editing: every save of SPEC (or of a file it names) rebuilds the lab in this one process and "
        "reloads every open tab, keeping the variable values you did not change; a build error shows in the "
        "page until the spec is fixed (serves on 127.0.0.1 unless --host says otherwise; not with --headless, "
        "--shared or --processes)",
    )
    sub.add_parser("schema", help="print the JSON Schema of the spec language")
    from ejsgen._docs import add_parser as _add_docs_parser

    _add_docs_parser(sub)
    from ejsgen.sweep import add_parser as _add_sweep_parser

    _add_sweep_parser(sub, options=sweep)
    from ejsgen._plant_cmd import add_parser as _add_plant_parser

    _add_plant_parser(sub)
    return p


#: the served app's options that take a value (``python app.py --help`` lists them all)
_APP_OPTIONS_WITH_VALUE = (
    "--port", "--host", "--allow-origin", "--max-sessions", "--processes", "--grace", "--duration", "--steps", "--csv", "--vars", "--set", "--every",
    "--grid", "--values", "--table", "--samples", "--sampling", "--seed", "--out", "--summary", "--plot", "--plot-y",
    "--plot-x", "--workers", "--scheduler",
)


def _split_run_args(argv: list[str]) -> tuple[list[str], list[str]]:
    """``run``'s own arguments (the spec, ``-o DIR``, ``--watch``, ``-h``) and the app's (all the others,
    before or after the spec): ``ejsgen run --port 8090 lab.ejs.yaml`` works as
    ``ejsgen run lab.ejs.yaml --port 8090``."""
    own, app, rest = [argv[0]], [], argv[1:]
    spec_seen = False
    while rest:
        arg = rest.pop(0)
        if arg in ("-o", "--output") and rest:
            own += [arg, rest.pop(0)]
        elif arg.startswith(("-o", "--output=")) and arg not in ("-o", "--output"):
            own.append(arg)
        elif arg in ("-h", "--help") and not spec_seen or arg == "--watch":
            own.append(arg)
        elif not spec_seen and not arg.startswith("-"):
            own.append(arg)
            spec_seen = True
        else:
            app.append(arg)
            if arg in _APP_OPTIONS_WITH_VALUE and rest and not spec_seen:
                app.append(rest.pop(0))  # an option's value is not the spec
    return own, app


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    app_args: list[str] = []
    if argv and argv[0] == "run":
        argv, app_args = _split_run_args(argv)
    if argv[:2] == ["plant", "serve"]:  # the reference plant's own options, --help included
        from ejsgen._plant_cmd import serve

        return serve(argv[2:])
    args = _parser(sweep=argv[:1] == ["sweep"]).parse_args(argv)
    try:
        if args.command == "new":
            return _cmd_new(args)
        if args.command == "validate":
            return _cmd_validate(args)
        if args.command == "build":
            return _cmd_build(args)
        if args.command == "run":
            return _cmd_run(args, app_args)
        if args.command == "schema":
            return _cmd_schema(args)
        if args.command == "docs":
            from ejsgen._docs import cmd_docs

            return cmd_docs(args)
        if args.command == "plant":
            from ejsgen._plant_cmd import cmd_plant

            return cmd_plant(args)
        if args.command == "sweep":
            from ejsgen.sweep import cmd_sweep

            return cmd_sweep(args)
    except EjsError as exc:
        print(exc, file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    return 2


if __name__ == "__main__":
    sys.exit(main())
