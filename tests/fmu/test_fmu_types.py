"""Every FMI variable type and shape in a lab, and the capability flags.

FMI 3 arrays (the Reference FMU StateSpace: y = C x + D u, x' = A x + B u, with A, u and y
arrays) run in co-simulation and model exchange and equal ``fmpy.simulate_fmu``; their
shapes are checked against the spec's variables at build time (FILE:LINE:COL) and at run
time (a value of the wrong shape names the FMU, the variable and the spec line). Binary and
String inputs pass through Feedthrough as bytes and text. Clocks, a step that may vary for
an FMU that cannot take one, and an FMU allowed once per process get a clear message.
"""

from __future__ import annotations

import io
import shutil
import textwrap
from pathlib import Path

import numpy as np
import pytest
from ejsgen.cli import main
from testkit import run_app
from testkit.fmu import cs_spec, fmu_folder, write_spec

from test_reference_fmus import reference

A = [[-1.0, 0.5, 0.0], [0.0, -2.0, 0.0], [0.3, 0.0, -3.0]]
U = [1.0, -2.0, 0.5]

STATE_SPACE = """\
ejs: 1
title: StateSpace ({kind})
model:
  variables:
    t: 0.0
    dt: 0.1
    n: 0
    A_m: {A}
    u0: {U}
    y: [0.0, 0.0, 0.0]
  evolution:
    - code: |
        n = n + 1
        t = n * dt
fmus:
  ss:
    file: StateSpace.fmu
    kind: {kind}
    {solver}
    parameters: {{A: A_m}}
    inputs: {{u: {u}}}
    outputs: {{y: {y}}}
"""


def state_space(tmp: Path, kind: str, u: str = "u0", y: str = "y", extra: str = "") -> Path:
    shutil.copy2(reference(3, "StateSpace"), tmp / "StateSpace.fmu")
    solver = "tolerance: 1.0e-10" if kind == "model_exchange" else ""
    text = STATE_SPACE.format(kind=kind, A=A, U=U, u=u, y=y, solver=solver)
    spec = tmp / "ss.ejs.yaml"
    spec.write_text(text.replace("    y: [0.0, 0.0, 0.0]\n", "    y: [0.0, 0.0, 0.0]\n" + extra))
    return spec


def build_error(spec: Path, capsys: pytest.CaptureFixture[str]) -> str:
    status = main(["build", str(spec), "-o", str(spec.parent / "out")])
    err = capsys.readouterr().err
    assert status == 1, err
    assert "Traceback" not in err
    return err.splitlines()[0]


def place(spec: Path, needle: str, at: str | None = None) -> str:
    for k, line in enumerate(spec.read_text().splitlines(), 1):
        if needle in line:
            return f"{spec}:{k}:{line.index(at or needle) + 1}"
    raise AssertionError(needle)


@pytest.mark.parametrize("kind", ["co_simulation", "model_exchange"])
def test_fmi3_arrays_run_in_a_lab_as_in_fmpy(tmp_path, kind):
    from ejsgen.cli import build
    from fmpy import simulate_fmu

    app = build(state_space(tmp_path, kind), tmp_path / "app")
    r = run_app(app, "--headless", "--duration", "1", "--csv", "-", "--vars", "t,y")
    assert r.returncode == 0, r.stderr
    d = np.genfromtxt(io.StringIO(r.stdout), delimiter=",", names=True, deletechars="")
    ours = np.column_stack([d["y[0]"], d["y[1]"], d["y[2]"]])
    fmi_type = "CoSimulation" if kind == "co_simulation" else "ModelExchange"
    ref = simulate_fmu(str(app / "StateSpace.fmu"), fmi_type=fmi_type, start_time=0.0, stop_time=1.0, output_interval=0.1, output=["y"], start_values={"A": np.ravel(A).tolist(), "u": U}, relative_tolerance=1e-10)
    assert ours.shape == ref["y"].shape == (11, 3)
    np.testing.assert_allclose(ours, ref["y"], rtol=0, atol=1e-13 if kind == "co_simulation" else 1e-7)
    assert np.ptp(ours[:, 0]) > 0.1  # A coupled the states: the output moved


def test_an_array_output_into_a_variable_of_another_shape_is_a_build_error(tmp_path, capsys):
    spec = state_space(tmp_path, "co_simulation", y="y2", extra="    y2: [0.0, 0.0]\n")
    err = build_error(spec, capsys)
    assert err == f"{place(spec, 'outputs: {y: y2}', 'y2')}: error: 'y' of the FMU 'StateSpace.fmu' is an array of shape (3,), and 'y2' is an array of shape (2,); declare it so, e.g. 'y2: [0.0, 0.0, 0.0]'"


def test_an_array_input_of_another_shape_is_a_build_error(tmp_path, capsys):
    spec = state_space(tmp_path, "co_simulation", u="u2", extra="    u2: [1.0, 2.0]\n")
    err = build_error(spec, capsys)
    assert err == f"{place(spec, 'inputs: {u: u2}', 'u2')}: error: 'u' of the FMU 'StateSpace.fmu' is an array of shape (3,), and its value here is an array of shape (2,)"


def test_an_array_of_the_wrong_shape_at_run_time_names_the_fmu_the_variable_and_the_spec_line(tmp_path):
    from ejsgen.cli import build

    spec = state_space(tmp_path, "model_exchange", u='"np.ones(2)"')
    app = build(spec, tmp_path / "app")
    r = run_app(app, "--headless", "--duration", "0.3")
    assert r.returncode == 1
    assert f"ss.ejs.yaml:{place(spec, 'ss:').split(':')[1]}:3: error: FMU 'ss': setting inputs: 'u' is an array of shape (3,), not of shape (2,)" in r.stderr
    assert "TypeError" not in r.stderr


FEEDTHROUGH = """\
ejs: 1
title: Binary and String ({kind})
model:
  variables:
    t: 0.0
    dt: 0.1
    n: 0
    b_out: ""
    s_out: ""
  evolution:
    - code: |
        n = n + 1
        t = n * dt
fmus:
  ft:
    file: Feedthrough.fmu
    kind: {kind}
    inputs:
      Binary_input: "b'\\\\x00\\\\xffab' if t < 0.5 else b'xyz'"
      String_input: "'hello' if t < 0.5 else 'wörld'"
    outputs: {{Binary_output: b_out, String_output: s_out}}
"""


@pytest.mark.parametrize("kind", ["co_simulation", "model_exchange"])
def test_binary_and_string_values_pass_as_bytes_and_text(tmp_path, kind):
    from ejsgen.cli import build
    from ejsrl.app import load_app

    shutil.copy2(reference(3, "Feedthrough"), tmp_path / "Feedthrough.fmu")
    spec = tmp_path / "ft.ejs.yaml"
    spec.write_text(FEEDTHROUGH.format(kind=kind))
    app = load_app(build(spec, tmp_path / "app"))
    try:
        seen = []
        for _ in range(8):
            app.step_once()
            seen.append((round(float(app.model.t), 9), app.model.b_out, app.model.s_out))
        assert app.error is None, app.error
    finally:
        app.stop()
    assert seen[0][1:] == (b"\x00\xffab", "hello")  # bytes with a zero byte and a non-ASCII one
    assert seen[-1][1:] == (b"xyz", "wörld")
    assert {type(b) for _, b, _ in seen} == {bytes}


def test_an_fmu_with_only_scheduled_execution_is_refused_with_the_right_hint(tmp_path, capsys):
    shutil.copy2(reference(3, "Clocks"), tmp_path / "Clocks.fmu")
    spec = tmp_path / "clocks.ejs.yaml"
    spec.write_text(textwrap.dedent("""\
        ejs: 1
        title: Clocks
        model:
          variables: {t: 0.0, dt: 0.1, ticks: 0}
          evolution:
            - code: t = t + dt
        fmus:
          clocks:
            file: Clocks.fmu
            outputs: {totalInClockTicks: ticks}
        """))
    err = build_error(spec, capsys)
    assert err == (
        f"{place(spec, 'file: Clocks.fmu', 'Clocks.fmu')}: error: the FMU 'Clocks.fmu' has neither a co-simulation nor a model-exchange interface; "
        "FMI 3 scheduled execution, the only one it offers, is not supported; export the model as a co-simulation or model-exchange FMU"
    )


def test_a_clock_or_a_clocked_variable_is_refused_naming_the_fmu_and_the_variable(tmp_path, capsys):
    """The Clocks FMU given a co-simulation interface (as a tool exporting both would): its
    clocks and the variables they drive are refused, each at its line."""
    import zipfile

    folder = tmp_path / "Clocks"
    with zipfile.ZipFile(reference(3, "Clocks")) as zf:
        zf.extractall(folder)
    md = folder / "modelDescription.xml"
    md.write_text(md.read_text().replace('<ScheduledExecution modelIdentifier="Clocks"/>', '<CoSimulation modelIdentifier="Clocks" canHandleVariableCommunicationStepSize="true"/>'))
    spec = tmp_path / "clocks.ejs.yaml"
    spec.write_text(textwrap.dedent("""\
        ejs: 1
        title: Clocks
        model:
          variables: {t: 0.0, dt: 0.1, ticks: 0, on: false}
          evolution:
            - code: t = t + dt
        fmus:
          clocks:
            file: Clocks
            inputs: {inClock1: on}
            outputs: {totalInClockTicks: ticks}
        """))
    status = main(["build", str(spec), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err.splitlines()
    assert status == 1
    assert err[0] == (
        f"{place(spec, 'inClock1: on', 'inClock1')}: error: 'inClock1' of the FMU 'Clocks' is an FMI 3 clock: FMI 3 clocks are not supported "
        "(they need scheduled execution or co-simulation event mode); use the FMU's variables that no clock drives"
    )
    assert err[1].startswith(f"{place(spec, 'totalInClockTicks', 'totalInClockTicks')}: error: 'totalInClockTicks' of the FMU 'Clocks' is clocked (it changes only when a clock ticks)")


def _flag(folder: Path, attribute: str) -> None:
    md = folder / "modelDescription.xml"
    text = md.read_text()
    text = text.replace('canHandleVariableCommunicationStepSize="true"', "")
    md.write_text(text.replace('<CoSimulation modelIdentifier="joint_drives"', f'<CoSimulation modelIdentifier="joint_drives" {attribute}'))


def test_an_fmu_that_cannot_vary_its_step_refuses_a_step_that_may_vary(tmp_path, capsys):
    _flag(fmu_folder(tmp_path), 'canHandleVariableCommunicationStepSize="false"')
    spec = write_spec(tmp_path, cs_spec("2 * dt"))
    err = build_error(spec, capsys)
    assert err == (
        f"{place(spec, 'step: 2 * dt', '2 * dt')}: error: the FMU 'drives' cannot take a communication step that changes "
        "(canHandleVariableCommunicationStepSize is false), and 'step' is an expression; give 'step' a number"
    )


def test_an_fmu_that_cannot_vary_its_step_stops_when_the_models_step_changes(tmp_path):
    from ejsgen.cli import build
    from ejsrl.app import load_app

    _flag(fmu_folder(tmp_path), 'canHandleVariableCommunicationStepSize="false"')
    app = load_app(build(write_spec(tmp_path, cs_spec()), tmp_path / "app"))
    try:
        for _ in range(5):
            app.step_once()
        assert app.error is None
        app.model.dt = 0.02  # as a slider on the step would
        app.play()
        app._run_steps(1)
        assert app.error is not None
        assert app.error.message == "FMU 'drives' cannot take a communication step that changes (canHandleVariableCommunicationStepSize is false): it stepped by 0.01, now by 0.02 at t = 0.05"
        assert app.error.where == "lab.ejs.yaml:15:3"
    finally:
        app.stop()


def test_an_fmu_allowed_once_per_process_says_so_in_a_second_tab(tmp_path):
    from ejsgen.cli import build
    from ejsrl.app import load_app

    _flag(fmu_folder(tmp_path), 'canHandleVariableCommunicationStepSize="true" canBeInstantiatedOnlyOncePerProcess="true"')
    folder = build(write_spec(tmp_path, cs_spec()), tmp_path / "app")
    first = load_app(folder)
    try:
        second = load_app(folder)
        try:
            assert second.error is not None
            assert "FMU 'drives' can be instantiated only once per process (canBeInstantiatedOnlyOncePerProcess), and it already runs" in second.error.message
        finally:
            second.stop()
        first.step_once()
        assert first.error is None
    finally:
        first.stop()
    third = load_app(folder)  # freed with the first: it can run again
    try:
        third.step_once()
        assert third.error is None
    finally:
        third.stop()
