"""Grade student specs against a reference: the same sweep of runs, compared variable by variable.

    python examples/grading/grade.py                      # reference.ejs.yaml against students/*.ejs.yaml
    python examples/grading/grade.py REF.ejs.yaml FOLDER --values c=0,0.5 --values k=1,4 --duration 5 --vars x,v,E

The reference and every student's spec are built and run over the same parameter sets (an
``ejsgen sweep`` through its Python API, ``ejsrl.app.sweep.sweep``); a student passes when
every compared variable of every run stays within ``--rtol``/``--atol`` of the reference at
every recorded step. The report names, for each student, the variables that differ and
the worst difference (where and with which parameters), or why the spec does not build or
run; ``--report grades.csv`` also writes it as a table. See specs/sweeps.md.
"""

from __future__ import annotations

import argparse
import csv
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


@dataclass
class Grade:
    """One student's result: passed, the variables that differ (name: worst absolute difference), why."""

    name: str
    passed: bool
    differ: dict[str, float] = field(default_factory=dict)
    detail: str = ""


def run_sweep(spec: Path, out: Path, args: argparse.Namespace):
    """Build ``spec`` and run the grading sweep on it; raises ``EjsError`` when it does not build."""
    from ejsgen.cli import build
    from ejsrl.app.sweep import sweep

    app = build(spec, out)
    return sweep(app, values=args.values, grid=args.grid, duration=args.duration, variables=args.vars.split(","), workers=args.workers)


def compare(reference, student, names: list[str], rtol: float, atol: float) -> Grade:
    """Compare two sweeps of the same runs, variable by variable."""
    failed = [r for r in student.results if r.status == "error"]
    if failed:
        r = failed[0]
        settings = " ".join(f"{n}={v}" for n, v in r.settings)
        return Grade("", False, detail=f"run {r.run} ({settings}) failed: {r.error}")
    ref, got = reference.results_table().to_pydict(), student.results_table().to_pydict()
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
        b = np.array(got[col], dtype=float) if len(got[col]) == len(a) else None
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


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description="Grade student specs against a reference by running both over the same parameter sets.")
    p.add_argument("reference", nargs="?", default=str(HERE / "reference.ejs.yaml"))
    p.add_argument("students", nargs="?", default=str(HERE / "students"), help="a folder of .ejs.yaml files")
    p.add_argument("--values", action="append", help="parameter values, as ejsgen sweep --values (default: c=0,0.5 and k=1,4)")
    p.add_argument("--grid", action="append", default=[], help="as ejsgen sweep --grid")
    p.add_argument("--duration", type=float, default=5.0, help="each run's duration (default 5)")
    p.add_argument("--vars", default="x,v,E", help="the variables compared (default x,v,E)")
    p.add_argument("--rtol", type=float, default=1e-6, help="relative tolerance (default 1e-6)")
    p.add_argument("--atol", type=float, default=1e-9, help="absolute tolerance (default 1e-9)")
    p.add_argument("--workers", type=int, default=0, help="worker processes per sweep (default 0: in this process)")
    p.add_argument("--report", metavar="CSV", help="also write the grades as a table")
    args = p.parse_args(argv)
    if args.values is None:
        args.values = ["c=0,0.5", "k=1,4"]
    from ejsgen.errors import EjsError

    names = args.vars.split(",")
    grades: list[Grade] = []
    with tempfile.TemporaryDirectory(prefix="ejsgen-grade-") as tmp:
        reference = run_sweep(Path(args.reference), Path(tmp) / "reference", args)
        if reference.failed:
            print(f"error: the reference fails: {reference.failed[0].error}", file=sys.stderr)
            return 2
        students = sorted(Path(args.students).glob("*.ejs.yaml"))
        for i, spec in enumerate(students):
            try:
                result = run_sweep(spec, Path(tmp) / f"student{i}", args)
            except EjsError as exc:
                grade = Grade(spec.name, False, detail=f"does not build: {str(exc).splitlines()[0]}")
            except ValueError as exc:  # a compared variable or a parameter it does not declare
                grade = Grade(spec.name, False, detail=f"does not fit the exercise: {exc}")
            else:
                grade = compare(reference, result, names, args.rtol, args.atol)
                grade.name = spec.name
            grades.append(grade)
            verdict = "PASS" if grade.passed else "FAIL"
            what = f"{', '.join(grade.differ)} differ{'s' if len(grade.differ) == 1 else ''}; " if grade.differ else ""
            print(f"{spec.name}: {verdict}" + (f": {what}{grade.detail}" if not grade.passed else f" ({len(result.results)} runs)"))
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
