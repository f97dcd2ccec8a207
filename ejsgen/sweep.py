"""``ejsgen sweep SPEC ...``: build a spec, then run it over many parameter values.

The sweep itself is the runtime's (:mod:`ejsrl.app.sweep`), the same one a built app runs
with ``python app.py --sweep ...``; this command builds the app into a temporary folder
(or ``-o DIR``) first, so a spec's errors are reported as ``FILE:LINE:COL`` before any run.

``--sandbox`` sweeps a spec you did not write (a student's hand-in): the build and every
run are contained by :mod:`ejsgen._sandbox` (bubblewrap: read-only file system but the
run's own folder, no network, CPU, memory, file and wall-time limits per run), each run a
process of its own (:mod:`ejsrl.app.sweep_sandbox`); this process never imports the app.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["add_parser", "cmd_sweep"]


def add_parser(sub: Any, *, options: bool = True) -> None:
    """Add the ``sweep`` subcommand to ``ejsgen``'s subparsers.

    Its options come from the runtime (``ejsrl.app``, which loads the web UI's libraries), so
    the other commands leave them out (``options=False``) and start quickly.
    """
    s = sub.add_parser(
        "sweep",
        help="run a spec over a grid, lists, a table or samples of parameter values; collect the results in tables",
        description="Build SPEC, then run it headless once per parameter set, in worker processes (or on Dask); "
        "write every run's recorded variables (--out) and a summary of each run (final, min, max, metrics). "
        "Example: ejsgen sweep pendulum.ejs.yaml --grid L=0.5:2:4 --values b=0,0.1 --duration 10 --out runs.parquet",
    )
    s.add_argument("spec", metavar="SPEC")
    s.add_argument("-o", "--output", metavar="DIR", help="keep the built app in this folder (default: a temporary one)")
    b = s.add_argument_group("a spec you did not write (a student's hand-in): build it and run each run in a sandbox")
    b.add_argument("--sandbox", action="store_true", help="build and run in bubblewrap: read-only file system but the run's "
                   "own folder, no network, the limits below per build and per run (a run past one fails, the others go on)")
    b.add_argument("--cpu-limit", type=float, default=30.0, metavar="S", help="with --sandbox: CPU seconds per build or run (default 30)")
    b.add_argument("--memory-limit", type=int, default=3000, metavar="MB", help="with --sandbox: memory per build or run (default 3000 MB)")
    b.add_argument("--wall-limit", type=float, default=120.0, metavar="S", help="with --sandbox: real seconds per build or run (default 120)")
    b.add_argument("--file-limit", type=int, default=1000, metavar="MB", help="with --sandbox: the largest file (and /tmp) a build or run "
                   "may write (default 1000 MB)")
    if options:
        from ejsrl.app.sweep import add_sweep_options

        add_sweep_options(s)


def cmd_sweep(args: argparse.Namespace) -> int:
    from ejsgen.cli import build

    if args.sandbox:
        return _sweep_contained(args)
    if args.output:
        return _sweep_folder(build(args.spec, args.output), args)
    with tempfile.TemporaryDirectory(prefix="ejsgen-sweep-") as tmp:
        return _sweep_folder(build(args.spec, Path(tmp) / "app"), args)


def _sweep_folder(folder: Path, args: argparse.Namespace) -> int:
    from ejsrl.app.sweep import sweep_main
    from ejsrl.app.sweep_worker import app_ref, loaded

    ref = app_ref(folder)
    app = loaded(ref)
    return sweep_main(ref, app, args, label=f"ejsgen sweep {Path(args.spec).name}")


def _sweep_contained(args: argparse.Namespace) -> int:
    """``--sandbox``: build the spec in a sandbox, learn its variables in another, run each run in its own."""
    import shutil
    import sys
    import threading

    from ejsgen._sandbox import Contained, Limits, bwrap_hint, contained, handin_files
    from ejsrl.app.sweep import sweep_main
    from ejsrl.app.sweep_sandbox import ContainedRuns, SandboxError
    from ejsrl.app.sweep_worker import app_ref

    err = sys.stderr
    hint = bwrap_hint("ejsgen sweep --sandbox")
    if hint:
        print(f"error: {hint}", file=err)
        return 2
    if args.dask or args.scheduler:
        print("error: --sandbox runs each run in bubblewrap on this machine; it cannot run on Dask (leave out --dask/--scheduler)", file=err)
        return 2
    if min(args.cpu_limit, args.wall_limit) <= 0 or min(args.memory_limit, args.file_limit) <= 0:
        print("error: --cpu-limit, --memory-limit, --wall-limit and --file-limit must be more than 0", file=err)
        return 2
    limits = Limits(args.cpu_limit, args.memory_limit, args.wall_limit, args.file_limit)
    spec = Path(args.spec).resolve()
    if not spec.is_file():
        print(f"error: {args.spec}: no such file", file=err)
        return 1

    def contain(cmd: list[str], writable: Path, readable: list[Path], stop: threading.Event | None) -> Contained:
        return contained(cmd, writable=writable, readable=readable, limits=limits, stop=stop)

    with tempfile.TemporaryDirectory(prefix="ejsgen-sweep-") as tmp:
        work = Path(tmp) / "build"
        work.mkdir()
        folder = work / "app"
        built = contain([sys.executable, "-P", "-m", "ejsgen", "build", str(spec), "-o", str(folder)], work, handin_files(spec), None)
        if built.status != 0 or built.reason:  # the build's own FILE:LINE:COL message, or the limit it hit
            print(f"error: {args.spec}: the build {built.reason}" if built.reason else built.stderr.strip() or f"error: {args.spec}: "
                  f"the build ended with status {built.status}", file=err)
            return 1
        if args.output:
            shutil.copytree(folder, args.output, symlinks=True, dirs_exist_ok=True)
        runs = ContainedRuns(folder, Path(tmp) / "runs", contain, result_limit=limits.file_mb * 1024 * 1024)
        try:
            app = runs.describe()
        except SandboxError as exc:
            print(f"error: {args.spec}: {exc}", file=err)
            return 1
        return sweep_main(app_ref(folder), app, args, label=f"ejsgen sweep --sandbox {spec.name}", sandbox=runs)
