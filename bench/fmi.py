"""FMU overhead of generated apps, side by side with a bare FMPy loop and fmpy.simulate_fmu.

Prints, in one run, the cost of one simulation step of a lab whose only work is one FMU
(lab 8's joint drives: 9 inputs, 6 outputs, 6 states, from its C sources), in co-simulation
and in model exchange:

- **ejsgen**: the generated app's ``model._ejs_step()`` (the spec's code page, the FMU's
  inputs read from the model, the FMI calls, the outputs written into the model);
- **bare FMPy loop**: a hand-written loop making the same FMI calls through FMPy's ctypes
  functions with buffers made once, moving the same data (the inputs read from three
  arrays, the outputs written into two) (co-simulation: set the inputs, ``doStep``, get the
  outputs; model exchange with the FMU's own RK4 solver: set the inputs at the step's
  start, per RK4 stage set the time and the states and get the
  derivatives, at the end set them and get the outputs, then ``completedIntegratorStep``):
  the floor a Python importer can reach;
- **fmpy.simulate_fmu**: FMPy's own master over the same steps (model exchange with its
  fixed-step Euler solver), for scale.

Goal (issue #25): ejsgen <= 1.3x the bare loop in co-simulation and <= 1.5x in model
exchange. Times are the process's CPU time (a machine shared with other work slows the
wall clock of one run and not of the other), the best of interleaved runs.
``--profile`` prints the top of cProfile's listing of the ejsgen run.

Run: python bench/fmi.py [--steps 20000] [--repeat 5] [--profile]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from ctypes import c_double, c_uint
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import EXAMPLES  # noqa: E402

DRIVES = EXAMPLES / "paper" / "fmu_motor_control" / "joint_drives"
INPUTS = ["q_ref1", "q_ref2", "q_ref3", "q1", "q2", "q3", "qd1", "qd2", "qd3"]
OUTPUTS = ["tau1", "tau2", "tau3", "V1", "V2", "V3"]
DT = 0.001

SPEC = """\
ejs: 1
title: The joint drives alone ({kind})
model:
  variables:
    t: 0.0
    dt: {dt}
    n: 0
    q_ref: [1.0, 0.5, -0.5]
    q: [0.0, 0.0, 0.0]
    qd: [0.0, 0.0, 0.0]
    tau: [0.0, 0.0, 0.0]
    V: [0.0, 0.0, 0.0]
  evolution:
    - code: |
        n = n + 1
        t = n * dt
fmus:
  drives:
    file: joint_drives
    kind: {kind}
    {solver}
    inputs: {{q_ref1: "q_ref[0]", q_ref2: "q_ref[1]", q_ref3: "q_ref[2]", q1: "q[0]", q2: "q[1]", q3: "q[2]", qd1: "qd[0]", qd2: "qd[1]", qd3: "qd[2]"}}
    outputs: {{tau1: "tau[0]", tau2: "tau[1]", tau3: "tau[2]", V1: "V[0]", V2: "V[1]", V3: "V[2]"}}
"""


def build(kind: str, root: Path) -> tuple[object, Path]:
    """The app of the drives alone, loaded; and the .fmu the build compiled."""
    import shutil

    from ejsgen.cli import build as build_spec
    from ejsrl.app import load_app

    folder = root / kind
    folder.mkdir()
    shutil.copytree(DRIVES, folder / "joint_drives")
    spec = folder / "drives.ejs.yaml"
    solver = "method: rk4" if kind == "model_exchange" else ""
    spec.write_text(SPEC.format(kind=kind, dt=DT, solver=solver))
    out = build_spec(spec, folder / "app")
    return load_app(out), out / "joint_drives.fmu"


def ejsgen_step(app: object, steps: int) -> float:
    model = app.model  # type: ignore[attr-defined]
    step = model._ejs_step
    start = time.process_time()
    for _ in range(steps):
        step()
    return (time.process_time() - start) / steps


def _open(fmu: Path, kind: str):  # noqa: ANN202 - an FMPy FMU object
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Model, FMU2Slave

    md = read_model_description(str(fmu))
    cls = FMU2Slave if kind == "co_simulation" else FMU2Model
    f = cls(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.modelExchange.modelIdentifier, instanceName="bare")
    f.instantiate()
    f.setupExperiment(startTime=0.0)
    f.enterInitializationMode()
    f.exitInitializationMode()
    vr = {v.name: v.valueReference for v in md.modelVariables}
    vin = (c_uint * len(INPUTS))(*[vr[n] for n in INPUTS])
    vout = (c_uint * len(OUTPUTS))(*[vr[n] for n in OUTPUTS])
    return f, vin, vout


class Held:
    """The model's side of the bare loops: the arrays the inputs come from and the outputs go to."""

    def __init__(self) -> None:
        self.q_ref = np.array([1.0, 0.5, -0.5])
        self.q, self.qd = np.zeros(3), np.zeros(3)
        self.tau, self.V = np.zeros(3), np.zeros(3)

    def inputs(self, u: object) -> None:
        u[:] = [*self.q_ref.tolist(), *self.q.tolist(), *self.qd.tolist()]  # type: ignore[index]

    def outputs(self, y: object) -> None:
        values = y[:]  # type: ignore[index]
        self.tau[0:3] = values[0:3]
        self.V[0:3] = values[3:6]


def bare_cs(fmu: Path, steps: int) -> float:
    f, vin, vout = _open(fmu, "co_simulation")
    u = (c_double * len(INPUTS))()
    y = (c_double * len(OUTPUTS))()
    comp, set_real, get_real, do_step = f.component, f.fmi2SetReal, f.fmi2GetReal, f.fmi2DoStep
    m = Held()
    t = 0.0
    start = time.process_time()
    for k in range(steps):
        m.inputs(u)
        set_real(comp, vin, len(INPUTS), u)
        t_next = (k + 1) * DT
        do_step(comp, t, t_next - t, 1)
        t = t_next
        get_real(comp, vout, len(OUTPUTS), y)
        m.outputs(y)
    out = (time.process_time() - start) / steps
    f.terminate()
    f.freeInstance()
    return out


def bare_me(fmu: Path, steps: int) -> float:
    """RK4 over the FMU's states with the same FMI calls per stage as ejsgen's."""
    f, vin, vout = _open(fmu, "model_exchange")
    f.newDiscreteStates()
    f.enterContinuousTimeMode()
    nx = 6
    x = np.zeros(nx)
    xs, dx = np.zeros(nx), np.zeros(nx)
    from ctypes import POINTER

    px, pdx = xs.ctypes.data_as(POINTER(c_double)), dx.ctypes.data_as(POINTER(c_double))
    u = (c_double * len(INPUTS))()
    y = (c_double * len(OUTPUTS))()
    m = Held()
    comp = f.component
    set_time, set_x, set_real, get_real = f.fmi2SetTime, f.fmi2SetContinuousStates, f.fmi2SetReal, f.fmi2GetReal
    get_dx, completed = f.fmi2GetDerivatives, f.fmi2CompletedIntegratorStep
    from ctypes import byref, c_int

    enter, term = c_int(), c_int()

    def rates(t: float, state: np.ndarray) -> np.ndarray:
        set_time(comp, t)
        xs[:] = state
        set_x(comp, px, nx)
        get_dx(comp, pdx, nx)
        return dx.copy()

    t, h = 0.0, DT
    start = time.process_time()
    for k in range(steps):
        m.inputs(u)  # the inputs, held over the step
        set_real(comp, vin, len(INPUTS), u)
        k1 = rates(t, x)
        k2 = rates(t + h / 2, x + h / 2 * k1)
        k3 = rates(t + h / 2, x + h / 2 * k2)
        k4 = rates(t + h, x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t = (k + 1) * h
        set_time(comp, t)  # the outputs at the step's end
        xs[:] = x
        set_x(comp, px, nx)
        get_real(comp, vout, len(OUTPUTS), y)
        m.outputs(y)
        completed(comp, 1, byref(enter), byref(term))
    out = (time.process_time() - start) / steps
    f.terminate()
    f.freeInstance()
    return out


def fmpy_master(fmu: Path, kind: str, steps: int) -> float:
    from fmpy import simulate_fmu

    start = time.process_time()
    if kind == "co_simulation":
        simulate_fmu(str(fmu), fmi_type="CoSimulation", stop_time=steps * DT, output_interval=DT, output=OUTPUTS, start_values={"q_ref1": 1.0})
    else:
        simulate_fmu(str(fmu), fmi_type="ModelExchange", solver="Euler", step_size=DT, stop_time=steps * DT, output_interval=DT, output=OUTPUTS, start_values={"q_ref1": 1.0})
    return (time.process_time() - start) / steps


def best(fn, repeat: int) -> float:  # noqa: ANN001
    return min(fn() for _ in range(repeat))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--profile", action="store_true", help="print cProfile's top functions of the ejsgen runs")
    args = ap.parse_args(argv)
    root = Path(tempfile.mkdtemp(prefix="ejsgen-bench-fmi-"))
    print(f"per-step cost, best of {args.repeat} runs of {args.steps} steps (dt = {DT} s), lab 8's joint drives alone")
    print(f"{'':16}{'ejsgen':>12}{'bare FMPy':>12}{'ratio':>8}{'simulate_fmu':>14}  goal")
    for kind, goal, bare in (("co_simulation", 1.3, bare_cs), ("model_exchange", 1.5, bare_me)):
        app, fmu = build(kind, root)
        try:
            ours, floor = np.inf, np.inf
            for _ in range(args.repeat):  # interleaved: a busy machine slows both alike
                ours = min(ours, ejsgen_step(app, args.steps))
                floor = min(floor, bare(fmu, args.steps))
            master = best(lambda: fmpy_master(fmu, kind, args.steps), max(1, args.repeat // 2))
            print(f"{kind:16}{ours * 1e6:10.1f}us{floor * 1e6:10.1f}us{ours / floor:7.2f}x{master * 1e6:12.1f}us  <= {goal}x")
            if args.profile:
                import cProfile
                import pstats

                prof = cProfile.Profile()
                prof.runcall(ejsgen_step, app, args.steps)
                pstats.Stats(prof).sort_stats("tottime").print_stats(12)
        finally:
            app.stop()  # type: ignore[attr-defined]
    return 0


if __name__ == "__main__":
    sys.exit(main())
