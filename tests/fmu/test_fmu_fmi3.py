"""The FMI 3.0 path: the lab's joint drives as an FMI 3.0 FMU (tests/fmu/fmi3_drives, built
from C by the build like the lab's FMI 2.0 one), in the lab itself (model exchange) and
alone (co-simulation). References: the same model as a plain ODE spec, and FMPy's own
co-simulation master on the same FMU."""

from __future__ import annotations

import io
import shutil

import numpy as np
import pytest
from testkit import EXAMPLES, ROOT, run_app
from testkit.fmu import DRIVES, cs_spec
from testkit.labs import headless

FMI3 = ROOT / "tests" / "fmu" / "fmi3_drives"


def fmi3_folder(dest):
    shutil.copytree(FMI3, dest)
    shutil.copy2(DRIVES / "sources" / "drives.h", dest / "sources" / "drives.h")
    return dest


@pytest.fixture(scope="module")
def lab3(tmp_path_factory):
    """Lab 8 with its FMU replaced by the FMI 3.0 one."""
    from ejsgen.cli import build

    folder = tmp_path_factory.mktemp("fmi3")
    fmi3_folder(folder / "drives3")
    text = (EXAMPLES / "paper" / "fmu_motor_control.ejs.yaml").read_text()
    assert "file: fmu_motor_control/joint_drives\n" in text
    spec = folder / "lab3.ejs.yaml"
    spec.write_text(text.replace("file: fmu_motor_control/joint_drives\n", "file: drives3\n"))
    return build(spec, folder / "app")


def test_the_built_fmi3_fmu_is_valid(lab3):
    from fmpy import platform_tuple, read_model_description
    from fmpy.validation import validate_fmu

    fmu = lab3 / "drives3.fmu"
    assert read_model_description(str(fmu)).fmiVersion == "3.0"
    assert validate_fmu(str(fmu)) == []
    import zipfile

    assert f"binaries/{platform_tuple}/joint_drives3.so" in zipfile.ZipFile(fmu).namelist()


def test_the_lab_with_an_fmi3_fmu_matches_the_plain_ode_model(lab3, tmp_path):
    from ejsgen.cli import build

    reference = build(ROOT / "tests" / "fmu" / "specs" / "motor_control_ode.ejs.yaml", tmp_path / "ref")
    a = headless(lab3, 2.0, vars="t,q,qd,tau", every=10)
    b = headless(reference, 2.0, vars="t,q,qd,tau", every=10)
    for key in b:
        np.testing.assert_allclose(a[key], b[key], rtol=0, atol=1e-6, err_msg=key)
    np.testing.assert_allclose([a["q[0]"][-1], a["q[1]"][-1], a["q[2]"][-1]], [np.pi / 2, np.pi / 3, -np.pi / 4], atol=0.01)


def test_an_fmi3_co_simulation_matches_fmpys_master_and_reports_its_errors(tmp_path):
    from ejsgen.cli import build
    from fmpy import simulate_fmu

    fmi3_folder(tmp_path / "drives")
    spec = tmp_path / "cs3.ejs.yaml"
    spec.write_text(cs_spec().lstrip())
    app = build(spec, tmp_path / "app")
    r = run_app(app, "--headless", "--duration", "0.3", "--csv", "-", "--vars", "t,tau")
    assert r.returncode == 0, r.stderr
    d = np.genfromtxt(io.StringIO(r.stdout), delimiter=",", names=True, deletechars="")
    ref = simulate_fmu(str(app / "drives.fmu"), fmi_type="CoSimulation", stop_time=0.3, output_interval=0.01, start_values={"q_ref1": 1.0}, output=["tau1"])
    np.testing.assert_allclose(d["tau[0]"], ref["tau1"], rtol=1e-12, atol=1e-12)
    bad = run_app(app, "--headless", "--duration", "0.3", "--set", "i_max=5")
    assert bad.returncode == 1
    assert "cs3.ejs.yaml:15:3: error: FMU 'drives': fmi3DoStep returned error: joint 1: armature current" in bad.stderr


def test_gains_changed_while_the_fmi3_lab_runs_reach_its_fmu_in_event_mode(lab3, tmp_path):
    """The FMI 3.0 drives refuse a tunable parameter in continuous-time mode (as the
    Reference FMUs do): moving Kd and Ki mid-run must go through event mode, and the arm then
    follows the plain ODE model given the same change at the same step."""
    from ejsgen.cli import build
    from ejsrl.app import load_app

    reference = build(ROOT / "tests" / "fmu" / "specs" / "motor_control_ode.ejs.yaml", tmp_path / "ref")
    runs = []
    for folder in (lab3, reference):
        app = load_app(folder)
        try:
            for _ in range(200):
                app.step_once()
            app.model.Kd, app.model.Ki = 0.0, 25.0
            for _ in range(300):
                app.step_once()
            assert app.error is None, app.error
            runs.append(np.array(app.model.q, dtype=float))
        finally:
            app.stop()
    np.testing.assert_allclose(runs[0], runs[1], rtol=0, atol=1e-6)
