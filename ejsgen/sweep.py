"""``ejsgen sweep SPEC ...``: build a spec, then run it over many parameter values.

The sweep itself is the runtime's (:mod:`ejsrl.app.sweep`), the same one a built app runs
with ``python app.py --sweep ...``; this command builds the app into a temporary folder
(or ``-o DIR``) first, so a spec's errors are reported as ``FILE:LINE:COL`` before any run.
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
    if options:
        from ejsrl.app.sweep import add_sweep_options

        add_sweep_options(s)


def cmd_sweep(args: argparse.Namespace) -> int:
    from ejsgen.cli import build

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
