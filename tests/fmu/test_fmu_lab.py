"""Lab 8, the paper's figure 13 with its joint drives in an FMU, run headless.

References: the paper's set points themselves; the same model written as one plain ODE
spec (tests/fmu/specs/motor_control_ode.ejs.yaml: the drives in Python, their states as
ODE states), whose trajectory the FMU lab must follow to 1e-6; FMPy's own validation of
the FMU the build compiled from the lab's C sources.
"""

from __future__ import annotations

import zipfile

import numpy as np
import pytest
from testkit import ROOT, run_app
from testkit.labs import headless, settle_time, vector

SET_POINTS = np.array([np.pi / 2, np.pi / 3, -np.pi / 4])
SPEC = "paper/fmu_motor_control"


@pytest.fixture(scope="module")
def lab(built):
    return built(SPEC)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    from ejsgen.cli import build

    return build(ROOT / "tests" / "fmu" / "specs" / "motor_control_ode.ejs.yaml", tmp_path_factory.mktemp("ref") / "ref")


def test_the_built_lab_ships_an_fmu_compiled_from_the_labs_sources_that_fmpy_validates(lab):
    from fmpy import platform
    from fmpy.validation import validate_fmu

    fmu = lab / "fmu_motor_control" / "joint_drives.fmu"
    assert fmu.is_file()
    with zipfile.ZipFile(fmu) as zf:
        names = set(zf.namelist())
    assert f"binaries/{platform}/joint_drives.so" in names
    assert "sources/joint_drives.c" in names
    assert validate_fmu(str(fmu)) == []


def test_the_arm_reaches_the_papers_set_points_within_6_s_to_a_hundredth_of_a_radian(lab):
    d = headless(lab, 6.0, vars="t,q,tau", every=25)
    q = vector(d, "q", 3)  # the CSV names the joint vector's elements q[0], q[1], q[2]
    assert d["t"][-1] == pytest.approx(6.0)
    np.testing.assert_allclose(q[-1], SET_POINTS, atol=0.01)
    for j in range(3):  # and it got there well before the end
        assert settle_time(d["t"], q[:, j], SET_POINTS[j], band=0.02) < 3.0
    assert np.abs(vector(d, "tau", 3)[5]).max() > 1.0  # the FMU's torques drove it


def test_the_fmu_labs_trajectory_matches_the_same_model_as_a_plain_ode_spec(lab, reference):
    names = "t,q,qd,tau,V"
    a = headless(lab, 3.0, vars=names, every=10)
    b = headless(reference, 3.0, vars=names, every=10)
    assert len(a["t"]) == len(b["t"]) > 50
    for key in b:
        np.testing.assert_allclose(a[key], b[key], rtol=0, atol=1e-6, err_msg=key)
    assert np.ptp(a["q[1]"]) > 1.0  # a real motion, not two arms at rest


def test_set_changes_an_fmu_parameter_from_the_command_line(lab):
    base = headless(lab, 2.0, vars="t,q", every=5)
    no_d = headless(lab, 2.0, vars="t,q", every=5, sets={"Kd": "0"})
    over_base = np.max(vector(base, "q", 3) / SET_POINTS, axis=0) - 1
    over_no_d = np.max(vector(no_d, "q", 3) / SET_POINTS, axis=0) - 1
    assert np.all(over_no_d > over_base + 0.01)  # without the derivative term the joints overshoot more


def test_a_failing_fmu_call_stops_a_headless_run_with_the_fmus_message_and_the_spec_line(lab):
    r = run_app(lab, "--headless", "--duration", "1", "--csv", "-", "--set", "i_max=20", timeout=120)
    assert r.returncode != 0
    spec = (ROOT / "examples" / f"{SPEC}.ejs.yaml").read_text().splitlines()
    line = next(k for k, text in enumerate(spec, 1) if text.strip() == "drives:")
    assert f"fmu_motor_control.ejs.yaml:{line}:" in r.stderr
    assert "exceeds the amplifier's limit i_max = 20 A" in r.stderr  # the FMU's own log message
    rows = r.stdout.strip().splitlines()
    assert 2 <= len(rows) < 250  # it ran until the current grew past the limit, then stopped


def test_the_labs_fmu_refuses_the_calls_the_fmi_state_machine_forbids(lab, capfd):
    """As the Reference FMUs do: a lenient FMU would hide an importer's wrong call order."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Model

    fmu = lab / "fmu_motor_control" / "joint_drives.fmu"
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    model = FMU2Model(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.modelExchange.modelIdentifier, instanceName="order")
    model.instantiate(loggingOn=False)
    from fmpy.fmi1 import FMICallException

    model.setReal([vr["G1"]], [80.0])  # a fixed parameter before initialization: fine
    model.setupExperiment(startTime=0.0)
    model.enterInitializationMode()
    model.exitInitializationMode()  # -> event mode
    model.setReal([vr["Kd"]], [0.2])  # a tunable parameter in event mode: fine
    model.newDiscreteStates()
    model.enterContinuousTimeMode()
    model.setReal([vr["q_ref1"]], [1.0])  # a continuous input in continuous time: fine
    with pytest.raises(FMICallException):
        model.setReal([vr["Kd"]], [0.0])  # a tunable parameter in continuous time: refused
    with pytest.raises(FMICallException):
        model.newDiscreteStates()  # outside event mode: refused
    with pytest.raises(FMICallException):
        model.setReal([vr["G1"]], [50.0])  # a fixed parameter after initialization: refused
    model.enterEventMode()
    model.setReal([vr["Kd"]], [0.0])
    model.terminate()
    model.freeInstance()
    said = capfd.readouterr().out
    assert "value reference 29 is a tunable parameter and cannot be set in continuous-time mode" in said
    assert "fmi2NewDiscreteStates: Illegal call sequence (the FMU is in continuous-time mode)" in said
    assert "value reference 36 is a fixed parameter and cannot be set in continuous-time mode" in said


def test_gains_changed_while_the_lab_runs_reach_the_fmu_as_in_the_plain_ode_model(lab, reference):
    """A slider moving Kd and Ki mid-run: the FMU gets them in event mode (model exchange), and
    the arm follows the plain ODE model given the same change at the same step."""
    from ejsrl.app import load_app

    runs = []
    for folder in (lab, reference):
        app = load_app(folder)
        try:
            for _ in range(200):
                app.step_once()
            app.model.Kd, app.model.Ki = 0.0, 25.0  # as the sliders do, between two steps
            for _ in range(300):
                app.step_once()
            assert app.error is None, app.error
            runs.append((float(app.model.t), np.array(app.model.q, dtype=float)))
        finally:
            app.stop()
    (t_a, q_a), (t_b, q_b) = runs
    assert t_a == pytest.approx(2.0) and t_b == pytest.approx(2.0)
    np.testing.assert_allclose(q_a, q_b, rtol=0, atol=1e-6)


def test_two_instances_of_the_lab_in_one_process_each_get_their_fmus_own_messages(lab, capfd):
    """FMPy's formatting shim keeps one logger per process: each instance must still get its own
    FMU's messages (two class sessions), and FMPy's own default logger must still print after."""
    from ejsrl.app import load_app
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Model

    apps = [load_app(lab), load_app(lab)]
    try:
        for app in apps:
            app.step_once()
        drives = [app.model._ejs_fmus.runs[0].inst for app in apps]
        assert len(drives) == 2
        for d in drives:
            start = len(d.log)
            with pytest.raises(Exception):
                d.call("fmi2NewDiscreteStates", d._fmu.newDiscreteStates)  # in continuous time: refused
            assert d.said(start) == ["fmi2NewDiscreteStates: Illegal call sequence (the FMU is in continuous-time mode)"]
    finally:
        for app in apps:
            app.stop()
    fmu = lab / "fmu_motor_control" / "joint_drives.fmu"
    md = read_model_description(str(fmu))
    model = FMU2Model(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.modelExchange.modelIdentifier, instanceName="after")
    model.instantiate()
    model.setupExperiment(startTime=0.0)
    model.enterInitializationMode()
    model.exitInitializationMode()
    model.enterContinuousTimeMode()
    with pytest.raises(Exception):
        model.newDiscreteStates()
    model.terminate()
    model.freeInstance()
    assert "Illegal call sequence" in capfd.readouterr().out
