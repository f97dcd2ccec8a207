"""Sweep throughput: runs per second of ``ejsgen sweep`` against a shell loop of ``app.py --headless``.

Prints, in one run, for 1,000 short pendulum runs (0.5 s of simulated time, 50 RK4 steps)
and 200 six-axis inverse-kinematics runs (the paper's lab 1: IK to a target in ``init``,
then 0.1 s of the joint motion):

- runs/s of the local process pool (as many workers as cores; pool start-up included);
- runs/s of a shell loop ``for ...; do python app.py --headless --set ...; done`` (on a
  subset of the runs: it is slow), and the pool's speed-up over it (goal: >= 20x for short runs);
- runs/s on a Dask LocalCluster of as many workers as cores (its start-up reported apart);
- the pool's scaling from 1 to 2 workers (goal: >= 1.8x on two idle cores).

The load average is printed first: on a busy machine the scaling cannot reach its goal
(two workers share cores with everything else); rerun on a quiet machine.

Run: python bench/sweeps.py [--quick] [--no-dask]
"""

from __future__ import annotations

import argparse
import os
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import EXAMPLES  # noqa: E402


def build(spec: Path, root: Path) -> Path:
    from ejsgen.cli import build as build_app

    return build_app(spec, root / spec.name.split(".")[0])


def pendulum_design(n: int) -> dict:
    """``n`` runs (a multiple of 25): L on a grid times 25 dampings."""
    b = ",".join(f"{0.02 * i:g}" for i in range(25))
    return {"grid": [f"L=0.5:2.5:{n // 25}"], "values": [f"b={b}"], "duration": 0.5, "variables": ["theta", "omega", "E"]}


def ik_design(n: int) -> dict:
    """``n`` runs (a multiple of 10): targets on an X-Y grid in reach of the arm, Z = 0.3."""
    return {"grid": [f"X=0.2:0.45:{n // 10}", "Y=-0.3:0.3:10"], "duration": 0.1, "variables": ["q", "solved"]}


def sweep_rate(app: Path, design: dict, **where) -> tuple[float, int, int]:
    """(runs/s, runs, failed) of one sweep through the Python API (what ejsgen sweep runs)."""
    from ejsrl.app.sweep import sweep

    start = time.perf_counter()
    result = sweep(app, **design, **where)
    took = time.perf_counter() - start
    return len(result.results) / took, len(result.results), len(result.failed)


def shell_rate(app: Path, design: dict, runs: int) -> float:
    """runs/s of a bash loop of headless runs over the first ``runs`` of the design's runs."""
    from ejsrl.app.sweep_design import design as make_design
    from ejsrl.app.sweep_worker import app_ref, loaded

    types = loaded(app_ref(app)).model_cls.VARIABLES
    points = make_design(types, grid=design.get("grid", ()), values=design.get("values", ()))[:runs]
    tmp = Path(tempfile.mkdtemp(prefix="ejsgen-bench-loop-"))
    lines = []
    for run in points:
        sets = " ".join(f"--set {shlex.quote(s)}" for s in run.set_args())
        lines.append(
            f"{shlex.quote(sys.executable)} {shlex.quote(str(app / 'app.py'))} --headless --duration {design['duration']} "
            f"--vars {','.join(design['variables'])} --csv {tmp}/run{run.run}.csv {sets}"
        )
    script = "set -e\n" + "\n".join(lines) + "\n"
    start = time.perf_counter()
    subprocess.run(["bash", "-c", script], check=True, capture_output=True)
    return len(points) / (time.perf_counter() - start)


def dask_rate(app: Path, design: dict, workers: int) -> tuple[float, float]:
    """(runs/s on a running LocalCluster, its start-up in s)."""
    from distributed import LocalCluster

    start = time.perf_counter()
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        up = time.perf_counter() - start
        rate, _, _ = sweep_rate(app, design, scheduler=cluster.scheduler_address)
    return rate, up


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="200 pendulum and 40 IK runs, 5-run shell loops (a minute or two)")
    p.add_argument("--no-dask", action="store_true", help="skip the Dask LocalCluster")
    args = p.parse_args(argv)
    from ejsrl.app.sweep_exec import cpu_count

    cores = cpu_count()
    n_pend, n_ik, n_shell = (200, 40, 5) if args.quick else (1000, 200, 20)
    load = os.getloadavg()
    print(f"machine: {cores} cores, load average {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}"
          + ("  (BUSY: the numbers below are low, the scaling especially; rerun on a quiet machine)" if load[0] > 0.5 * cores else ""))
    root = Path(tempfile.mkdtemp(prefix="ejsgen-bench-sweeps-"))
    cases = [
        ("pendulum", build(EXAMPLES / "pendulum.ejs.yaml", root), pendulum_design(n_pend)),
        ("six-axis IK", build(EXAMPLES / "paper" / "six_axis_kinematics.ejs.yaml", root), ik_design(n_ik)),
    ]
    rows = []
    for name, app, design in cases:
        pool, n, failed = sweep_rate(app, design, workers=cores)
        shell = shell_rate(app, design, n_shell)
        line = {"case": name, "runs": n, "failed": failed, "pool": pool, "shell": shell}
        if not args.no_dask:
            line["dask"], line["dask_up"] = dask_rate(app, design, cores)
        rows.append(line)
        print(f"{name}: {n} runs ({failed} failed): pool of {cores} {pool:.1f} runs/s; shell loop {shell:.2f} runs/s "
              f"(over {n_shell} runs); speed-up {pool / shell:.1f}x"
              + (f"; Dask LocalCluster {line['dask']:.1f} runs/s (start-up {line['dask_up']:.1f} s)" if "dask" in line else ""),
              flush=True)
    pend_app, pend_design = cases[0][1], cases[0][2]
    one, _, _ = sweep_rate(pend_app, pend_design, workers=1)
    two, _, _ = sweep_rate(pend_app, pend_design, workers=2)
    print()
    print("| case | runs | local pool (runs/s) | shell loop (runs/s) | speed-up (goal >= 20x short runs) | Dask LocalCluster (runs/s) |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        dask = f"{r['dask']:.1f} (+{r['dask_up']:.0f} s start-up)" if "dask" in r else "skipped"
        print(f"| {r['case']} | {r['runs']} | {r['pool']:.1f} | {r['shell']:.2f} | {r['pool'] / r['shell']:.1f}x | {dask} |")
    print(f"\npendulum, 1 -> 2 workers: {one:.1f} -> {two:.1f} runs/s = {two / one:.2f}x (goal >= 1.8x on two idle cores)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
