"""Grade student specs against a reference: the same sweep of runs, compared variable by variable.

    python examples/grading/grade.py                      # reference.ejs.yaml against students/*.ejs.yaml
    python examples/grading/grade.py REF.ejs.yaml FOLDER --values c=0,0.5 --values k=1,4 --duration 5 --vars x,v,E

The reference is built and run over the parameter sets (an ``ejsgen sweep`` through its
Python API, ``ejsrl.app.sweep.sweep``); each student's spec is built, and run once per
parameter set (``app.py --headless --set ...``, which gives a sweep's rows bit for bit), in
a sandbox (:mod:`ejsgen._sandbox`, the one ``ejsgen sweep --sandbox`` uses: bubblewrap,
read-only but its own folder, no network, CPU, memory and wall-time limits): spec code is
Python and could otherwise do anything the teacher can. A student passes when
every compared variable of every run stays within ``--rtol``/``--atol`` of the reference at
every recorded step. The report names, for each student, the variables that differ and
the worst difference (where and with which parameters), or why the spec does not build or
run; ``--report grades.csv`` also writes it as a table. See specs/sweeps.md.
"""

from __future__ import annotations

import argparse
import csv
import signal
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ejsgen._sandbox import Limits, bwrap_hint, contained, handin_files

HERE = Path(__file__).resolve().parent


@dataclass
class Grade:
    """One student's result: passed, the variables that differ (name: worst absolute difference), why."""

    name: str
    passed: bool
    differ: dict[str, float] = field(default_factory=dict)
    detail: str = ""


def run_reference(spec: Path, out: Path, args: argparse.Namespace):
    """Build the teacher's ``spec`` and run the grading sweep on it (in this process: it is the
    teacher's own code); raises ``EjsError`` when it does not build."""
    from ejsgen.cli import build
    from ejsrl.app.sweep import sweep

    app = build(spec, out)
    return sweep(app, values=args.values, grid=args.grid, duration=args.duration, variables=args.vars.split(","), workers=args.workers)


def run_handin(spec: Path, work: Path, reference, args: argparse.Namespace, limits: Limits) -> tuple[Grade | None, dict[str, list[str]]]:
    """Build a hand-in and run each of the reference's runs with it, each step in the sandbox.

    Returns (a failing ``Grade`` if it does not build or a run fails, else None) and the
    recorded columns of all its runs, one after the other in run order (with ``run``).
    """
    work.mkdir(parents=True)
    built = contained([sys.executable, "-P", "-m", "ejsgen", "build", str(spec.resolve()), "-o", str(work / "app")], writable=work,
                       readable=handin_files(spec), limits=limits)
    if built.status != 0:
        why = built.reason or next((line for line in built.stderr.splitlines() if "error" in line), built.stderr.strip()[-300:])
        return Grade(spec.name, False, detail=f"does not build: {why}"), {}
    ind = reference.independent or "t"
    names = [ind] + [n for n in args.vars.split(",") if n != ind]
    got: dict[str, list[str]] = {"run": []}
    for run in reference.runs:
        out = work / f"run{run.run}.csv"
        cmd = [sys.executable, "-P", str(work / "app" / "app.py"), "--headless", "--duration", repr(args.duration),
               "--vars", ",".join(names), "--csv", str(out)]
        for item in run.set_args():
            cmd += ["--set", item]
        done = contained(cmd, writable=work, limits=limits)
        settings = " ".join(f"{n}={v}" for n, v in run.settings)
        if done.status == 2 and not done.reason and "--vars" in done.stderr or "--set" in done.stderr and "unknown variable" in done.stderr:
            return Grade(spec.name, False, detail=f"does not fit the exercise: {_last_error(done.stderr)}"), {}
        if done.status != 0 or done.reason:
            return Grade(spec.name, False, detail=f"run {run.run} ({settings}) failed: {done.reason or _last_error(done.stderr)}"), {}
        with open(out, newline="") as fh:
            rows = list(csv.reader(fh))
        for j, name in enumerate(rows[0]):
            got.setdefault(name, []).extend(row[j] for row in rows[1:])
        got["run"].extend([run.run] * (len(rows) - 1))
    return None, got


def _last_error(stderr: str) -> str:
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    errors = [line for line in lines if "error" in line]
    text = (errors or lines or ["it ended without a word"])[-1]
    return text[len("error: "):] if text.startswith("error: ") else text


def compare(reference, got: dict[str, list[str]], names: list[str], rtol: float, atol: float) -> Grade:
    """Compare a hand-in's recorded columns with the reference's, run by run and step by step."""
    ref = reference.results_table().to_pydict()
    ind = reference.independent or "t"
    differ: dict[str, float] = {}
    worst = ""
    worst_ratio = 0.0
    columns = [c for c in ref if c.split("[")[0] in names]
    for col in columns:
        if col not in got:
            differ[col] = float("inf")
            worst = worst or f"'{col}' is not recorded (is the variable declared with the same name and shape?)"
            continue
        a = np.array(ref[col], dtype=float)
        b = np.array([float(v) for v in got[col]], dtype=float) if len(got[col]) == len(a) else None
        if b is None:
            differ[col] = float("inf")
            worst = worst or f"{len(got[col])} rows instead of {len(a)} (does the run stop early?)"
            continue
        gap = np.abs(a - b)
        allowed = atol + rtol * np.abs(a)
        bad = ~(gap <= allowed)  # NaN counts as a difference
        if bad.any():
            differ[col] = float(np.nanmax(np.where(bad, gap, 0.0))) if not np.isnan(gap[bad]).all() else float("nan")
            i = int(np.argmax(np.where(bad, np.nan_to_num(gap / allowed, nan=np.inf), -1.0)))
            ratio = float(np.nan_to_num(gap[i] / allowed[i], nan=np.inf))
            if ratio > worst_ratio:
                worst_ratio = ratio
                run = ref["run"][i]
                params = " ".join(f"{n}={v}" for n, v in reference.results[run].settings)
                worst = f"worst: {col} = {b[i]:.6g} instead of {a[i]:.6g} at {ind} = {ref[ind][i]:g} in run {run} ({params})"
    return Grade("", not differ, differ, worst)


class _Stopped(Exception):
    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _stop(signum: int, frame: object) -> None:
    raise _Stopped(signum)


def _grade_all(args: argparse.Namespace, students: list[Path], tmp: Path, limits: Limits, names: list[str], grades: list[Grade]) -> int | None:
    """Run the reference, then grade each hand-in into ``grades``; an exit status when it cannot go on."""
    from ejsgen.errors import EjsError

    try:
        reference = run_reference(Path(args.reference), tmp / "reference", args)
    except EjsError as exc:
        print(f"error: the reference does not build: {str(exc).splitlines()[0]}", file=sys.stderr)
        return 2
    except ValueError as exc:
        print(f"error: the reference does not fit these options: {exc}", file=sys.stderr)
        return 2
    except _Stopped as stop:
        reference = None
        signum: int | None = stop.signum
    else:
        signum = reference.interrupted
    if signum:  # never grade against a cut-short reference
        print(f"stopped by {signal.Signals(signum).name} while running the reference; no hand-in was graded", file=sys.stderr)
        return 128 + int(signum)
    assert reference is not None
    if reference.failed:
        print(f"error: the reference fails: {reference.failed[0].error}", file=sys.stderr)
        return 2
    try:
        for i, spec in enumerate(students):
            failed, got = run_handin(spec, tmp / f"student{i}", reference, args, limits)
            grade = failed or compare(reference, got, names, args.rtol, args.atol)
            grade.name = spec.name
            grades.append(grade)
            verdict = "PASS" if grade.passed else "FAIL"
            what = f"{', '.join(grade.differ)} differ{'s' if len(grade.differ) == 1 else ''}; " if grade.differ else ""
            print(f"{spec.name}: {verdict}" + (f": {what}{grade.detail}" if not grade.passed else f" ({len(reference.runs)} runs)"),
                  flush=True)
    except _Stopped as stop:
        print(f"stopped by {signal.Signals(stop.signum).name} after {len(grades)} of {len(students)} hand-ins; "
              "the others are not graded", file=sys.stderr, flush=True)
        return 128 + stop.signum
    return None


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description="Grade student specs against a reference by running both over the same parameter sets; "
                                "each hand-in is built and run in a sandbox (bubblewrap) with limits.")
    p.add_argument("reference", nargs="?", default=str(HERE / "reference.ejs.yaml"))
    p.add_argument("students", nargs="?", default=str(HERE / "students"), help="a folder of .ejs.yaml files")
    p.add_argument("--values", action="append", help="parameter values, as ejsgen sweep --values (default: c=0,0.5 and k=1,4)")
    p.add_argument("--grid", action="append", default=[], help="as ejsgen sweep --grid")
    p.add_argument("--duration", type=float, default=5.0, help="each run's duration (default 5)")
    p.add_argument("--vars", default="x,v,E", help="the variables compared (default x,v,E)")
    p.add_argument("--rtol", type=float, default=1e-6, help="relative tolerance (default 1e-6)")
    p.add_argument("--atol", type=float, default=1e-9, help="absolute tolerance (default 1e-9)")
    p.add_argument("--workers", type=int, default=0, help="worker processes of the reference's sweep (default 0: in this process)")
    p.add_argument("--cpu-limit", type=float, default=30.0, metavar="S", help="CPU seconds a hand-in's build or run may use (default 30)")
    p.add_argument("--memory-limit", type=int, default=3000, metavar="MB", help="memory a hand-in's build or run may use (default 3000 MB)")
    p.add_argument("--wall-limit", type=float, default=120.0, metavar="S", help="real seconds a hand-in's build or run may take (default 120)")
    p.add_argument("--report", metavar="CSV", help="also write the grades as a table")
    args = p.parse_args(argv)
    if args.values is None:
        args.values = ["c=0,0.5", "k=1,4"]
    hint = bwrap_hint()
    if hint:
        print(f"error: {hint}", file=sys.stderr)
        return 2
    limits = Limits(args.cpu_limit, args.memory_limit, args.wall_limit)
    names = args.vars.split(",")
    grades: list[Grade] = []
    students = sorted(Path(args.students).glob("*.ejs.yaml"))
    previous = {s: signal.signal(s, _stop) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        with tempfile.TemporaryDirectory(prefix="ejsgen-grade-") as tmp:
            status = _grade_all(args, students, Path(tmp), limits, names, grades)
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    if status is not None:
        return status
    if args.report:
        with open(args.report, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["student", "passed", "differing", "detail"])
            for g in grades:
                w.writerow([g.name, int(g.passed), " ".join(g.differ), g.detail])
    passed = sum(g.passed for g in grades)
    print(f"{passed} of {len(grades)} passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
