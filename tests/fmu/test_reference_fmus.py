"""Every Reference FMU of the Modelica Association (FMI 2 and 3), in co-simulation and model
exchange, inside a lab, against ``fmpy.simulate_fmu`` on the same file.

The Reference FMUs are the FMI standard's own test models (time events: Stair; state
events: BouncingBall; every variable type, tunable parameters and discrete inputs:
Feedthrough; arrays: StateSpace; stiffness: Roberts). They are read from
``<project root>/../shared/fmus/reference/{fmi2,fmi3}``; a missing folder fails the tests
with the commands that build them.

Each lab is a spec with the FMU and a code page ``n = n + 1; t = n * dt`` (the times FMPy's
master uses); its CSV is compared, per variable, with FMPy's result on the same grid:
co-simulation exactly (the same doStep calls), model exchange against FMPy's CVode at
relative tolerance 1e-10 with the lab's dopri5 at 1e-10. Runs change a tunable parameter and
discrete inputs of every type mid-run; FMPy gets the same changes through ``input``.
"""

from __future__ import annotations

import io
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from testkit import ROOT, run_app

REFERENCE = ROOT.parent / "shared" / "fmus" / "reference"

BUILD = """\
the Reference FMUs are missing from {folder}; build them from github.com/modelica/Reference-FMUs:
    cmake -B build2 -DFMI_VERSION=2 . && cmake --build build2 --target BouncingBall Dahlquist Feedthrough Resource Stair VanDerPol
    cmake -B build3 -DFMI_VERSION=3 . && cmake --build build3 --target BouncingBall Dahlquist Feedthrough Resource Stair VanDerPol Clocks StateSpace Roberts
and copy the .fmu files into {folder}/fmi2 and {folder}/fmi3"""


def reference(version: int, name: str) -> Path:
    """The Reference FMU ``name`` of FMI ``version``; fails with the build commands if missing."""
    path = REFERENCE / f"fmi{version}" / f"{name}.fmu"
    if not path.is_file():
        pytest.fail(BUILD.format(folder=REFERENCE))
    return path


# -- the labs ------------------------------------------------------------------------------------

#: per FMU: stop time, step, outputs, inputs and parameters ({FMU variable: (spec expression, FMPy signal)})
#: a signal is [(time, value), ...]: FMPy interpolates linearly, a repeated time is a step
Signal = list[tuple[float, Any]]


def _step_at(t1: float, before: Any, after: Any, stop: float) -> tuple[str, Signal]:
    expr = f"{after!r} if t >= {t1} - 1e-9 else {before!r}"
    return expr, [(0.0, before), (t1, before), (t1, after), (stop, after)]


CASES: dict[str, dict[str, Any]] = {
    "BouncingBall": {"stop": 3.0, "dt": 0.01, "outputs": ["h", "v"]},
    "Dahlquist": {"stop": 10.0, "dt": 0.1, "outputs": ["x"]},
    "VanDerPol": {"stop": 20.0, "dt": 0.01, "outputs": ["x0", "x1"]},
    "Stair": {"stop": 10.0, "dt": 0.3, "outputs": ["counter"]},
    "Resource": {"stop": 1.0, "dt": 0.1, "outputs": ["y"]},
    "Feedthrough": {"stop": 2.0, "dt": 0.1},
    "Roberts": {"stop": 4.0, "dt": 0.04, "outputs": ["y1", "y2", "y3"], "method": "radau"},
}

FMI2 = ["BouncingBall", "Dahlquist", "VanDerPol", "Stair", "Resource", "Feedthrough"]
FMI3 = ["BouncingBall", "Dahlquist", "VanDerPol", "Stair", "Resource", "Feedthrough", "Roberts"]


def feedthrough(version: int, stop: float) -> tuple[list[str], dict[str, tuple[str, Signal]]]:
    """Feedthrough's outputs and inputs: a ramp on the continuous inputs, a step at t = 1 on
    every discrete input (each type) and on the tunable parameter."""
    ramp = ("2.0 * t - 1.0", [(0.0, -1.0), (stop, 2.0 * stop - 1.0)])
    inputs: dict[str, tuple[str, Signal]] = {"Float64_continuous_input": ramp, "Float64_discrete_input": _step_at(1.0, 0.5, -2.25, stop)}
    steps = {"Boolean": (False, True), "Enumeration": (1, 2)}
    if version == 2:
        steps["Int32"] = (3, -7)
    else:
        inputs["Float32_continuous_input"] = ramp
        inputs["Float32_discrete_input"] = _step_at(1.0, 0.25, 4.5, stop)
        steps.update({"Int8": (-3, 100), "UInt8": (7, 200), "Int16": (-300, 3000), "UInt16": (7, 60000), "Int32": (3, -7), "UInt32": (5, 4000000000), "Int64": (-5, 2**40), "UInt64": (5, 2**50)})
    for typ, (a, b) in steps.items():
        inputs[f"{typ}_input"] = _step_at(1.0, a, b, stop)
    outputs = [name.replace("_input", "_output") for name in inputs]
    return outputs, inputs


def spec_text(fmu: Path, kind: str, case: dict[str, Any], outputs: list[str], inputs: dict[str, tuple[str, Signal]], parameters: dict[str, tuple[str, Signal]]) -> str:
    """A lab holding the FMU alone; model variable ``o_<name>`` receives output ``name``."""
    lines = ["ejs: 1", f"title: {fmu.stem} ({kind})", "model:", "  variables:", "    t: 0.0", f"    dt: {case['dt']}", "    n: 0"]
    lines += [f"    o_{name}: 0" for name in outputs]
    lines += ["  evolution:", "    - code: |", "        n = n + 1", "        t = n * dt"]
    lines += ["fmus:", "  f:", f"    file: {fmu.name}", f"    kind: {kind}"]
    if kind == "model_exchange":
        lines += [f"    method: {case.get('method', 'dopri5')}", "    tolerance: 1.0e-10"]
    lines += ["    outputs:"] + [f"      {name}: o_{name}" for name in outputs]
    for key, table in (("inputs", inputs), ("parameters", parameters)):
        if table:
            lines += [f"    {key}:"] + [f'      {name}: "{expr}"' for name, (expr, _) in table.items()]
    return "\n".join(lines) + "\n"


def signals(table: dict[str, tuple[str, Signal]]) -> np.ndarray | None:
    """FMPy's ``input``: one structured array of every signal on the union of their times."""
    if not table:
        return None
    rows: list[float] = sorted({t for _, sig in table.values() for t, _ in sig})
    # a step: the time twice, before then after
    times: list[float] = []
    for t in rows:
        times += [t] * max(sum(1 for tt, _ in sig if tt == t) for _, sig in table.values())
    dtype = [("time", np.float64)] + [(name, np.float64) for name in table]
    data = np.zeros(len(times), dtype=dtype)
    data["time"] = times
    for name, (_, sig) in table.items():
        data[name] = _column(sig, times)
    return data


def _column(sig: Signal, times: list[float]) -> list[float]:
    """The signal at ``times`` (a time listed k times takes the signal's k-th value there)."""
    out = []
    seen: dict[float, int] = {}
    for t in times:
        k = seen.get(t, 0)
        seen[t] = k + 1
        at = [v for tt, v in sig if tt == t]
        if at:
            out.append(float(at[min(k, len(at) - 1)]))
        else:  # linear between the signal's own points
            ts = [tt for tt, _ in sig]
            vs = [float(v) for _, v in sig]
            out.append(float(np.interp(t, ts, vs)))
    return out


def build_lab(tmp: Path, version: int, name: str, kind: str, parameters: dict[str, tuple[str, Signal]] | None = None) -> tuple[Path, list[str], dict[str, Any], dict[str, tuple[str, Signal]]]:
    from ejsgen.cli import build

    case = CASES[name]
    fmu = reference(version, name)
    (tmp / fmu.name).write_bytes(fmu.read_bytes())
    if name == "Feedthrough":
        outputs, inputs = feedthrough(version, case["stop"])
        parameters = {"Float64_tunable_parameter": _step_at(1.0, 0.0, 3.5, case["stop"])}
    else:
        outputs, inputs = list(case["outputs"]), {}
    parameters = parameters or {}
    spec = tmp / "lab.ejs.yaml"
    spec.write_text(spec_text(fmu, kind, case, outputs, inputs, parameters))
    return build(spec, tmp / "app"), outputs, case, {**inputs, **parameters}


def run_lab(app: Path, outputs: list[str], stop: float) -> tuple[dict[str, np.ndarray], str]:
    r = run_app(app, "--headless", "--duration", str(stop), "--csv", "-", "--vars", ",".join(["t"] + [f"o_{o}" for o in outputs]))
    assert r.returncode == 0, r.stderr
    data = np.genfromtxt(io.StringIO(r.stdout), delimiter=",", names=True, deletechars="", dtype=None, encoding="utf-8")
    return {n: np.atleast_1d(data[n]) for n in data.dtype.names}, r.stderr


def fmpy_run(fmu: Path, kind: str, case: dict[str, Any], outputs: list[str], table: dict[str, tuple[str, Signal]]) -> np.ndarray:
    from fmpy import simulate_fmu

    common = dict(start_time=0.0, stop_time=case["stop"], output_interval=case["dt"], output=outputs, input=signals(table))
    if kind == "co_simulation":
        return simulate_fmu(str(fmu), fmi_type="CoSimulation", **common)
    return simulate_fmu(str(fmu), fmi_type="ModelExchange", relative_tolerance=1e-10, record_events=False, **common)


def as_float(column: np.ndarray) -> np.ndarray:
    if column.dtype.kind in "US":  # booleans as text
        return np.array([{"True": 1.0, "False": 0.0}.get(str(v), np.nan) for v in column])
    return column.astype(float)


PAIRS = [(2, n, k) for n in FMI2 for k in ("co_simulation", "model_exchange")] + [(3, n, k) for n in FMI3 for k in ("co_simulation", "model_exchange")]


@pytest.mark.parametrize("version, name, kind", PAIRS, ids=[f"fmi{v}-{n}-{'cs' if k == 'co_simulation' else 'me'}" for v, n, k in PAIRS])
def test_the_lab_equals_fmpys_simulation_of_the_same_fmu(tmp_path, version, name, kind):
    app, outputs, case, table = build_lab(tmp_path, version, name, kind)
    ours, _ = run_lab(app, outputs, case["stop"])
    ref = fmpy_run(app / f"{name}.fmu", kind, case, outputs, table)
    n = min(len(ref), len(ours["t"]))
    assert n >= 0.9 * case["stop"] / case["dt"]
    np.testing.assert_allclose(ours["t"][:n], ref["time"][:n], rtol=0, atol=1e-12)
    for o in outputs:
        a, b = as_float(ours[f"o_{o}"][:n]), ref[o][:n].astype(float)
        if kind == "co_simulation":  # the same doStep calls: the same numbers
            tol = 1e-13 * max(1.0, np.abs(b).max()) if not o.startswith("Float32") else 0.0
        else:  # two solvers at 1e-10
            tol = 1e-6 * max(1.0, np.abs(b).max())
        np.testing.assert_allclose(a, b, rtol=0, atol=tol, err_msg=f"{name} {kind} {o}")
        assert np.ptp(b) > 0 or name in ("Resource",), f"{o} never moved: a test that shows nothing"


def bounce_times(t: np.ndarray, h: np.ndarray, v: np.ndarray, g: float = -9.81) -> np.ndarray:
    """The impacts of a ballistic ball sampled on a grid: where v turns from falling to rising,
    solved from the row before (h + v s + g s^2 / 2 = 0: the ball flies freely in between)."""
    out = []
    for k in np.flatnonzero((v[:-1] < 0) & (v[1:] > 0)):
        s = (-v[k] - np.sqrt(v[k] ** 2 - 2 * g * h[k])) / g
        out.append(t[k] + s)
    return np.array(out)


def fmpy_in_two_runs(fmu: Path, t1: float, stop: float, before: dict[str, float], after: dict[str, float], events: bool) -> np.ndarray:
    """FMPy's model exchange with parameters changed at ``t1``: a run to t1, then a second one
    from there, started from the first one's states (``start_values``) and the new parameters.
    (FMPy's CVode sets an ``input`` that is a tunable parameter in continuous-time mode, which
    the Reference FMUs refuse; two runs are the same experiment.)"""
    from fmpy import simulate_fmu

    common = dict(fmi_type="ModelExchange", output_interval=0.01, relative_tolerance=1e-10, output=["h", "v"], record_events=events)
    a = simulate_fmu(str(fmu), start_time=0.0, stop_time=t1, start_values=before, **common)
    b = simulate_fmu(str(fmu), start_time=t1, stop_time=stop, start_values={"h": a["h"][-1], "v": a["v"][-1], **after}, **common)
    return np.concatenate([a[:-1], b])


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", ["co_simulation", "model_exchange"])
def test_the_bouncing_ball_with_its_restitution_changed_mid_run_bounces_when_fmpys_does(tmp_path, version, kind):
    """A tunable parameter changed at t = 1 (a slider would): model exchange sets it in event
    mode; every impact is located inside its step, to 1e-6 s of FMPy's CVode root."""
    e = _step_at(1.0, 0.7, 0.5, 3.0)
    app, outputs, case, table = build_lab(tmp_path, version, "BouncingBall", kind, parameters={"e": e})
    ours, _ = run_lab(app, outputs, case["stop"])
    fmu = app / "BouncingBall.fmu"
    if kind == "co_simulation":
        ref = fmpy_run(fmu, kind, case, outputs, table)
    else:
        ref = fmpy_in_two_runs(fmu, 1.0, 3.0, {"e": 0.7}, {"e": 0.5}, events=False)
    assert len(ref) == len(ours["t"]) == 301
    tol = 1e-13 if kind == "co_simulation" else 1e-6
    for o in outputs:
        np.testing.assert_allclose(ours[f"o_{o}"], ref[o], rtol=0, atol=tol, err_msg=o)
    mine = bounce_times(ours["t"], ours["o_h"], ours["o_v"])
    if kind == "model_exchange":
        events = fmpy_in_two_runs(fmu, 1.0, 3.0, {"e": 0.7}, {"e": 0.5}, events=True)
        t_ref, v_ref = events["time"], events["v"]
        same = np.flatnonzero(np.diff(t_ref) == 0)
        impacts = t_ref[same[(v_ref[same] < 0) & (v_ref[same + 1] > 0)]]
        assert len(impacts) == len(mine) >= 5
        np.testing.assert_allclose(mine, impacts, rtol=0, atol=1e-6)
    # the restitution changed at t = 1: the rebound speed over the impact speed is 0.7, then 0.5
    ratios = [ours["o_v"][k + 1] / -ours["o_v"][k] for k in np.flatnonzero((ours["o_v"][:-1] < 0) & (ours["o_v"][1:] > 0))]
    assert len(ratios) >= 4 and np.ptp(ratios) > 0.1


@pytest.mark.parametrize("version", [2, 3])
def test_the_stairs_time_events_land_exactly_on_the_announced_times(tmp_path, version):
    """Stair's counter feeds an ODE state: x' = counter integrates to the staircase's area only
    if every step ends at the announced event time (dt = 0.3 puts them mid-step)."""
    from ejsgen.cli import build

    fmu = reference(version, "Stair")
    (tmp_path / fmu.name).write_bytes(fmu.read_bytes())
    spec = tmp_path / "stair.ejs.yaml"
    spec.write_text(textwrap.dedent("""\
        ejs: 1
        title: Area under the Stair
        model:
          variables:
            t: 0.0
            dt: 0.3
            x: 0.0
            counter: 1
          evolution:
            - ode:
                equations:
                  x: counter
        fmus:
          stair:
            file: Stair.fmu
            kind: model_exchange
            outputs: {counter: counter}
        """))
    app = build(spec, tmp_path / "app")
    r = run_app(app, "--headless", "--duration", "10", "--csv", "-", "--vars", "t,x,counter")
    assert r.returncode == 0, r.stderr
    d = np.genfromtxt(io.StringIO(r.stdout), delimiter=",", names=True)
    area = np.array([sum(min(max(t - k, 0.0), 1.0) * (k + 1) for k in range(10)) for t in d["t"]])  # counter = k + 1 on [k, k + 1)
    np.testing.assert_allclose(d["x"], area, rtol=0, atol=1e-9)
    assert d["counter"][-1] >= 9
    assert "alert: FMU 'stair' ended the simulation at t = 9" in r.stderr  # Stair stops itself: information, not an error
