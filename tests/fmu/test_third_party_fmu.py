"""An FMU that nobody on this project wrote the C of: exported at test time by pythonfmu
(PyPI), a third-party exporter (FMI 2.0 co-simulation, its own binary calling Python), run
in a lab with an input and a tunable parameter changing mid-run, against
``fmpy.simulate_fmu`` given the same changes through its ``input``."""

from __future__ import annotations

import io
import subprocess
import sys
import textwrap

import numpy as np
from testkit import run_app

HEATER = '''\
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real


class Heater(Fmi2Slave):
    author = "ejsgen tests"
    description = "A thermal mass heated by an input power and cooled towards 20 degrees"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.power = 0.0
        self.k = 0.5
        self.T = 20.0
        self.steps = 0
        self.register_variable(Real("power", causality=Fmi2Causality.input))
        self.register_variable(Real("k", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
        self.register_variable(Real("T", causality=Fmi2Causality.output))
        self.register_variable(Integer("steps", causality=Fmi2Causality.output, variability=Fmi2Variability.discrete))

    def do_step(self, current_time, step_size):
        self.T += step_size * (self.power - self.k * (self.T - 20.0))
        self.steps += 1
        return True
'''

SPEC = """\
ejs: 1
title: A heater exported by pythonfmu
model:
  variables:
    t: 0.0
    dt: 0.05
    n: 0
    heating: 10.0
    T: 0.0
    steps: 0
  evolution:
    - code: |
        n = n + 1
        t = n * dt
fmus:
  heater:
    file: Heater.fmu
    inputs: {power: "heating if t < 1 - 1e-9 else 0.0"}
    parameters: {k: "0.5 if t < 2 - 1e-9 else 2.0"}
    outputs: {T: T, steps: steps}
"""


def test_a_pythonfmu_export_runs_in_a_lab_as_in_fmpy(tmp_path):
    from ejsgen.cli import build
    from fmpy import simulate_fmu

    (tmp_path / "heater.py").write_text(HEATER)
    r = subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f", "heater.py", "--dest", "."], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and (tmp_path / "Heater.fmu").is_file(), r.stderr
    (tmp_path / "heater.ejs.yaml").write_text(textwrap.dedent(SPEC))
    app = build(tmp_path / "heater.ejs.yaml", tmp_path / "app")
    run = run_app(app, "--headless", "--duration", "3", "--csv", "-", "--vars", "t,T,steps")
    assert run.returncode == 0, run.stderr
    d = np.genfromtxt(io.StringIO(run.stdout), delimiter=",", names=True)
    signals = np.array(
        [(0.0, 10.0, 0.5), (1.0, 10.0, 0.5), (1.0, 0.0, 0.5), (2.0, 0.0, 0.5), (2.0, 0.0, 2.0), (3.0, 0.0, 2.0)],
        dtype=[("time", float), ("power", float), ("k", float)],
    )
    ref = simulate_fmu(str(app / "Heater.fmu"), fmi_type="CoSimulation", start_time=0.0, stop_time=3.0, output_interval=0.05, output=["T", "steps"], input=signals)
    assert len(d) == len(ref) == 61
    np.testing.assert_allclose(d["T"], ref["T"], rtol=0, atol=1e-13)
    np.testing.assert_array_equal(d["steps"], ref["steps"])
    peak = int(np.argmax(d["T"]))
    assert abs(d["t"][peak] - 1.0) < 1e-9 and d["T"][peak] > 25  # heated until t = 1, then cooled
    # after t = 2 the cooling is four times faster: T - 20 falls by (1 - 2 dt) a step
    late = d["T"][d["t"] > 2.05] - 20
    np.testing.assert_allclose(late[1:] / late[:-1], 1 - 2.0 * 0.05, rtol=1e-12)
