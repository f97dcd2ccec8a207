"""Parameter sweeps and batch runs: many headless runs of one model, collected into tables.

``python app.py --sweep --grid L=0.5:2:4 --values b=0,0.1 --duration 10 --out runs.parquet``
(and ``ejsgen sweep SPEC ...``, which builds the spec first) runs the model once per point
of the design (:mod:`ejsrl.app.sweep_design`), each run a headless run with ``--set``
settings, in worker processes that import the model once (:mod:`ejsrl.app.sweep_worker`):
a local process pool sized to the cores, this process (``--workers 0``), or Dask
(``--dask``, ``--scheduler tcp://host:8786``; :mod:`ejsrl.app.sweep_exec`). The results
go into a tidy table and a summary table (:mod:`ejsrl.app.sweep_table`), as Parquet or
CSV, and optionally a plot (:mod:`ejsrl.app.sweep_plot`).

From Python: ``result = sweep("dist/pendulum", grid=["L=0.5:2:4"], duration=10)``, then
``result.summary()`` and ``result.results()`` (``.to_pydict()``, or written with
:func:`~ejsrl.app.sweep_table.write_table`).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ejsrl.app.sweep_design import Run, SweepDesignError, design
from ejsrl.app._rowfile import CannotWrite
from ejsrl.app.sweep_exec import DASK_HINT, Executor, Progress, SchedulerLost, cpu_count, execute
from ejsrl.app.sweep_journal import Journal, JournalError, assemble, parts_folder, sweep_key
from ejsrl.app.sweep_table import PYARROW_HINT, SUMMARY_COLUMNS, Table, results_table, summary_table, write_table
from ejsrl.app.sweep_worker import AppRef, LoadedApp, RunOptions, RunResult, app_ref, loaded, register

__all__ = ["SweepResult", "sweep", "add_sweep_options", "sweep_main", "app_sweep", "summary_path", "EXIT_CANNOT_WRITE", "EXIT_SCHEDULER_LOST"]

EXIT_CANNOT_WRITE = 74
"""The status of a sweep that could not write its tables or keep its runs (EX_IOERR)."""

EXIT_SCHEDULER_LOST = 69
"""The status of a sweep whose Dask scheduler was lost (EX_UNAVAILABLE)."""


@dataclass
class SweepResult:
    """A finished (or stopped) sweep: every run's result, by run number."""

    runs: list[Run]
    results: list[RunResult]
    types: dict[str, str]
    independent: str | None
    seconds: float
    interrupted: int | None = None

    @property
    def metric_names(self) -> list[str]:
        names: list[str] = []
        for r in self.results:
            for n in r.metrics:
                if n not in names:
                    names.append(n)
        return names

    @property
    def failed(self) -> list[RunResult]:
        return [r for r in self.results if r.status == "error"]

    def results_table(self) -> Table:
        return results_table(self.results, self.types, self.independent)

    def summary(self) -> Table:
        return summary_table(self.results, self.types, self.metric_names)


def check_settings(runs: Sequence[Run], types: dict[str, str]) -> None:
    """Parse every run's settings as ``--set`` would, before any run starts (``SweepDesignError``)."""
    from ejsrl.app.cli import parse_set

    seen: set[tuple[str, str]] = set()
    for run in runs:
        for name, text in run.settings:
            if (name, text) in seen:
                continue
            seen.add((name, text))
            try:
                parse_set(f"{name}={text}", types)
            except ValueError as exc:  # parse_set words it for --set; here it is a parameter's value
                message = str(exc)
                raise SweepDesignError("parameter " + message[len("--set "):] if message.startswith("--set ") else message) from None
            if name in SUMMARY_COLUMNS:
                raise SweepDesignError(f"the parameter '{name}' has the name of a column of the summary ({', '.join(SUMMARY_COLUMNS)})")


def check_variables(names: Sequence[str] | None, types: dict[str, str]) -> None:
    """Refuse a ``--vars`` name that is not a variable (``SweepDesignError``, with a suggestion)."""
    for n in names or ():
        if n not in types:
            from ejsrl._suggest import did_you_mean

            raise SweepDesignError(f"--vars: unknown variable '{n}'{did_you_mean(n, types)}")


def sweep(
    app: str | Path | AppRef,
    *,
    duration: float,
    grid: Sequence[str] = (),
    values: Sequence[str] = (),
    table: str | Path | None = None,
    samples: int | None = None,
    seed: int | None = None,
    sampling: str = "lhs",
    fixed: Sequence[str] = (),
    variables: Sequence[str] | None = None,
    every: int = 1,
    workers: int | None = None,
    dask: bool = False,
    scheduler: str | None = None,
    progress: Progress | None = None,
) -> SweepResult:
    """Run a sweep of the built app in folder ``app`` (see the command line for the options).

    Raises ``SweepDesignError`` (a ``ValueError``) for a parameter or variable the model does not have."""
    ref = app if isinstance(app, AppRef) else app_ref(app)
    model_cls = loaded(ref).model_cls
    types = dict(model_cls.VARIABLES)
    check_variables(variables, types)
    runs = design(types, grid=grid, values=values, table=table, samples=samples, seed=seed, sampling=sampling, fixed=fixed)
    check_settings(runs, types)
    options = RunOptions(float(duration), tuple(variables) if variables is not None else None, every)
    ex = Executor(cpu_count() if workers is None else workers, dask=dask, scheduler=scheduler)
    start = time.perf_counter()
    if progress is not None:
        progress.total = len(runs)
    results, signum = execute(ref, runs, options, ex, progress=progress)
    return SweepResult(runs, results, types, model_cls.INDEPENDENT, time.perf_counter() - start, signum)


# -- the command line ------------------------------------------------------------------------------------


def add_sweep_options(p: argparse.ArgumentParser) -> None:
    """The options of ``app.py --sweep`` and ``ejsgen sweep``."""
    d = p.add_argument_group("the runs (their product; each setting means what --set means in a headless run)")
    d.add_argument("--grid", action="append", default=[], metavar="NAME=start:stop:count", help="count evenly spaced values, ends included (repeatable)")
    d.add_argument("--values", action="append", default=[], metavar="NAME=a,b,c", help="these values (lists keep their commas: q0=[0,0],[1,1]; repeatable)")
    d.add_argument("--table", metavar="params.csv", help="one run per row: a header of variable names, then values")
    d.add_argument("--samples", type=int, metavar="N", help="N points drawn from the --grid ranges (NAME=start:stop) instead of a grid")
    d.add_argument("--sampling", choices=("lhs", "random"), default="lhs", help="with --samples: Latin hypercube (default) or uniform random")
    d.add_argument("--seed", type=int, metavar="S", help="with --samples: the random seed (the same seed, the same points)")
    d.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="a value for every run (repeatable)")
    r = p.add_argument_group("each run")
    r.add_argument("--duration", type=float, required=True, metavar="T", help="how long each run lasts, in units of the independent variable")
    r.add_argument("--vars", metavar="a,b,q", help="the variables to record (default: every numeric variable)")
    r.add_argument("--every", type=int, default=1, metavar="N", help="record a row every N steps (default 1)")
    o = p.add_argument_group("output")
    o.add_argument("--out", default="sweep.parquet", metavar="FILE", help="the results table: .parquet (default sweep.parquet; needs pyarrow) or .csv")
    o.add_argument("--summary", metavar="FILE", help="the summary table (default: beside --out, runs.parquet -> runs.summary.parquet)")
    o.add_argument("--plot", metavar="PNG", help="draw a summary column against one or two parameters (needs matplotlib)")
    o.add_argument("--plot-y", metavar="COLUMN", help="the summary column to plot (default: the first metric, else a final value)")
    o.add_argument("--plot-x", metavar="P[,Q]", help="the parameter on the x axis (and the one of the curves); default: the one with the most values, then the next")
    o.add_argument("--quiet", action="store_true", help="no progress bar")
    o.add_argument("--resume", action="store_true", help="continue a stopped sweep (same options): run only the runs its OUT.parts folder lacks")
    x = p.add_argument_group("where the runs execute")
    x.add_argument("--workers", type=int, metavar="N", help=f"processes (default: the cores, {cpu_count()} here; 0: in this process)")
    x.add_argument("--dask", action="store_true", help="start a Dask LocalCluster of --workers processes and run there")
    x.add_argument("--scheduler", metavar="tcp://host:8786", help="run on the Dask cluster of this scheduler")


def summary_path(out: str | Path) -> Path:
    """``runs.parquet`` -> ``runs.summary.parquet``."""
    out = Path(out)
    return out.with_name(f"{out.stem}.summary{out.suffix or '.parquet'}")


def _check_output(args: argparse.Namespace) -> str | None:
    for path in (args.out, args.summary):
        if path is None:
            continue
        parent = Path(path).resolve().parent
        if not parent.is_dir():
            return f"cannot write {path}: the folder {parent} does not exist"
        if Path(path).suffix.lower() != ".csv":
            try:
                import pyarrow  # noqa: F401
            except ImportError:
                return PYARROW_HINT
    if args.dask or args.scheduler:
        try:
            import distributed  # noqa: F401
        except ImportError:
            return DASK_HINT
    if args.plot:
        from ejsrl.app.sweep_plot import check_matplotlib

        return check_matplotlib()
    return None


def sweep_main(ref: AppRef, app: LoadedApp, args: argparse.Namespace, *, label: str, sandbox: Any = None) -> int:
    """Run the sweep the parsed command line asks for; write its tables; the exit status.

    0 when the tables were written and some run succeeded, 1 when every run failed, 2 for a
    wrong command line, 128 + n when signal n stopped the sweep (the finished runs are written),
    ``EXIT_CANNOT_WRITE`` (74) when a file could not be written, ``EXIT_SCHEDULER_LOST`` (69)
    when the Dask scheduler was lost. Finished runs are kept in ``OUT.parts/`` as they finish
    (:mod:`ejsrl.app.sweep_journal`); ``--resume`` runs only the ones missing there.
    ``sandbox``: a :class:`~ejsrl.app.sweep_sandbox.ContainedRuns` that runs each run contained.
    """
    err = sys.stderr
    np.seterr(all="ignore")
    if args.duration is None or not math.isfinite(args.duration) or args.duration < 0:
        print("error: --duration T must be a number >= 0", file=err)
        return 2
    if args.every < 1:
        print("error: --every must be at least 1", file=err)
        return 2
    if args.workers is not None and args.workers < 0:
        print("error: --workers must be 0 or more", file=err)
        return 2
    if args.dask and args.scheduler:
        print("error: --dask starts a cluster here; --scheduler uses a running one: give one of them", file=err)
        return 2
    if args.dask and args.workers == 0:
        print("error: --dask needs at least one worker", file=err)
        return 2
    problem = _check_output(args)
    if problem:
        print(f"error: {problem}", file=err)
        return 2
    model_cls = app.model_cls
    types = dict(model_cls.VARIABLES)
    names = [n.strip() for n in args.vars.split(",") if n.strip()] if args.vars else None
    try:
        check_variables(names, types)
        runs = design(
            types, grid=args.grid, values=args.values, table=args.table, samples=args.samples, seed=args.seed, sampling=args.sampling, fixed=args.set
        )
        check_settings(runs, types)
    except SweepDesignError as exc:
        print(f"error: {exc}", file=err)
        return 2
    options = RunOptions(float(args.duration), tuple(names) if names is not None else None, args.every)
    ex = Executor(cpu_count() if args.workers is None else args.workers, dask=args.dask, scheduler=args.scheduler, sandbox=sandbox)
    if not ex.dask and not ex.scheduler and ex.workers > len(runs):
        ex.workers = len(runs)
    parts = parts_folder(args.out)
    try:
        journal = Journal.start(parts, sweep_key(ref.digest, runs, options), len(runs), resume=bool(getattr(args, "resume", False)))
    except JournalError as exc:
        print(f"error: {exc}", file=err)
        return 2
    except (CannotWrite, OSError) as exc:
        print(exc.line() if isinstance(exc, CannotWrite) else f"error: cannot write {parts}: {exc.strerror or exc}", file=err)
        return EXIT_CANNOT_WRITE
    done = journal.done()
    todo = [r for r in runs if r.run not in done]
    plural = "s" if len(runs) != 1 else ""
    span = f"each advancing {model_cls.INDEPENDENT} by {args.duration:g}" if model_cls.INDEPENDENT else f"each of {args.duration:g} steps"
    resuming = f" (resuming: {len(done)} done, {len(todo)} to run)" if done else ""
    print(f"{label}: {len(runs)} run{plural}, {span}, on {ex.describe()}{resuming}", file=err, flush=True)
    progress = None if args.quiet else Progress(len(runs), err)
    if progress is not None:
        progress.skip(len(done))
    start = time.perf_counter()
    try:
        _, signum = execute(ref, todo, options, ex, progress=progress, on_batch=journal.write)
    except SchedulerLost as exc:
        print(f"error: the Dask scheduler at {exc.address} was lost after {len(journal.done())} of {len(runs)} runs; "
              f"finished runs are in {parts}; rerun with --resume", file=err, flush=True)
        return EXIT_SCHEDULER_LOST
    except CannotWrite as exc:
        print(f"{exc.line()}; the {len(journal.done())} finished runs are kept in {parts}: rerun with --resume once there is room",
              file=err, flush=True)
        return EXIT_CANNOT_WRITE
    except RuntimeError as exc:  # Dask could not start or reach its scheduler
        print(f"error: {exc}", file=err)
        return 2
    except OSError as exc:  # e.g. the scheduler's address does not answer
        print(f"error: {ex.describe()}: {exc}", file=err)
        return 2
    seconds = time.perf_counter() - start
    summary_file = Path(args.summary) if args.summary else summary_path(args.out)
    try:
        tally = assemble(journal, Path(args.out), summary_file, types, model_cls.INDEPENDENT, keep_summary=bool(args.plot))
    except CannotWrite as exc:
        print(f"error: cannot write {exc.path}: {exc.reason}; removed it; the finished runs are kept in {parts}: "
              "rerun with --resume once there is room",
              file=err, flush=True)
        return EXIT_CANNOT_WRITE
    if not signum:
        journal.remove()
    ran = tally.runs - len(done)
    rate = ran / seconds if seconds > 0 else math.inf
    stopped = f"stopped by {_signal_name(signum)} after {tally.runs} of {len(runs)} runs; " if signum else ""
    counts = f"{tally.runs} run{'s' if tally.runs != 1 else ''} ({tally.ok} ok, {tally.failed} failed)"
    if not todo:  # a resumed sweep whose runs had all finished: only the tables were left to write
        counts = f"nothing to run: all {counts} were already in {parts}"
    elif done:  # resumed: the rate is of the runs computed now
        counts += f" in {seconds:.2f} s: {ran} run now ({rate:.1f} runs/s), {len(done)} were already in {parts}"
    else:
        counts += f" in {seconds:.2f} s ({rate:.1f} runs/s)"
    print(f"{label}: {stopped}{counts}; wrote {args.out} ({tally.rows} rows) and {summary_file}", file=err, flush=True)
    if signum:
        print(f"{label}: the finished runs are kept in {parts}; rerun with --resume to run the other {len(runs) - tally.runs}",
              file=err, flush=True)
    for r in tally.first_failed:
        settings = " ".join(f"{n}={v}" for n, v in r.settings)
        print(f"  run {r.run} ({settings or 'the spec as written'}): {r.error}", file=err)
    if tally.failed > 5:
        print(f"  ... and {tally.failed - 5} more (the summary's error column has each)", file=err)
    if args.plot:
        from ejsrl.app.sweep_plot import PlotError, plot_summary

        try:
            assert tally.summary is not None
            plot_summary(tally.summary, [name for name, _ in runs[0].settings] if runs else [], args.plot, y=args.plot_y, x=args.plot_x)
            print(f"{label}: drew {args.plot}", file=err)
        except PlotError as exc:
            print(f"error: --plot: {exc}", file=err)
            return 2
        except OSError as exc:  # a full disk, a read-only folder
            from ejsrl.app.sweep_journal import writing_reason

            print(f"error: cannot write {args.plot}: {writing_reason(exc)}", file=err)
            return EXIT_CANNOT_WRITE
    if signum:
        return 128 + int(signum)
    return 1 if tally.runs and tally.ok == 0 else 0


def _signal_name(signum: int) -> str:
    import signal

    return signal.Signals(signum).name


def sweep_parser(prog: str, description: str) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=prog, description=description)
    p.add_argument("--sweep", action="store_true", help=argparse.SUPPRESS)
    add_sweep_options(p)
    return p


def app_sweep(
    model_cls: type, view: list[Any], *, sim: Any, meta: Any, base_dir: Path | str, argv: Sequence[str]
) -> int:
    """``python app.py --sweep ...``: a sweep of this app (its folder is what workers import)."""
    prog = f"{Path(sys.argv[0]).name} --sweep"
    args = sweep_parser(prog, f"{meta.title}: run the model over many parameter values (an ejsgen sweep).").parse_args(list(argv))
    import tempfile

    with tempfile.TemporaryDirectory(prefix="ejsrl-sweep-") as tmp:
        folder = Path(base_dir)
        if not (folder / "app.py").is_file():  # a single-file bundle (.pyz): app.py is inside the archive
            folder = _unpacked_app(model_cls, folder, Path(tmp))
        ref = app_ref(folder)
        app = LoadedApp(model_cls, view, sim, meta, Path(base_dir))
        register(ref, app)
        return sweep_main(ref, app, args, label=meta.title)


def _unpacked_app(model_cls: type, assets: Path, into: Path) -> Path:
    """A folder holding the app's ``app.py`` (from its module's source) and its assets, for workers to import."""
    import inspect
    import shutil

    module = sys.modules[model_cls.__module__]
    if assets.is_dir():
        shutil.copytree(assets, into, dirs_exist_ok=True)
    (into / "app.py").write_text(inspect.getsource(module), encoding="utf-8")
    return into
