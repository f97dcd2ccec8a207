"""Benchmark ejsrl.robotics against Robotics Toolbox for Python and Pinocchio (Puma 560).

Runs the same operations in one process and prints time ratios (anchor time / ejsrl time:
above 1 means ejsrl is faster), for single calls and over 10,000 configurations:
fkine, jacob0, ikine, rne, inertia, accel. The results are checked to agree before they
are timed. Ends with the issue's targets, each marked MET or NOT MET.

Needs the ``bench`` extra: ``pip install roboticstoolbox-python pin`` (Robotics Toolbox
for Python >= 1.1 and Pinocchio >= 3, both work with NumPy 2). If they cannot share the
main environment, use a separate one:

    python -m venv /tmp/rtbvenv
    /tmp/rtbvenv/bin/pip install roboticstoolbox-python pin numpy scipy
    /tmp/rtbvenv/bin/python bench/robotics.py            # finds ejsrl in runtime/

Options: ``--quick`` (fewer repetitions), ``--n-ik N`` (IK targets, default 1,000 as in the target).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
import warnings
from pathlib import Path
from typing import Callable

import numpy as np

try:
    import ejsrl.robotics  # noqa: F401
except ImportError:  # run from a checkout without installing
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "runtime"))

from ejsrl.robotics import models  # noqa: E402

BATCH = 10_000


def best_time(f: Callable[[], object], repeat: int, number: int) -> float:
    """Best of ``repeat`` runs of ``number`` calls: seconds per call."""
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            f()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def load_anchors() -> tuple[object | None, object | None]:
    warnings.filterwarnings("ignore")
    try:
        import roboticstoolbox as rtb
    except ImportError:
        print("roboticstoolbox-python not installed: pip install roboticstoolbox-python")
        rtb = None
    try:
        import pinocchio as pin
    except ImportError:
        print("Pinocchio not installed: pip install pin")
        pin = None
    return rtb, pin


def pinocchio_puma(pin, robot):  # type: ignore[no-untyped-def]
    """The same Puma 560 (standard DH, with armature) as a Pinocchio model.

    Joint i sits in DH frame i-1 and turns about its z axis; link i's body is attached
    through the fixed part ``Tz(d) Tx(a) Rx(alpha)`` of its DH transform."""
    model = pin.Model()
    parent = 0
    placement = pin.SE3.Identity()
    robot._params()
    for i, link in enumerate(robot.links):
        jid = model.addJoint(parent, pin.JointModelRZ(), placement, f"j{i + 1}")
        S = link.A(-link.offset)  # fixed part: A at theta = 0
        Rs, ps = S[:3, :3], S[:3, 3]
        inertia = pin.Inertia(link.m, Rs @ link.r + ps, Rs @ link.I @ Rs.T)
        model.appendBodyToJoint(jid, inertia, pin.SE3.Identity())
        placement = pin.SE3(Rs, ps)
        parent = jid
    fid = model.addFrame(pin.Frame("tool", parent, placement * pin.SE3(robot.tool[:3, :3], robot.tool[:3, 3]),
                                   pin.FrameType.OP_FRAME))
    model.armature = np.array([k.Jm * k.G**2 for k in robot.links])
    model.gravity.linear = robot.gravity
    return model, model.createData(), fid


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--n-ik", type=int, default=1000)
    args = ap.parse_args()
    rep, num = (3, 50) if args.quick else (5, 300)
    brep = 2 if args.quick else 5
    rtb, pin = load_anchors()

    ours = models.puma560()
    rng = np.random.default_rng(1)
    lim = ours.qlim
    q = ours.qn + 0.1
    # ejsrl generates each operation's code for the arm on first use: time that once.
    t0 = time.perf_counter()
    for op in (ours.fkine, ours.jacob0, ours.inertia, ours.gravload):
        op(q)
    ours.rne(q, q, q)
    ours.accel(q, q, q)
    ours.ikine(ours.fkine(q))
    t_build = time.perf_counter() - t0
    qd = np.linspace(-0.5, 0.5, 6)
    qdd = np.linspace(1.0, -1.0, 6)
    tau = ours.rne(q, qd, qdd)
    Q = rng.uniform(lim[0], lim[1], (BATCH, 6))
    Qd = rng.uniform(-1, 1, (BATCH, 6))
    Qdd = rng.uniform(-1, 1, (BATCH, 6))
    Tau = ours.rne(Q, Qd, Qdd)
    T_goal = ours.fkine(q)

    rows: list[tuple[str, str, float, dict[str, float]]] = []  # (op, mode, ours, anchors)

    def add(op: str, mode: str, f_ours: Callable[[], object], anchors: dict[str, Callable[[], object]]) -> None:
        t_ours = best_time(f_ours, rep, num)
        t_anchor = {name: best_time(f, rep, num) for name, f in anchors.items()}
        rows.append((op, mode, t_ours, t_anchor))

    # ---------------------------------------------------------------- anchors and agreement
    single: dict[str, dict[str, Callable[[], object]]] = {k: {} for k in ("fkine", "jacob0", "rne", "inertia", "accel")}
    batched: dict[str, dict[str, Callable[[], object]]] = {k: {} for k in single}
    Qs = Q[:: BATCH // 1000]  # loops over anchors run on 1,000 configurations, scaled x10
    if rtb is not None:
        p = rtb.models.DH.Puma560()
        ets = p.ets()
        assert np.allclose(p.fkine(q).A, ours.fkine(q)) and np.allclose(p.jacob0(q), ours.jacob0(q))
        assert np.allclose(p.rne(q, qd, qdd), ours.rne(q, qd, qdd))
        assert np.allclose(p.inertia(q), ours.inertia(q)) and np.allclose(p.accel(q, qd, tau), qdd)
        single["fkine"].update({"RTB DHRobot.fkine": lambda: p.fkine(q), "RTB ETS.fkine (C++)": lambda: ets.fkine(q)})
        single["jacob0"].update({"RTB DHRobot.jacob0": lambda: p.jacob0(q), "RTB ETS.jacob0 (C++)": lambda: ets.jacob0(q)})
        single["rne"]["RTB rne (C frne)"] = lambda: p.rne(q, qd, qdd)
        single["inertia"]["RTB inertia"] = lambda: p.inertia(q)
        single["accel"]["RTB accel"] = lambda: p.accel(q, qd, tau)
        batched["fkine"]["RTB ETS.fkine (C++) on (m, n)"] = lambda: ets.fkine(Qs)
        batched["jacob0"]["RTB loop ETS.jacob0 (C++)"] = lambda: [ets.jacob0(x) for x in Qs]
        batched["rne"]["RTB rne (C) on (m, n)"] = lambda: p.rne(Qs, Qd[: len(Qs)], Qdd[: len(Qs)])
        batched["inertia"]["RTB inertia on (m, n)"] = lambda: p.inertia(Qs)
        batched["accel"]["RTB loop accel"] = lambda: [p.accel(x, qd, tau) for x in Qs]
    if pin is not None:
        model, data, fid = pinocchio_puma(pin, ours)
        pin.framesForwardKinematics(model, data, q)
        assert np.allclose(data.oMf[fid].homogeneous, ours.fkine(q))
        Jp = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        assert np.allclose(Jp, ours.jacob0(q))
        assert np.allclose(pin.rnea(model, data, q, qd, qdd), ours.rne(q, qd, qdd, friction=False))
        M = pin.crba(model, data, q)
        assert np.allclose(np.triu(M) + np.triu(M, 1).T, ours.inertia(q))
        tau_nf = ours.rne(q, qd, qdd, friction=False)
        assert np.allclose(pin.aba(model, data, q, qd, tau_nf), qdd)

        def pin_fk(x):  # type: ignore[no-untyped-def]
            pin.framesForwardKinematics(model, data, x)
            return data.oMf[fid].homogeneous

        single["fkine"]["Pinocchio framesForwardKinematics"] = lambda: pin_fk(q)
        single["jacob0"]["Pinocchio computeFrameJacobian"] = lambda: pin.computeFrameJacobian(
            model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        single["rne"]["Pinocchio rnea"] = lambda: pin.rnea(model, data, q, qd, qdd)
        single["inertia"]["Pinocchio crba"] = lambda: pin.crba(model, data, q)
        single["accel"]["Pinocchio aba"] = lambda: pin.aba(model, data, q, qd, tau_nf)
        batched["fkine"]["Pinocchio Python loop"] = lambda: [pin_fk(x) for x in Qs]
        batched["jacob0"]["Pinocchio Python loop"] = lambda: [
            pin.computeFrameJacobian(model, data, x, fid, pin.LOCAL_WORLD_ALIGNED) for x in Qs]
        batched["rne"]["Pinocchio Python loop"] = lambda: [pin.rnea(model, data, x, qd, qdd) for x in Qs]
        batched["inertia"]["Pinocchio Python loop"] = lambda: [pin.crba(model, data, x) for x in Qs]
        batched["accel"]["Pinocchio Python loop"] = lambda: [pin.aba(model, data, x, qd, tau_nf) for x in Qs]

    ours_single = {
        "fkine": lambda: ours.fkine(q),
        "jacob0": lambda: ours.jacob0(q),
        "rne": lambda: ours.rne(q, qd, qdd),
        "inertia": lambda: ours.inertia(q),
        "accel": lambda: ours.accel(q, qd, tau),
    }
    ours_batch = {
        "fkine": lambda: ours.fkine(Q),
        "jacob0": lambda: ours.jacob0(Q),
        "rne": lambda: ours.rne(Q, Qd, Qdd),
        "inertia": lambda: ours.inertia(Q),
        "accel": lambda: ours.accel(Q, Qd, Tau),
    }
    for op in ours_single:
        add(op, "single", ours_single[op], single[op])
    for op in ours_batch:
        # best of brep runs on both sides: on a shared machine one run can be twice as slow
        t_ours = best_time(ours_batch[op], brep, 1)
        t_anchor = {name: 10 * best_time(f, brep, 1) for name, f in batched[op].items()}  # 1,000 -> 10,000
        rows.append((op, f"{BATCH:,} configs", t_ours, t_anchor))

    # ---------------------------------------------------------------- inverse kinematics
    targets = ours.fkine(rng.uniform(lim[0], lim[1], (args.n_ik, 6)))
    times, ok = [], 0
    for T in targets:
        t0 = time.perf_counter()
        sol = ours.ikine(T)
        times.append(time.perf_counter() - t0)
        ok += sol.success
    ik_med = statistics.median(times)
    ik_rate = ok / len(targets)
    ik_anchor: dict[str, float] = {}
    if rtb is not None:
        rt, rok = [], 0
        for T in targets:
            t0 = time.perf_counter()
            s = ets.ikine_LM(T, tol=1e-10, joint_limits=True)
            rt.append(time.perf_counter() - t0)
            rok += bool(s.success)
        ik_anchor["RTB ETS.ikine_LM (C++)"] = statistics.median(rt)
        print(f"RTB ikine_LM success {rok}/{len(targets)}")
    rows.append(("ikine", f"median of {len(targets)}", ik_med, ik_anchor))
    t_single_ik = best_time(lambda: ours.ikine(T_goal, q0=ours.qn), rep, 20)

    # ---------------------------------------------------------------- report
    print(f"\nPuma 560, ejsrl.robotics vs anchors (ratio = anchor time / ejsrl time; > 1: ejsrl faster)")
    print(f"{'operation':<9} {'mode':<18} {'ejsrl':>11}  anchor: time (ratio)")
    for op, mode, t_o, anchors in rows:
        cells = "; ".join(f"{name} {fmt(t)} ({t / t_o:.2f}x)" for name, t in anchors.items())
        print(f"{op:<9} {mode:<18} {fmt(t_o):>11}  {cells}")
    print(f"ikine from a nearby seed (q0 = qn): {fmt(t_single_ik)}; success over random targets: "
          f"{ik_rate * 100:.1f} %")
    print(f"first calls (generate the arm's code for fkine, jacob0, inertia, gravload, rne, accel, ikine): "
          f"{fmt(t_build)} in all, once per arm and parameter change")

    print("\nTargets:")
    for op, mode, t_o, anchors in rows:
        rtb_times = [t for name, t in anchors.items() if name.startswith("RTB")]
        if rtb_times:
            met = t_o < min(rtb_times)
            print(f"  {'MET    ' if met else 'NOT MET'} faster than the Toolbox: {op} ({mode}): "
                  f"{fmt(t_o)} vs best {fmt(min(rtb_times))}")
    for op, mode, t_o, anchors in rows:
        if mode.endswith("configs") and op in ("fkine", "jacob0", "rne"):
            pin_t = [t for name, t in anchors.items() if name.startswith("Pinocchio")]
            if pin_t:
                print(f"  {'MET    ' if t_o < pin_t[0] else 'NOT MET'} batched {op} faster than a Python loop "
                      f"over Pinocchio: {fmt(t_o)} vs {fmt(pin_t[0])}")
    print(f"  {'MET    ' if ik_med < 0.5e-3 else 'NOT MET'} median ikine under 0.5 ms: {fmt(ik_med)}")
    print(f"  {'MET    ' if ik_rate >= 0.995 else 'NOT MET'} ikine success >= 99.5 %: {ik_rate * 100:.1f} %")


def fmt(t: float) -> str:
    if t < 1e-3:
        return f"{t * 1e6:.1f} us"
    if t < 1:
        return f"{t * 1e3:.2f} ms"
    return f"{t:.2f} s"


if __name__ == "__main__":
    main()
