"""`ejsgen sweep`: each run equals the headless run with the same --set settings, row for row and bit
for bit; the results and summary tables; metrics; failed runs; Parquet and CSV; the built app's --sweep."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from testkit import EXAMPLES
from testkit.sweeps import SPECS, ejsgen, headless_csv, read, rows_of


@pytest.fixture(scope="module")
def springs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from ejsgen.cli import build

    return build(SPECS / "springs.ejs.yaml", tmp_path_factory.mktemp("apps") / "springs")


def test_every_run_of_a_grid_equals_the_headless_run_with_the_same_settings(tmp_path: Path) -> None:
    out = tmp_path / "runs.parquet"
    proc = ejsgen("sweep", str(EXAMPLES / "pendulum.ejs.yaml"), "-o", str(tmp_path / "app"), "--grid", "L=0.5:2:4",
                  "--values", "b=0,0.25", "--duration", "1.5", "--out", str(out), "--workers", "2")
    assert proc.returncode == 0, proc.stderr
    assert "8 runs (8 ok, 0 failed)" in proc.stderr
    table = read(out)
    summary = read(tmp_path / "runs.summary.parquet")
    # the runs are the product of the values and the grid, numbered in order
    assert summary["run"] == list(range(8))
    assert summary["b"] == [0.0] * 4 + [0.25] * 4
    assert summary["L"] == [0.5, 1.0, 1.5, 2.0] * 2
    assert list(table)[:4] == ["run", "b", "L", "t"]  # run id, parameters, time, variables
    for run, settings in ((1, ("b=0", "L=1.0")), (6, ("b=0.25", "L=1.5"))):
        ref = headless_csv(tmp_path / "app", 1.5, *settings)
        got = rows_of(table, run)
        assert len(got["t"]) == len(ref["t"]) == 151
        for name in ("t", "theta", "omega", "x", "y", "E"):
            assert got[name] == [float(v) for v in ref[name]], name  # bit for bit: repr round-trips
        # the parameter's column holds the value the run was started with
        assert set(got["L"]) == {float(settings[1].split("=")[1])}
    # the summary's final/min/max are those of the run's rows
    for run in range(8):
        rows = rows_of(table, run)
        assert summary["theta.final"][run] == rows["theta"][-1]
        assert summary["theta.min"][run] == min(rows["theta"])
        assert summary["E.max"][run] == max(rows["E"])
    assert summary["status"] == ["ok"] * 8 and summary["error"] == [""] * 8


def test_arrays_expr_variables_and_integers_are_set_as_a_headless_run_sets_them(springs: Path, tmp_path: Path) -> None:
    from ejsrl.app.sweep import sweep

    result = sweep(springs, duration=0.5, values=["N=2,4", "x0=[0.5, 0.5, 0.5],[1,2,3]"], workers=0)
    assert [r.status for r in result.results] == ["ok"] * 4, [r.error for r in result.results]
    table = result.results_table().to_pydict()
    assert "x[3]" in table  # N=4 sizes x (an expr: variable declared from N) to four springs
    # run 3 is N=4 with x0=[1,2,3]: np.resize repeats x0 to [1, 2, 3, 1]
    ref = headless_csv(springs, 0.5, "N=4", "x0=[1,2,3]")
    got = rows_of(table, 3)
    for name in ("x[0]", "x[3]", "v[2]", "E"):
        assert got[name] == [float(v) for v in ref[name]], name
    assert got["x[3]"][0] == 1.0
    # runs with N=2 have no x[2], x[3]: those cells are missing, not zero
    assert rows_of(table, 0)["x[3]"][0] is None
    # an integer variable's grid values stay integers; a value that is not whole is refused
    assert sweep(springs, duration=0.02, grid=["N=1:3:3"], workers=0).summary().to_pydict()["N"] == [1, 2, 3]
    from ejsrl.app.sweep_design import SweepDesignError

    with pytest.raises(SweepDesignError, match="'N' is an integer variable; 1.5 is not a whole number"):
        sweep(springs, duration=0.02, grid=["N=1:2:3"], workers=0)


def test_the_spec_metrics_are_columns_of_the_summary(springs: Path) -> None:
    from ejsrl.app.sweep import sweep

    result = sweep(springs, duration=2.0, values=["c=0,0.5,2"], workers=0)
    summary = result.summary().to_pydict()
    assert list(summary)[:5] == ["run", "c", "status", "error", "seconds"]
    energy = summary["energy_left"]
    # undamped, the energy stays (RK4 at dt = 0.01 keeps it to 1e-6); damped, it decays
    assert energy[0] == pytest.approx(1.0, abs=1e-6)
    assert energy[0] > energy[1] > energy[2]
    # an undamped unit-mass spring of stiffness 4 from x = 1 at rest peaks at the speed 2 (omega * amplitude)
    assert summary["peak_speed"][0] == pytest.approx(2.0, rel=1e-4)
    assert summary["still"] == [False, False, False]
    assert all(isinstance(v, float) for v in energy)


def test_a_failed_run_is_recorded_with_its_error_and_the_sweep_goes_on(springs: Path, tmp_path: Path) -> None:
    out = tmp_path / "runs.csv"
    proc = ejsgen("sweep", str(SPECS / "springs.ejs.yaml"), "--values", "m=1,0,2", "--duration", "0.2", "--out", str(out), "--workers", "2")
    assert proc.returncode == 0, proc.stderr
    assert "3 runs (2 ok, 1 failed)" in proc.stderr
    summary = read(tmp_path / "runs.summary.csv")
    assert summary["status"] == ["ok", "error", "ok"]
    assert summary["m"] == ["1.0", "0.0", "2.0"]
    # m = 0 divides by zero: the run stops on a non-finite state, reported at the spec's equations
    assert "springs.ejs.yaml:" in summary["error"][1] and "non-finite" in summary["error"][1], summary["error"][1]
    assert "run 1 (m=0)" in proc.stderr
    assert summary["energy_left"][1] == ""  # no metrics for a failed run
    runs = read(out)["run"]
    assert runs.count("0") == runs.count("2") == 21


def test_csv_on_request_holds_the_same_values_as_parquet(tmp_path: Path) -> None:
    spec = str(EXAMPLES / "pendulum.ejs.yaml")
    args = ["--values", "L=0.7,1.3", "--duration", "0.3", "--vars", "theta,E", "--every", "3", "--workers", "0"]
    assert ejsgen("sweep", spec, *args, "--out", str(tmp_path / "r.parquet")).returncode == 0
    assert ejsgen("sweep", spec, *args, "--out", str(tmp_path / "r.csv"), "--summary", str(tmp_path / "s.csv")).returncode == 0
    pq, csv_ = read(tmp_path / "r.parquet"), read(tmp_path / "r.csv")
    assert list(pq) == list(csv_) == ["run", "L", "t", "theta", "E"]  # --vars records the time too
    for name in pq:
        assert [float(v) for v in csv_[name]] == [float(v) for v in pq[name]], name
    assert len(pq["t"]) == 2 * 11  # the first row, then every 3rd of 30 steps
    s = read(tmp_path / "s.csv")
    assert s["theta.final"] == [repr(v) for v in read(tmp_path / "r.summary.parquet")["theta.final"]]


def test_the_built_app_sweeps_itself_like_ejsgen_sweep(springs: Path, tmp_path: Path) -> None:
    import subprocess
    import sys

    args = ["--grid", "k=1:9:3", "--duration", "0.3", "--every", "10", "--workers", "2"]
    proc = subprocess.run([sys.executable, str(springs / "app.py"), "--sweep", *args, "--out", str(tmp_path / "app.parquet")],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "Springs for sweeps: 3 runs (3 ok, 0 failed)" in proc.stderr
    assert ejsgen("sweep", str(SPECS / "springs.ejs.yaml"), *args, "--out", str(tmp_path / "ejsgen.parquet")).returncode == 0
    assert read(tmp_path / "app.parquet") == read(tmp_path / "ejsgen.parquet")
    assert read(tmp_path / "app.parquet")["k"][::4] == [1.0, 5.0, 9.0]
    helptext = subprocess.run([sys.executable, str(springs / "app.py"), "--help"], capture_output=True, text=True, timeout=120).stdout
    assert "--sweep" in helptext


def test_wrong_options_are_refused_before_any_run(tmp_path: Path) -> None:
    spec = str(SPECS / "springs.ejs.yaml")
    cases = [
        (["--grid", "kk=1:2:3"], "--grid: unknown variable 'kk'; did you mean 'k'?"),
        (["--grid", "k=1:2"], "expected NAME=start:stop:count"),
        (["--values", "m=1,x"], "parameter m: 'x' is not a number"),
        (["--values", "label=a,b", "--values", "label=c"], "'label' is already a parameter"),
        (["--grid", "label=1:2:2"], "'label' is text; a grid takes a number variable"),
        (["--values", "k=1", "--vars", "E,EE"], "--vars: unknown variable 'EE'; did you mean 'E'?"),
        (["--values", "k=1", "--seed", "3"], "--seed goes with --samples"),
    ]
    for extra, message in cases:
        proc = ejsgen("sweep", spec, *extra, "--duration", "1", "--out", str(tmp_path / "x.parquet"))
        assert proc.returncode == 2 and message in proc.stderr, (extra, proc.stderr)
        assert not (tmp_path / "x.parquet").exists()


def test_an_unknown_name_in_a_metric_is_an_error_at_its_place(tmp_path: Path) -> None:
    text = (SPECS / "springs.ejs.yaml").read_text()
    bad = tmp_path / "bad.ejs.yaml"
    bad.write_text(text.replace("peak_speed: peak", "peak_speed: peek").replace("still: not moving", "E: not moving"))
    proc = ejsgen("validate", str(bad))
    assert proc.returncode == 1
    line = next(i for i, l in enumerate(bad.read_text().splitlines(), 1) if "peak_speed" in l)
    assert f"bad.ejs.yaml:{line}:15: error: unknown name 'peek'; did you mean 'peak'?" in proc.stderr
    assert f"bad.ejs.yaml:{line + 1}:3: error: the metric 'E' has the name of a variable" in proc.stderr
    # ejsgen sweep builds first: the same errors, before any run
    swept = ejsgen("sweep", str(bad), "--values", "k=1,2", "--duration", "1", "--out", str(tmp_path / "x.parquet"))
    assert swept.returncode == 1 and f"bad.ejs.yaml:{line}:15: error: unknown name 'peek'" in swept.stderr
    assert not (tmp_path / "x.parquet").exists()


def test_lhs_samples_fill_every_stratum_once_and_a_seed_repeats_them() -> None:
    from ejsrl.app.sweep_design import design

    types = {"L": "float", "b": "float", "n": "int"}
    runs = design(types, grid=["L=0.5:2.5", "b=0:1"], samples=20, seed=7)
    L = np.array([float(r.params["L"]) for r in runs])
    b = np.array([float(r.params["b"]) for r in runs])
    # Latin hypercube: each of the 20 equal slices of each range holds exactly one point
    assert sorted(np.floor((L - 0.5) / 2.0 * 20).astype(int)) == list(range(20))
    assert sorted(np.floor(b * 20).astype(int)) == list(range(20))
    assert design(types, grid=["L=0.5:2.5", "b=0:1"], samples=20, seed=7) == runs
    assert design(types, grid=["L=0.5:2.5", "b=0:1"], samples=20, seed=8) != runs
    rnd = design(types, grid=["n=0:10"], samples=50, seed=1, sampling="random")
    assert all(r.params["n"].isdigit() and 0 <= int(r.params["n"]) <= 10 for r in rnd)
    assert not math.isclose(len({r.params["n"] for r in rnd}), 1)


def test_a_table_gives_one_run_per_row_crossed_with_values(tmp_path: Path) -> None:
    from ejsrl.app.sweep_design import SweepDesignError, design

    table = tmp_path / "params.csv"
    table.write_text('L,q0\n1.0,"[0, 1]"\n2.5,"[2, 3]"\n')
    runs = design({"L": "float", "q0": "array", "b": "float"}, table=table, values=["b=0,0.5"])
    assert [r.settings for r in runs] == [
        (("L", "1.0"), ("q0", "[0, 1]"), ("b", "0")),
        (("L", "1.0"), ("q0", "[0, 1]"), ("b", "0.5")),
        (("L", "2.5"), ("q0", "[2, 3]"), ("b", "0")),
        (("L", "2.5"), ("q0", "[2, 3]"), ("b", "0.5")),
    ]
    table.write_text("L,b\n1.0\n")
    with pytest.raises(SweepDesignError, match=r"params.csv:2: 1 values for 2 variables"):
        design({"L": "float", "b": "float"}, table=table)


def test_a_metric_that_raises_fails_its_run_with_the_metric_and_its_place(tmp_path: Path) -> None:
    from ejsgen.cli import build
    from ejsrl.app.sweep import sweep

    text = (SPECS / "springs.ejs.yaml").read_text()
    spec = tmp_path / "ratio.ejs.yaml"
    spec.write_text(text.replace("  still: not moving", "  still: not moving\n  ratio: 1 / c"))
    line = spec.read_text().splitlines().index("  ratio: 1 / c") + 1
    result = sweep(build(spec, tmp_path / "app"), values=["c=0.5,0"], duration=0.1, workers=0)
    summary = result.summary().to_pydict()
    assert summary["status"] == ["ok", "error"]
    assert summary["ratio"] == [2.0, None]
    assert summary["error"][1] == f"ratio.ejs.yaml:{line}:10: metric 'ratio': ZeroDivisionError: float division by zero"


def test_a_run_that_pauses_itself_is_stopped_not_failed(tmp_path: Path) -> None:
    from ejsgen.cli import build
    from ejsrl.app.sweep import sweep

    text = (SPECS / "springs.ejs.yaml").read_text()
    spec = tmp_path / "halt.ejs.yaml"
    # an event that stops the simulation when the first spring passes x = 0 (at a quarter period, pi/4 s for k = 4)
    spec.write_text(text.replace("          v: -(k*x + c*v)/m\n", "          v: -(k*x + c*v)/m\n        events:\n          - {when: \"x[0]\", direction: down, stop: true}\n"))
    result = sweep(build(spec, tmp_path / "app"), values=["x0=[1.0, 0.5, 0.25],[-1.0, 0.5, 0.25]"], duration=2.0, workers=0)
    summary = result.summary().to_pydict()
    assert summary["status"] == ["stopped", "ok"]
    assert summary["t.final"][0] == pytest.approx(0.79, abs=0.006)  # the step in which x[0] crossed zero
    assert summary["t.final"][1] == pytest.approx(2.0)


def test_a_single_file_bundle_sweeps_itself(tmp_path: Path) -> None:
    import subprocess
    import sys

    from ejsgen.cli import build

    folder = build(SPECS / "springs.ejs.yaml", tmp_path / "lab", bundle=True)
    args = ["--sweep", "--values", "k=1,4", "--duration", "0.2", "--workers", "2"]
    pyz = subprocess.run([sys.executable, str(folder / "lab.pyz"), *args, "--out", str(tmp_path / "pyz.csv")],
                         capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert pyz.returncode == 0, pyz.stderr
    app = subprocess.run([sys.executable, str(folder / "app.py"), *args, "--out", str(tmp_path / "app.csv")],
                         capture_output=True, text=True, timeout=300)
    assert app.returncode == 0, app.stderr
    assert (tmp_path / "pyz.csv").read_text() == (tmp_path / "app.csv").read_text()
    assert read(tmp_path / "pyz.summary.csv")["status"] == ["ok", "ok"]
