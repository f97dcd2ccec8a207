"""Benchmark ejsrl.mobile against the Robotics Toolbox for Python: planners and filters on
the same inputs, interleaved call by call in one process (CPU time, median of repeats),
with a check that both give the same answer first.

- distance-transform planner on the Toolbox's house floor plan (397 x 596 cells), kitchen
  to bedroom 3: the paths must be equal; the distance maps are compared too (the Toolbox
  stops its grassfire once no cell is newly reached, which can leave cells above their
  shortest distance; ejsrl iterates until nothing changes);
- D* on a 150 x 200 cell crop of the house (the Toolbox's D* takes ~10 s on the whole
  house): the path lengths must be equal;
- EKF localisation and EKF-SLAM, 100 s at 10 Hz (1,000 steps, 20 landmarks) with the same
  seeds: the final estimates must be equal;
- PRM (300 points) on the house: random on both sides, compared by path length;
- the lattice planner on a 40 x 40 cell sample of the house (the whole lattice, then 20
  queries): the path costs must be equal;
- pose-graph optimisation of the Toolbox's killian-small.toro: the optimised poses compared;
- a particle filter (1,000 particles, uniform start, 20 s): random, so compared by the
  median final error over seeds;
- a vehicle (Bicycle) stepped 1,000 times with odometry noise.

Needs the ``bench`` extra (``pip install roboticstoolbox-python``). Options: ``--repeat N``
(default 5). Prints the load average beside the figures: rerun on a quiet machine.
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
    import ejsrl.mobile  # noqa: F401
except ImportError:  # run from a checkout without installing
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "runtime"))

from ejsrl import mobile as M  # noqa: E402


def cpu(f: Callable[[], object]) -> tuple[float, object]:
    c0 = time.process_time()
    out = f()
    return time.process_time() - c0, out


def interleaved(pairs: dict[str, Callable[[], object]], repeat: int) -> dict[str, tuple[float, object]]:
    """Median CPU time of each function, called in turn (order rotated each round)."""
    names = list(pairs)
    times: dict[str, list[float]] = {k: [] for k in names}
    last: dict[str, object] = {}
    for i in range(repeat):
        for name in names[i % len(names):] + names[:i % len(names)]:
            t, out = cpu(pairs[name])
            times[name].append(t)
            last[name] = out
    return {k: (float(np.median(v)), last[k]) for k, v in times.items()}


def fmt(t: float) -> str:
    return f"{t * 1e3:9.2f} ms" if t < 1 else f"{t:9.2f} s "


def report(title: str, res: dict[str, tuple[float, object]], same: str) -> float:
    (a, ta), (b, tb) = ((k, v[0]) for k, v in res.items())
    print(f"\n{title}\n  {a:<34} {fmt(ta)}\n  {b:<34} {fmt(tb)}\n  ratio (Toolbox / ejsrl): {ta / tb if 'Toolbox' in a else tb / ta:.2f}x;"
          f" {same}")
    return ta / tb if "Toolbox" in a else tb / ta


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    import roboticstoolbox as rtb

    load0 = os.getloadavg()
    met: list[tuple[bool, str]] = []
    house = rtb.rtb_load_matfile("data/house.mat")
    floor, places = house["floorplan"], house["places"]
    goal, start = places["kitchen"], places["br3"]

    # distance transform
    og, ours = rtb.BinaryOccupancyGrid(floor), M.BinaryOccupancyGrid(floor)

    def dt_rtb():  # type: ignore[no-untyped-def]
        p = rtb.DistanceTransformPlanner(occgrid=og, metric="euclidean")
        p.plan(goal=goal)
        return p, p.query(start=start)

    def dt_ours():  # type: ignore[no-untyped-def]
        p = M.DistanceTransformPlanner(ours)
        p.plan(goal)
        return p, p.query(start)

    res = interleaved({"Toolbox DistanceTransformPlanner": dt_rtb, "ejsrl DistanceTransformPlanner": dt_ours},
                      args.repeat)
    (pr, path_r), (po, path_o) = res["Toolbox DistanceTransformPlanner"][1], res["ejsrl DistanceTransformPlanner"][1]
    equal = np.array_equal(path_r, path_o)
    A, B = pr.distancemap, po.distancemap
    fin = np.isfinite(A) & np.isfinite(B)
    above = int((A[fin] - B[fin] > 1e-3).sum())
    r = report("Distance transform, house 397 x 596, kitchen -> br3 (plan + query)", res,
               f"paths equal: {equal} ({len(path_o)} cells, {M.path_length(path_o):.2f} m); Toolbox distances above the "
               f"shortest at {above} cells (by up to {np.max(A[fin] - B[fin]):.1f})")
    met += [(equal, "distance transform: the same path as the Toolbox"), (r > 1, f"distance transform faster: {r:.2f}x")]

    # D* on a crop
    crop = floor[:150, :200]
    g2, s2 = (150, 100), (20, 20)
    ogc, oursc = rtb.BinaryOccupancyGrid(crop), M.BinaryOccupancyGrid(crop)

    def ds_rtb():  # type: ignore[no-untyped-def]
        p = rtb.DstarPlanner(occgrid=ogc)
        p.plan(goal=g2)
        out = p.query(start=s2)
        return out[0] if isinstance(out, tuple) else out

    def ds_ours():  # type: ignore[no-untyped-def]
        p = M.DstarPlanner(oursc.copy())
        p.plan(g2)
        return p.query(s2)

    res = interleaved({"Toolbox DstarPlanner": ds_rtb, "ejsrl DstarPlanner (D* Lite)": ds_ours}, max(1, args.repeat // 2))
    lr, lo = M.path_length(res["Toolbox DstarPlanner"][1]), M.path_length(res["ejsrl DstarPlanner (D* Lite)"][1])
    r = report("D*, house crop 150 x 200 (plan + query)", res, f"path lengths {lr:.4f} m and {lo:.4f} m")
    met += [(abs(lr - lo) < 1e-9, "D*: paths of the same length"), (r > 1, f"D* faster: {r:.2f}x")]

    # PRM on the house (random: both sample their own points; compared by path length)
    def prm_rtb():  # type: ignore[no-untyped-def]
        p = rtb.PRMPlanner(occgrid=og, npoints=300, seed=0)
        p.plan()
        return p.query(start=start, goal=goal)

    def prm_ours():  # type: ignore[no-untyped-def]
        p = M.PRMPlanner(ours, npoints=300, seed=0)
        p.plan()
        return p.query(start, goal)

    res = interleaved({"Toolbox PRMPlanner (300 points)": prm_rtb, "ejsrl PRMPlanner (300 points)": prm_ours},
                      max(1, args.repeat // 2))
    lr = M.path_length(res["Toolbox PRMPlanner (300 points)"][1])
    lo = M.path_length(res["ejsrl PRMPlanner (300 points)"][1])
    r = report("PRM, house, kitchen -> br3 (plan + query)", res,
               f"path lengths {lr:.1f} m and {lo:.1f} m (the grid's shortest: {M.path_length(path_o):.1f} m)")
    met += [(r > 1, f"PRM faster: {r:.2f}x")]

    # lattice planner: the whole lattice on a 40 x 40 m crop of the house at 1 m a cell (the
    # Toolbox's lattice is a pgraph graph), then 20 queries from the root; equal costs
    import contextlib
    import io

    lat = floor[100:300:5, 100:300:5].astype(bool)  # every 5th cell of a 200 x 200 crop
    lat[20, 20] = False
    ogl = rtb.BinaryOccupancyGrid(lat, cellsize=1.0, origin=(-20, -20))
    oursl = M.BinaryOccupancyGrid(lat, cellsize=1.0, origin=(-20, -20))
    probe = M.LatticePlanner(oursl)
    probe.plan()
    goals = probe.vertices[np.random.default_rng(0).choice(len(probe.vertices), 20, replace=False)]

    def lat_rtb():  # type: ignore[no-untyped-def]
        p = rtb.LatticePlanner(occgrid=ogl)
        with contextlib.redirect_stdout(io.StringIO()):  # it prints every iteration
            p.plan()
        return [p.query(start=(0, 0, 0), goal=g)[1].cost for g in goals]

    def lat_ours():  # type: ignore[no-untyped-def]
        p = M.LatticePlanner(oursl)
        p.plan()
        return [p.query((0, 0, 0), g)[1].cost for g in goals]

    res = interleaved({"Toolbox LatticePlanner": lat_rtb, "ejsrl LatticePlanner": lat_ours}, max(1, args.repeat // 2))
    cr, co = np.array(res["Toolbox LatticePlanner"][1]), np.array(res["ejsrl LatticePlanner"][1])
    same = bool(np.allclose(cr, co, atol=1e-9))
    r = report(f"Lattice planner, house 40 x 40 m at 1 m ({len(probe.vertices)} poses; plan + 20 queries)", res,
               f"path costs equal: {same}")
    met += [(same, "lattice: the Toolbox's path costs"), (r > 1, f"lattice planner faster: {r:.2f}x")]

    # pose graph: the Toolbox's killian-small.toro (1,941 poses, 3,995 edges), Gauss-Newton
    import rtbdata

    toro = str(Path(rtbdata.__file__).parent / "data" / "killian-small.toro")

    def pg_rtb():  # type: ignore[no-untyped-def]
        g = rtb.PoseGraph(toro)
        g.optimize()
        return np.array([g.pose(i) for i in range(g.graph.n)])

    def pg_ours():  # type: ignore[no-untyped-def]
        g = M.PoseGraph.load(toro)
        g.optimize()
        return g.poses

    res = interleaved({"Toolbox PoseGraph.optimize": pg_rtb, "ejsrl PoseGraph.optimize": pg_ours},
                      max(1, args.repeat // 2))
    dmax = float(np.abs(res["Toolbox PoseGraph.optimize"][1] - res["ejsrl PoseGraph.optimize"][1]).max())
    r = report("Pose graph, killian-small.toro (load + optimise)", res,
               f"largest difference of the optimised poses {dmax:.1e} (m, rad; sums in another order)")
    met += [(dmax < 1e-3, f"pose graph: the Toolbox's poses within {dmax:.1e}"), (r > 1, f"pose graph faster: {r:.2f}x")]

    # EKF
    V = np.diag([0.02, math.radians(0.5)]) ** 2
    W = np.diag([0.1, math.radians(1.0)]) ** 2
    P0 = np.diag([0.05, 0.05, math.radians(0.5)]) ** 2

    def drive(veh, t, x):  # type: ignore[no-untyped-def]
        return (1.0, 0.25 * math.sin(0.3 * t))

    for kind in ("localisation", "SLAM"):
        def ekf_rtb():  # type: ignore[no-untyped-def]
            lm = rtb.LandmarkMap(20, workspace=10, seed=0)
            veh = rtb.Bicycle(covar=V, control=drive, animation=None, seed=1)
            sensor = rtb.RangeBearingSensor(robot=veh, map=lm, covar=W, range=8, angle=math.pi / 2, seed=0,
                                            animate=False)
            e = rtb.EKF(robot=(veh, V), P0=P0, map=lm if kind == "localisation" else None, sensor=(sensor, W),
                        animate=False)
            e.run(T=100)
            return e.x_est

        def ekf_ours():  # type: ignore[no-untyped-def]
            lm = M.LandmarkMap(20, workspace=10, seed=0)
            veh = M.Bicycle(covar=V, control=drive, seed=1)
            sensor = M.RangeBearingSensor(veh, lm, covar=W, range=8, angle=math.pi / 2, seed=0)
            e = M.EKF(robot=(veh, V), P0=P0, map=lm if kind == "localisation" else None, sensor=(sensor, W))
            e.run(100)
            return e.x_est

        res = interleaved({f"Toolbox EKF {kind}": ekf_rtb, f"ejsrl EKF {kind}": ekf_ours}, args.repeat)
        xr, xo = res[f"Toolbox EKF {kind}"][1], res[f"ejsrl EKF {kind}"][1]
        same = xr.shape == xo.shape and bool(np.allclose(xr, xo, atol=1e-9))
        r = report(f"EKF {kind}, 1,000 steps, 20 landmarks", res, f"final estimates equal: {same} (state {xo.shape[0]})")
        met += [(same, f"EKF {kind}: the Toolbox's estimate"), (r > 1, f"EKF {kind} faster: {r:.2f}x")]

    # particle filter: random, so compared by its error over seeds, not bit for bit
    R = np.diag([0.1, 0.1, math.radians(1.0)]) ** 2
    Lk = np.diag([0.1, 0.1])
    errs: dict[str, list[float]] = {"Toolbox ParticleFilter": [], "ejsrl ParticleFilter": []}

    def pf_run(lib: str, seed: int):  # type: ignore[no-untyped-def]
        def run():  # type: ignore[no-untyped-def]
            mod = rtb if lib == "Toolbox ParticleFilter" else M
            lm = mod.LandmarkMap(20, workspace=10, seed=0)
            if mod is rtb:
                veh = rtb.Bicycle(covar=V, control=lambda v, t, x: (1.0, 0.15), animation=None, seed=1)
                sensor = rtb.RangeBearingSensor(robot=veh, map=lm, covar=W, seed=0, animate=False)
                pf = rtb.ParticleFilter(veh, sensor, R, Lk, nparticles=1000, seed=seed)
                pf.run(T=20)
            else:
                veh = M.Bicycle(covar=V, control=lambda v, t, x: (1.0, 0.15), seed=1)
                sensor = M.RangeBearingSensor(veh, lm, covar=W, seed=0)
                pf = M.ParticleFilter(veh, sensor, R, Lk, nparticles=1000, seed=seed)
                pf.run(20)
            e = pf.get_xyt()[-1]
            errs[lib].append(math.hypot(e[0] - veh.x[0], e[1] - veh.x[1]))
        return run

    times = {k: [] for k in errs}
    for seed in range(args.repeat):
        for lib in (list(errs) if seed % 2 == 0 else list(errs)[::-1]):
            times[lib].append(cpu(pf_run(lib, seed))[0])
    res = {k: (float(np.median(v)), None) for k, v in times.items()}
    er, eo = (float(np.median(errs[k])) for k in errs)
    r = report("Particle filter, 1,000 particles from a uniform start, 200 steps", res,
               f"median final position error over {args.repeat} seeds: {er:.3f} m and {eo:.3f} m")
    met += [(eo < 0.3, f"particle filter localises the car: {eo:.3f} m"), (r > 1, f"particle filter faster: {r:.2f}x")]

    def veh_rtb():  # type: ignore[no-untyped-def]
        v = rtb.Bicycle(covar=V, control=drive, animation=None, seed=1)
        v.init()
        for _ in range(1000):
            v.step(animate=False)
        return v.x

    def veh_ours():  # type: ignore[no-untyped-def]
        v = M.Bicycle(covar=V, control=drive, seed=1)
        for _ in range(1000):
            v.step()
        return v.x

    res = interleaved({"Toolbox Bicycle.step x 1000": veh_rtb, "ejsrl Bicycle.step x 1000": veh_ours}, args.repeat)
    same = bool(np.array_equal(res["Toolbox Bicycle.step x 1000"][1], res["ejsrl Bicycle.step x 1000"][1]))
    r = report("Vehicle, 1,000 noisy steps", res, f"final poses equal: {same}")
    met += [(same, "vehicle: the Toolbox's poses"), (r > 1, f"vehicle steps faster: {r:.2f}x")]

    print("\nTargets:")
    for ok, text in met:
        print(f"  {'MET    ' if ok else 'NOT MET'} {text}")
    load1 = os.getloadavg()
    print(f"\nload average (1, 5, 15 min) at start {', '.join(f'{x:.1f}' for x in load0)}, at end "
          f"{', '.join(f'{x:.1f}' for x in load1)} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
