"""The mobile-robot labs run headless, as a teacher's CSV export sees them: the car-like
robot ends on the goal pose it was given (ahead of it, beside it, behind it: in reverse),
within the speed and steering limits; EKF localisation reproduces the library's filter
driven the same way (same seeds), keeps its error within its covariance, and drifts
when its sensor is off."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from testkit import run_app


def _csv(path) -> dict[str, np.ndarray]:  # type: ignore[no-untyped-def]
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


@pytest.mark.parametrize(("gx", "gy", "heading"), [(5.0, 3.0, 90.0), (-8.0, -3.0, 180.0), (-2.0, 5.0, -45.0)])
def test_car_lab_ends_on_the_goal_pose(built, tmp_path, gx: float, gy: float, heading: float) -> None:  # type: ignore[no-untyped-def]
    app = built("mobile_car_to_pose")
    out = tmp_path / "run.csv"
    r = run_app(app, "--headless", "--duration", "40", "--csv", str(out), "--vars", "t,x,y,theta,v,gamma",
                "--set", f"gx={gx}", "--set", f"gy={gy}", "--set", f"goal_heading={heading}")
    assert r.returncode == 0, r.stderr
    d = _csv(out)
    assert math.hypot(d["x"][-1] - gx, d["y"][-1] - gy) < 1e-3
    assert abs((d["theta"][-1] - math.radians(heading) + math.pi) % (2 * math.pi) - math.pi) < 1e-3
    assert np.abs(d["v"]).max() <= 2.0 + 1e-12 and np.abs(d["gamma"]).max() <= 0.7 + 1e-12
    if gx < -6.0:  # the goal is behind the start (-6, -3, heading 0): it backs up to it
        assert d["v"][1] < 0


def test_ekf_lab_matches_the_library_and_its_covariance(built, tmp_path) -> None:  # type: ignore[no-untyped-def]
    from ejsrl.mobile import EKF, Bicycle, LandmarkMap, RangeBearingSensor

    app = built("mobile_ekf_localisation")
    out = tmp_path / "run.csv"
    r = run_app(app, "--headless", "--duration", "40", "--csv", str(out), "--vars", "t,xt,xe,P,err,sigma,seen")
    assert r.returncode == 0, r.stderr
    d = _csv(out)
    # the same filter, written directly against ejsrl.mobile
    lm = np.array([[2.74, -9.43], [-4.6, -7.51], [-9.18, 3.41], [-9.67, 2.94], [6.27, 2.31], [8.26, -2.33], [2.13, 9.94],
                   [4.59, 9.62], [0.87, 3.71], [8.7, 3.01], [6.32, 3.77], [-9.95, -2.22], [7.15, -7.3], [-9.33, 4.43],
                   [4.59, 0.51], [-6.49, -3.8], [7.26, -0.28], [0.83, 7.79], [-4.01, 8.68], [-1.55, -2.84]])
    V = np.diag([0.02, math.radians(0.5)]) ** 2
    W = np.diag([0.1, math.radians(1.0)]) ** 2
    veh = Bicycle(L=1.0, covar=V, x0=[0, -6, 0], dt=0.1, seed=1)
    sensor = RangeBearingSensor(veh, LandmarkMap(lm.T), covar=W, range=8.0, angle=math.pi / 2, seed=2)
    ekf = EKF(robot=(veh, V), P0=np.diag([0.05, 0.05, math.radians(0.5)]) ** 2, x0=[0, -6, 0], map=LandmarkMap(lm.T),
              sensor=(sensor, W))
    xe = [ekf.x_est[:3].copy()]
    for _ in range(400):
        ekf.predict(veh.step([1.0, 0.15]))
        z, k = sensor.reading()
        ekf.update(z, k)
        xe.append(ekf.x_est[:3].copy())
    lab_xe = np.column_stack([d["xe[0]"], d["xe[1]"], d["xe[2]"]])
    np.testing.assert_allclose(lab_xe, np.array(xe), atol=1e-9)
    # the error stays within the 3-sigma ellipse of the filter's own covariance
    e = np.column_stack([d["xt[0]"] - d["xe[0]"], d["xt[1]"] - d["xe[1]"]])
    P = np.stack([np.array([[a, b], [c, dd]]) for a, b, c, dd in zip(d["P[0][0]"], d["P[0][1]"], d["P[1][0]"], d["P[1][1]"])])
    m2 = np.einsum("ni,nij,nj->n", e, np.linalg.inv(P), e)
    assert np.mean(m2 < 11.8) > 0.95  # chi-squared, 2 dof, 99.7 %
    assert d["err"].max() < 0.25 and (d["seen"] >= 0).mean() > 0.9


def test_ekf_lab_drifts_without_its_sensor(built, tmp_path) -> None:  # type: ignore[no-untyped-def]
    app = built("mobile_ekf_localisation")
    out = tmp_path / "run.csv"
    r = run_app(app, "--headless", "--duration", "40", "--csv", str(out), "--vars", "t,err,sigma,seen",
                "--set", "sensor_on=False")
    assert r.returncode == 0, r.stderr
    d = _csv(out)
    assert (d["seen"] < 0).all()
    assert d["sigma"][-1] > 5 * d["sigma"][0]  # dead reckoning: the uncertainty only grows
    assert np.all(np.diff(d["sigma"]) > -1e-12)


def test_dstar_lab_drives_to_the_goal_clear_of_obstacles(built, tmp_path) -> None:  # type: ignore[no-untyped-def]
    app = built("mobile_dstar_replanning")
    out = tmp_path / "run.csv"
    r = run_app(app, "--headless", "--duration", "30", "--csv", str(out), "--vars", "t,x,y,cost,expanded")
    assert r.returncode == 0, r.stderr
    d = _csv(out)
    # the first plan: the shortest 8-connected path on the walls and blocks grown by a cell
    from test_planners import grid_dijkstra

    walls = np.zeros((20, 30), dtype=bool)
    walls[0, :] = walls[-1, :] = walls[:, 0] = walls[:, -1] = True
    walls[0:11, 11] = True
    walls[9:20, 19] = True
    occ = walls.copy()
    for c, rr in ((6, 8), (15, 4), (24, 14)):
        occ[rr - 1:rr + 2, c - 1:c + 2] = True
    grown = occ.copy()
    grown[1:, :] |= occ[:-1, :]
    grown[:-1, :] |= occ[1:, :]
    g2 = grown.copy()
    g2[:, 1:] |= grown[:, :-1]
    g2[:, :-1] |= grown[:, 1:]
    assert d["cost"][0] == pytest.approx(grid_dijkstra(g2, (27, 17))[2, 2], abs=1e-9)
    # it arrives in the goal's cell and never drives through an obstacle cell
    assert math.hypot(d["x"][-1] - 27.0, d["y"][-1] - 17.0) < 0.71
    cells = np.round(np.column_stack([d["x"], d["y"]])).astype(int)
    assert not occ[cells[:, 1], cells[:, 0]].any()


def test_slam_lab_maps_every_landmark_and_closing_the_loop_shrinks_the_error(built, tmp_path) -> None:  # type: ignore[no-untyped-def]
    app = built("mobile_ekf_slam")
    out = tmp_path / "run.csv"
    r = run_app(app, "--headless", "--duration", "80", "--csv", str(out), "--vars", "t,nmapped,map_error", "--every", "10")
    assert r.returncode == 0, r.stderr
    d = _csv(out)
    assert d["nmapped"][-1] == 20 and np.all(np.diff(d["nmapped"]) >= 0)
    worst = d["map_error"][(d["t"] > 20) & (d["t"] < 50)].max()  # before the loop closes
    assert d["map_error"][-1] < 0.15 and d["map_error"][-1] < 0.5 * worst


def test_particle_filter_lab_converges_on_the_car(built, tmp_path) -> None:  # type: ignore[no-untyped-def]
    app = built("mobile_particle_filter")
    out = tmp_path / "run.csv"
    r = run_app(app, "--headless", "--duration", "20", "--csv", str(out), "--vars", "t,spread,err,xt,xe", "--every", "10")
    assert r.returncode == 0, r.stderr
    d = _csv(out)
    assert d["spread"][0] > 4.0  # spread over the 20 m map
    late = d["t"] > 10
    assert d["spread"][late].max() < 0.5 and d["err"][late].max() < 0.3
    np.testing.assert_allclose(d["err"], np.hypot(d["xe[0]"] - d["xt[0]"], d["xe[1]"] - d["xt[1]"]), atol=1e-12)
