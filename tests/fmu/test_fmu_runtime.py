"""FMUs at run time: co-simulation stepping against FMPy's own master, resets that
re-instantiate, a failing call that pauses the app with the FMU's message, freeing on stop,
tunable parameters changed while running.

The independent reference is ``fmpy.simulate_fmu`` (FMPy's co-simulation master) run on
the same FMU, with the same inputs and communication step.
"""

from __future__ import annotations

import io

import numpy as np
import pytest
from testkit import run_app
from testkit.fmu import build_spec, cs_spec


def csv_columns(text: str) -> dict[str, np.ndarray]:
    data = np.genfromtxt(io.StringIO(text), delimiter=",", names=True, deletechars="")
    return {n: np.atleast_1d(data[n]) for n in data.dtype.names}


def fmpy_reference(app, interval: float, stop: float) -> np.ndarray:
    """(time, tau1) from FMPy's master: doStep every ``interval``, q_ref1 = 1."""
    from fmpy import simulate_fmu

    r = simulate_fmu(str(app / "drives.fmu"), fmi_type="CoSimulation", stop_time=stop, output_interval=interval, start_values={"q_ref1": 1.0}, output=["tau1"])
    return np.column_stack([r["time"], r["tau1"]])


@pytest.fixture(scope="module")
def cs_app(tmp_path_factory):
    return build_spec(tmp_path_factory.mktemp("cs"), cs_spec())


def test_one_do_step_per_model_step_matches_fmpys_master(cs_app):
    r = run_app(cs_app, "--headless", "--duration", "0.5", "--csv", "-", "--vars", "t,tau")
    assert r.returncode == 0, r.stderr
    d = csv_columns(r.stdout)
    ref = fmpy_reference(cs_app, 0.01, 0.5)
    assert len(d["t"]) == len(ref) == 51
    np.testing.assert_allclose(d["t"], ref[:, 0], atol=1e-12)
    np.testing.assert_allclose(d["tau[0]"], ref[:, 1], rtol=1e-12, atol=1e-12)
    assert ref[-1, 1] > 1.0


def test_a_communication_step_holds_the_outputs_between_communication_points(tmp_path):
    app = build_spec(tmp_path, cs_spec("0.05"))
    r = run_app(app, "--headless", "--duration", "0.5", "--csv", "-", "--vars", "t,tau")
    assert r.returncode == 0, r.stderr
    d = csv_columns(r.stdout)
    ref = fmpy_reference(app, 0.05, 0.5)
    at_points = np.isclose(np.mod(d["t"] + 1e-9, 0.05), 0.0, atol=1e-6)
    np.testing.assert_allclose(d["tau[0]"][at_points], ref[:, 1], rtol=1e-12, atol=1e-12)
    # between communication points the model sees the last output (zero-order hold)
    held = d["tau[0]"][1:6]
    assert np.all(held[:4] == d["tau[0]"][0]) and held[4] != held[0]


def test_reset_re_instantiates_the_fmu(cs_app):
    from ejsrl.app import load_app

    app = load_app(cs_app)
    try:
        for _ in range(20):
            app.step_once()
        first = [float(app.model.tau[0])]
        run = app.model._ejs_fmus.runs[0]
        app.reset()
        assert run.inst.freed  # the old instance is gone
        assert app.model.t == 0.0 and app.model.tau[0] == 0.0
        assert app.model._ejs_fmus.runs[0].inst is not run.inst
        for _ in range(20):
            app.step_once()
        assert [float(app.model.tau[0])] == first  # a fresh FMU, not one carrying on its integrals
    finally:
        app.stop()


def test_stopping_the_app_frees_the_fmu(cs_app):
    from ejsrl.app import load_app

    app = load_app(cs_app)
    app.step_once()
    inst = app.model._ejs_fmus.runs[0].inst
    app.stop()
    assert inst.freed and app.model._ejs_fmus is None


def test_a_failing_fmu_call_pauses_the_app_with_the_fmus_own_message(cs_app):
    from ejsrl.app import load_app

    app = load_app(cs_app, overrides={"i_max": 5.0})
    try:
        app.play()
        for _ in range(30):
            app._run_steps(1)
            if app.error is not None:
                break
        assert app.error is not None and not app.playing
        assert "joint 1: armature current" in app.error.message and "i_max = 5 A" in app.error.message
        assert "fmi2DoStep returned error: joint 1: armature current" in app.error.message
        assert app.error.where == "lab.ejs.yaml:15:3"  # the FMU's entry in the spec
    finally:
        app.stop()


def test_a_tunable_parameter_changed_while_running_reaches_the_fmu(cs_app):
    from ejsrl.app import load_app

    app = load_app(cs_app, overrides={"i_max": 5.0})
    try:
        app.model.i_max = 1000.0  # as a slider would, before the current grows past 5 A
        for _ in range(30):
            app.step_once()
        assert app.error is None and app.model.tau[0] > 1.0
    finally:
        app.stop()


def test_an_app_run_without_fmpy_says_how_to_install_it(cs_app):
    import subprocess
    import sys

    code = "import runpy, sys; sys.modules['fmpy'] = None; sys.argv = ['app.py', '--headless', '--duration', '0.1']; runpy.run_path('app.py', run_name='__main__')"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=cs_app)
    assert r.returncode == 1
    assert "lab.ejs.yaml:15:3: error" in r.stderr and "pip install 'ejsgen[fmu]'" in r.stderr


def test_a_model_dropped_without_stopping_frees_its_fmu(cs_app):
    """A browser tab's session that ends drops its model: the FMU goes with it."""
    import gc

    from ejsrl.app import load_app

    app = load_app(cs_app)
    app.step_once()
    inst = app.model._ejs_fmus.runs[0].inst
    del app
    gc.collect()
    assert inst.freed
