"""Benchmark ejsrl.robotics against Robotics Toolbox for Python and Pinocchio.

Part 1 (Puma 560): fkine, jacob0, rne, inertia, accel, single calls and over 10,000
configurations, as time ratios (anchor time / ejsrl time: above 1 means ejsrl is faster).
The results are checked to agree before they are timed.

Part 2 (inverse kinematics on Puma 560, UR5 and PA-10, which have closed forms, and on the
Panda, KUKA KR5, ABB IRB140, LBR iiwa, UR10 and a random 6R): 1,000 random reachable targets per
arm, every solver asked for 1e-10 in position (m) and orientation (rad). Robotics
Toolbox's tolerance is on ``E = e^T e / 2``, so it gets ``tol = 0.5e-20`` (|e| < 1e-10);
its default ``tol=1e-10`` on E only guarantees |e| < 1.4e-5. Both Toolbox paths are timed,
interleaved target by target with ejsrl's (the machine may be loaded): the C++ solver
``ETS.ik_LM`` with ejsrl's ``ikine``, then the Python one ``ETS.ikine_LM`` with ejsrl's
LM-only path (``closed_form=False``). Accuracy is measured independently of
every solver: the Toolbox's ``ETS.fkine`` of the answer, position error norm and rotation
angle ``2 asin(|R - R*|_F / sqrt 8)``. Then targets at and near the wrist singularity
(q5 = 0, 1e-7, 1e-4) and unreachable targets (time to reject). Ends with the issue's
targets, each marked MET or NOT MET, and the load average during the run.

Needs the ``bench`` extra: ``pip install roboticstoolbox-python pin`` (Robotics Toolbox
for Python >= 1.1 and Pinocchio >= 3, both work with NumPy 2). If they cannot share the
main environment, use a separate one:

    python -m venv /tmp/rtbvenv
    /tmp/rtbvenv/bin/pip install roboticstoolbox-python pin numpy scipy
    /tmp/rtbvenv/bin/python bench/robotics.py            # finds ejsrl in runtime/

Options: ``--quick`` (fewer repetitions), ``--n-ik N`` (IK targets per arm, default 1,000
as in the target), ``--ik-only`` (part 2 only), ``--n-py N`` (targets given to the slow
Python ``ikine_LM``, default 200), ``--arms panda,kr5`` (only the IK arms whose name contains one).

ejsrl's LM searches run compiled (numba, the ``fast`` extra) when numba is installed;
``EJSRL_IK=python`` times the Python path instead.

Why a call grows when other solvers run between calls (profiled on Puma 560, CPU time, 2
cores): OpenBLAS's worker threads keep spinning for a while after a BLAS call in the code
run in between (the Toolbox's Python ``ikine_LM``) and take the core's shared resources
(17 -> 77 us a call on the Python path; with ``OPENBLAS_NUM_THREADS=1`` 31 us), and that
code evicts the Python path's bytecode and data from the caches (the rest, 1.8x). The
compiled searches run as one numba call, a few kilobytes of machine code with no Python
per iteration: the LM-only path goes 18 -> 33-41 us when interleaved, where the Python one
went 149 -> 246 us. The passes below pair each ejsrl path with the Toolbox path it is
compared with, as before.
"""

from __future__ import annotations

import argparse
import math
import os
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

from ejsrl.robotics import _ik_closed, models  # noqa: E402

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
    ap.add_argument("--n-py", type=int, default=200)
    ap.add_argument("--ik-only", action="store_true")
    ap.add_argument("--arms", default="", help="IK arms whose name contains one of these (comma-separated)")
    args = ap.parse_args()
    rtb, pin = load_anchors()
    load0 = os.getloadavg()
    if not args.ik_only:
        bench_puma(args, rtb, pin)
    ik_bench(args, rtb)
    load1 = os.getloadavg()
    print(f"\nload average (1, 5, 15 min) at start {fmt_load(load0)}, at end {fmt_load(load1)} "
          f"on {os.cpu_count()} cores")


def fmt_load(load: tuple[float, float, float]) -> str:
    return ", ".join(f"{x:.1f}" for x in load)


def bench_puma(args: argparse.Namespace, rtb, pin) -> None:  # type: ignore[no-untyped-def]
    """Part 1: kinematics and dynamics of the Puma 560 against both anchors."""
    rep, num = (3, 50) if args.quick else (5, 300)
    brep = 2 if args.quick else 5

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

    # ---------------------------------------------------------------- report
    print(f"\nPuma 560, ejsrl.robotics vs anchors (ratio = anchor time / ejsrl time; > 1: ejsrl faster)")
    print(f"{'operation':<9} {'mode':<18} {'ejsrl':>11}  anchor: time (ratio)")
    for op, mode, t_o, anchors in rows:
        cells = "; ".join(f"{name} {fmt(t)} ({t / t_o:.2f}x)" for name, t in anchors.items())
        print(f"{op:<9} {mode:<18} {fmt(t_o):>11}  {cells}")
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


# ---------------------------------------------------------------------------- inverse kinematics
IK_TOL = 1e-10  # m and rad, for every solver
RTB_TOL = 0.5 * IK_TOL**2  # the Toolbox's tolerance is on E = e^T e / 2


def rtb_arm(rtb, robot):  # type: ignore[no-untyped-def]
    """The same arm (standard DH, same joint limits) as a Toolbox DHRobot and its ETS."""
    from spatialmath import SE3

    cls = rtb.RevoluteMDH if robot.mdh else rtb.RevoluteDH
    links = [cls(d=k.d, a=k.a, alpha=k.alpha, offset=k.offset, qlim=k.qlim) for k in robot.links]
    arm = rtb.DHRobot(links, name=robot.name, base=SE3(robot.base, check=False), tool=SE3(robot.tool, check=False))
    ets = arm.ets()
    q = robot.qlim.mean(axis=0) + 0.1
    assert np.allclose(ets.fkine(q).A, robot.fkine(q), atol=1e-12), robot.name
    return ets


def measured(ets, T: np.ndarray, q: np.ndarray,  # type: ignore[no-untyped-def]
             lim: np.ndarray) -> tuple[bool, float, float]:
    """Does ``q`` reach ``T`` to IK_TOL, by the Toolbox's fkine, within ``lim``?
    Returns (ok, position error m, rotation angle rad)."""
    if q is None or not np.all(np.isfinite(q)):
        return False, math.inf, math.inf
    Tq = ets.fkine(q).A
    pe = float(np.linalg.norm(Tq[:3, 3] - T[:3, 3]))
    re = 2.0 * math.asin(min(1.0, float(np.linalg.norm(Tq[:3, :3] - T[:3, :3])) / math.sqrt(8.0)))
    inside = bool(np.all(q >= lim[0] - 1e-12) and np.all(q <= lim[1] + 1e-12))
    return pe < IK_TOL and re < IK_TOL and inside, pe, re


def solvers(rtb, robot, ets):  # type: ignore[no-untyped-def]
    """name -> f(T) returning (claimed success, q)."""
    out = {"ejsrl ikine": lambda T: _sol(robot.ikine(T)),
           "ejsrl ikine, LM only (closed_form=False)": lambda T: _sol(robot.ikine(T, closed_form=False))}
    if rtb is not None:
        out["RTB C++ ETS.ik_LM"] = lambda T: _sol(ets.ik_LM(T, tol=RTB_TOL, joint_limits=True))
        out["RTB Python ETS.ikine_LM"] = lambda T: _sol(ets.ikine_LM(T, tol=RTB_TOL, joint_limits=True, seed=0))
    return out


def _sol(s) -> tuple[bool, np.ndarray]:  # type: ignore[no-untyped-def]
    return bool(s.success), np.asarray(s.q, dtype=float)


def run_targets(fs: dict, targets: np.ndarray, ets,  # type: ignore[no-untyped-def]
                lim: np.ndarray, limits: dict[str, int]) -> dict:
    """Time every solver on every target, interleaved (solver order rotated per target).
    ``limits``: solver name -> number of targets it gets (the slow Python solver)."""
    names = list(fs)
    res = {name: {"t": [], "cpu": [], "claimed": 0, "ok": 0, "inside": 0, "n": 0, "worst_p": 0.0, "worst_r": 0.0}
           for name in names}
    for i, T in enumerate(targets):
        order = names[i % len(names):] + names[: i % len(names)]
        for name in order:
            if i >= limits.get(name, len(targets)):
                continue
            c0 = time.thread_time()
            t0 = time.perf_counter()
            claimed, q = fs[name](T)
            dt = time.perf_counter() - t0
            dc = time.thread_time() - c0
            ok, pe, re = measured(ets, T, q, lim)
            r = res[name]
            r["t"].append(dt)
            r["cpu"].append(dc)
            r["n"] += 1
            r["claimed"] += claimed
            r["ok"] += claimed and ok
            r["inside"] += bool(np.all(q >= lim[0] - 1e-12) and np.all(q <= lim[1] + 1e-12)) if claimed else 0
            if claimed:
                r["worst_p"], r["worst_r"] = max(r["worst_p"], pe), max(r["worst_r"], re)
    return res


FAST = ("ejsrl ikine", "RTB C++ ETS.ik_LM")


def paired(fs: dict, targets: np.ndarray, ets, lim: np.ndarray, n_py: int) -> dict:  # type: ignore[no-untyped-def]
    """Two interleaved passes, each pairing an ejsrl path with the Toolbox path it is
    compared with: ``ikine`` with the C++ ``ik_LM``, then the LM-only path with the Python
    ``ikine_LM`` (on the first ``n_py`` targets; none when 0). A slow solver run in between
    evicts the other's code and data from the caches and slows both (measured on a loaded
    machine: ejsrl's ikine 1.7x, the C++ solver 1.3x)."""
    res = run_targets({k: v for k, v in fs.items() if k in FAST}, targets, ets, lim, {})
    rest = {k: v for k, v in fs.items() if k not in FAST and (n_py > 0 or "Python" not in k)}
    res.update(run_targets(rest, targets, ets, lim, {"RTB Python ETS.ikine_LM": n_py}))
    return res


def ik_bench(args: argparse.Namespace, rtb) -> None:  # type: ignore[no-untyped-def]
    """Part 2: inverse kinematics on Puma 560, UR5 and PA-10 (closed-form families), then
    the Panda, KR5, IRB140, LBR iiwa, UR10 and a random 6R (see the module docstring)."""
    from ejsrl.robotics import _ik_fast

    if _ik_fast.BACKEND == "auto" and _ik_fast.LOADER.get(wait=True) is not None:
        _ik_fast.BACKEND = "numba"  # time the compiled searches, not the first calls' Python ones
    print(f"\nejsrl's LM searches: {'compiled (numba)' if _ik_fast.module() is not None else 'Python'}")
    arms = [models.puma560(), models.ur5(), models.pa10(), models.panda(), models.kr5(), models.irb140(),
            models.lbr_iiwa(), models.ur10(), models.random_arm(6, seed=0)]
    if args.arms:
        arms = [r for r in arms if any(a.lower() in r.name.lower() for a in args.arms.split(","))]
    targets_met: list[tuple[bool, str]] = []
    print(f"\nInverse kinematics, {args.n_ik} random reachable targets per arm, every solver to {IK_TOL:g} m and rad "
          f"(Toolbox tol = {RTB_TOL:g} on E), accuracy by the Toolbox's fkine; times interleaved; "
          f"the Python ikine_LM gets the first {args.n_py} targets")
    if rtb is None:
        print("  (Robotics Toolbox missing: only ejsrl is timed)")
    for robot in arms:
        ets = rtb_arm(rtb, robot) if rtb is not None else None
        lim = robot.qlim
        rng = np.random.default_rng(14)
        robot.ikine(robot.fkine(robot.qz))  # generate the arm's code once
        robot.ikine(robot.fkine(robot.qz), closed_form=False)
        closed = _ik_closed.solver(robot) is not None
        fs = solvers(rtb, robot, ets)
        if ets is None:
            ets = _OwnFkine(robot)
        targets = robot.fkine(rng.uniform(lim[0], lim[1], (args.n_ik, robot.n)))
        # two interleaved passes, each pairing an ejsrl path with the Toolbox path it is
        # compared with: a slow solver run in between evicts the other's code and data from
        # the caches and slows both (measured: ejsrl 1.7x, the C++ solver 1.3x)
        res = paired(fs, targets, ets, lim, args.n_py)
        print(f"\n{robot.name} ({robot.n} joints)")
        print(f"  {'solver':<42} {'median':>9} {'mean':>9} {'p95':>9} {'CPU med.':>9}  {'success (verified)':>22} "
              f"{'in limits':>9} {'worst pos / rot error':>22}")
        for name, r in res.items():
            t = np.array(r["t"])
            print(f"  {name:<42} {fmt(float(np.median(t))):>9} {fmt(float(t.mean())):>9} "
                  f"{fmt(float(np.percentile(t, 95))):>9} {fmt(float(np.median(r['cpu']))):>9}  "
                  f"{r['ok']:>5}/{r['n']} ({r['ok'] / r['n'] * 100:5.1f} %)"
                  f"{'':>3} {r['inside']:>5}/{r['claimed']}  {r['worst_p']:.1e} / {r['worst_r']:.1e}")
        ours = res["ejsrl ikine"]
        med = float(np.median(ours["t"]))
        if "RTB C++ ETS.ik_LM" in res:
            cpp = float(np.median(res["RTB C++ ETS.ik_LM"]["t"]))
            py_t = res.get("RTB Python ETS.ikine_LM", {}).get("t") or [math.nan]
            py = float(np.median(py_t))
            cpu = float(np.median(res["RTB C++ ETS.ik_LM"]["cpu"])) / float(np.median(ours["cpu"]))
            print(f"  ratio (Toolbox median / ejsrl median): C++ ik_LM {cpp / med:.2f}x (CPU time {cpu:.2f}x), "
                  f"Python ikine_LM {py / med:.2f}x (on its {len(py_t) if py == py else 0} targets)")
            targets_met.append((med < cpp, f"{robot.name}: median ikine below the Toolbox's C++ ik_LM: "
                                           f"{fmt(med)} vs {fmt(cpp)} ({cpp / med:.2f}x)"))
            mean_o = float(np.mean(ours["cpu"]))
            mean_c = float(np.mean(res["RTB C++ ETS.ik_LM"]["cpu"]))
            targets_met.append((mean_o < mean_c, f"{robot.name}: mean ikine CPU time below the Toolbox's C++ ik_LM: "
                                                 f"{fmt(mean_o)} vs {fmt(mean_c)} ({mean_c / mean_o:.2f}x)"))
        rate = ours["ok"] / ours["n"]
        targets_met.append((rate >= 0.999, f"{robot.name}: success >= 99.9 % (verified): {rate * 100:.1f} %"))
        targets_met.append((ours["inside"] == ours["claimed"],
                            f"{robot.name}: every answer within the joint limits: {ours['inside']}/{ours['claimed']}"))

        # at and near the wrist singularity
        wrist = [4] if robot.n == 6 else [4, 5]
        n_s = max(20, args.n_ik // 5)
        for j in wrist:
            for q5 in (0.0, 1e-7, 1e-4):
                Q = rng.uniform(lim[0], lim[1], (n_s, robot.n))
                Q[:, j] = q5
                sres = paired(fs, robot.fkine(Q), ets, lim, 0)
                cells = "; ".join(f"{k} {r['ok']}/{r['n']} ({fmt(float(np.median(r['t'])))})" for k, r in sres.items())
                print(f"  q{j + 1} = {q5:g}: {cells}")
                o = sres["ejsrl ikine"]
                targets_met.append((o["ok"] == o["n"], f"{robot.name}: q{j + 1} = {q5:g}: {o['ok']}/{o['n']}"))

        # unreachable: beyond the reach bound (3 m away), and inside it but outside the
        # workspace (a horizontal ring at 0.95 of the sum of the link lengths)
        bound = sum(math.hypot(k.a, k.d) for k in robot.links)
        angles = np.linspace(0, 2 * math.pi, 20, endpoint=False)
        for label, pts in (("3 m away", [3.0 * np.array([math.cos(a), math.sin(a), 0.3]) for a in angles]),
                           (f"{0.95 * bound:.2f} m away, horizontal",
                            [0.95 * bound * np.array([math.cos(a), math.sin(a), 0.0]) for a in angles])):
            ures = paired(fs, np.array([transl_np(p) for p in pts]), ets, lim, 0)
            cells = "; ".join(f"{k}: {r['n'] - r['claimed']}/{r['n']} rejected, "
                              f"median {fmt(float(np.median(r['t'])))}, max {fmt(float(np.max(r['t'])))} "
                              f"(CPU max {fmt(float(np.max(r['cpu'])))})"
                              for k, r in ures.items())
            print(f"  unreachable ({label}): {cells}")
            o = ures["ejsrl ikine"]
            cmax = float(np.max(o["cpu"]))
            limit = 2e-3 if closed else 5e-3
            targets_met.append((o["claimed"] == 0 and cmax <= limit,
                                f"{robot.name}: unreachable ({label}) rejected in <= {limit * 1e3:g} ms: "
                                f"{o['n'] - o['claimed']}/{o['n']}, slowest {fmt(cmax)} CPU "
                                f"({fmt(float(np.max(o['t'])))} wall)"))
    print("\nIK targets:")
    for met, text in targets_met:
        print(f"  {'MET    ' if met else 'NOT MET'} {text}")


class _OwnFkine:
    """Stands in for the Toolbox's ETS when it is missing (accuracy then by ejsrl's fkine)."""

    def __init__(self, robot) -> None:  # type: ignore[no-untyped-def]
        self.robot = robot

    def fkine(self, q):  # type: ignore[no-untyped-def]
        class _T:
            A = self.robot.fkine(q)

        return _T


def transl_np(p: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = p
    return T


def fmt(t: float) -> str:
    if t < 1e-3:
        return f"{t * 1e6:.1f} us"
    if t < 1:
        return f"{t * 1e3:.2f} ms"
    return f"{t:.2f} s"


if __name__ == "__main__":
    main()
