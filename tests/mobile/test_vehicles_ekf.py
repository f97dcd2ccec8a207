"""Vehicles and the EKF against the Robotics Toolbox on the same inputs and seeds: the same
odometry noise, the same poses, the same estimates and covariances (EKF localisation and
EKF-SLAM), and the same random landmark map."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ejsrl import mobile as M


def _vehicle(name: str, inputs):  # type: ignore[no-untyped-def]
    V = np.array(inputs.V)
    if name == "bicycle":
        return M.Bicycle(L=2.0, steer_max=0.5, covar=V, x0=[1, 2, 0.3], seed=3, control=inputs.control("bicycle"))
    if name == "unicycle":
        return M.Unicycle(covar=V, x0=[0, 0, 1.0], seed=4, control=inputs.control("unicycle"))
    return M.DiffSteer(W=0.5, covar=V, seed=5, control=inputs.control("diffsteer"))


@pytest.mark.parametrize("name", ["bicycle", "unicycle", "diffsteer"])
def test_vehicle_steps_equal_the_toolbox(name: str, rtb_ref, inputs) -> None:  # type: ignore[no-untyped-def]
    ref = rtb_ref["vehicles"][name]
    veh = _vehicle(name, inputs)
    xs, odos = [], []
    for _ in range(150):
        odos.append(veh.step())
        xs.append(veh.x.copy())
    np.testing.assert_allclose(xs, ref["x"], atol=1e-12, rtol=0)
    np.testing.assert_allclose(odos, ref["odo"], atol=1e-12, rtol=0)
    # init() starts over with the same noise
    veh.init()
    np.testing.assert_allclose(veh.step(), ref["odo"][0], atol=1e-12, rtol=0)


def test_bicycle_steering_limit_and_turning_circle() -> None:
    """Full lock at constant speed drives a circle of radius L / tan(steer_max)."""
    car = M.Bicycle(L=2.5, steer_max=0.4, dt=0.001)
    assert car.radius_min == pytest.approx(2.5 / math.tan(0.4))
    xs = car.run(2 * math.pi * car.radius_min, u=(1.0, 1.5))  # asks for 1.5 rad: clipped to 0.4
    R = car.radius_min
    centre = np.array([0.0, R])
    r = np.hypot(*(xs[:, :2] - centre).T)
    assert np.abs(r - R).max() < 2e-3 * R  # Euler at dt = 1 ms
    assert np.hypot(*(xs[-1, :2] - xs[0, :2])) < 0.01 * R  # back where it started
    # deriv is the ODE a spec integrates
    np.testing.assert_allclose(car.deriv([0, 0, 0.3], [2.0, 0.2]), 2.0 * np.array([math.cos(0.3), math.sin(0.3),
                                                                                   math.tan(0.2) / 2.5]))


def test_omni_moves_sideways_in_its_own_frame() -> None:
    base = M.Omni(speed_max=1.0)
    np.testing.assert_allclose(base.deriv([0, 0, math.pi / 2], [0.0, 2.0, 0.1]), [-1.0, 0.0, 0.1], atol=1e-12)


def test_landmark_map_equals_the_toolbox(rtb_ref) -> None:  # type: ignore[no-untyped-def]
    np.testing.assert_allclose(M.LandmarkMap(20, workspace=10, seed=0).landmarks, rtb_ref["landmarks"], rtol=0, atol=0)


@pytest.mark.parametrize("kind", ["localisation", "slam"])
def test_ekf_equals_the_toolbox_with_the_same_noise(kind: str, rtb_ref, inputs) -> None:  # type: ignore[no-untyped-def]
    ref = rtb_ref[kind]
    V, W, P0 = (np.array(v) for v in (inputs.V, inputs.W, inputs.P0))
    lm = M.LandmarkMap(20, workspace=10, seed=0)
    veh = M.Bicycle(covar=V, control=inputs.control("ekf"), seed=1)
    sensor = M.RangeBearingSensor(veh, lm, covar=W, range=8, angle=math.pi / 2, seed=0)
    ekf = M.EKF(robot=(veh, V), P0=P0, map=lm if kind == "localisation" else None, sensor=(sensor, W))
    ekf.run(30)
    np.testing.assert_allclose(veh.x, ref["true"], atol=1e-12, rtol=0)
    assert [h.lm_id for h in ekf.history] == ref["lm"]
    np.testing.assert_allclose(ekf.get_xyt(), ref["xyt"], atol=1e-9, rtol=0)
    np.testing.assert_allclose(ekf.x_est, ref["x_est"], atol=1e-9, rtol=0)
    np.testing.assert_allclose(ekf.P_est, ref["P_est"], atol=1e-12, rtol=1e-9)
    if kind == "slam":
        assert {str(k): v for k, v in ekf.landmarks.items()} == ref["landmarks"]
        # and the map it built is where the landmarks are (to a few noise sigmas)
        est = ekf.get_map()
        true = lm.landmarks.T[sorted(ekf.landmarks)]
        assert np.hypot(*(est - true).T).max() < 0.5


def test_ekf_localisation_error_stays_within_its_covariance() -> None:
    """Over a long run the pose error is inside the 3-sigma bound of its own P most of the
    time (a filter that is not overconfident), and dead reckoning alone drifts further."""
    V = np.diag([0.02, math.radians(0.5)]) ** 2
    W = np.diag([0.1, math.radians(1.0)]) ** 2
    lm = M.LandmarkMap(20, workspace=10, seed=0)

    def drive(veh, t, x):  # type: ignore[no-untyped-def]
        return (1.0, 0.15)  # a circle of radius 6.6 m among the landmarks

    runs = {}
    for with_sensor in (True, False):
        veh = M.Bicycle(covar=V, control=drive, seed=11)
        sensor = M.RangeBearingSensor(veh, lm, covar=W, range=10, seed=12) if with_sensor else None
        ekf = M.EKF(robot=(veh, V), P0=np.diag([1e-4, 1e-4, 1e-4]), map=lm,
                    sensor=None if sensor is None else (sensor, W))
        inside, errs = 0, []
        ekf.init()
        for _ in range(600):
            ekf.step()
            e = veh.x[:2] - ekf.x_est[:2]
            errs.append(np.hypot(*e))
            inside += e @ np.linalg.solve(ekf.P_est[:2, :2], e) < 9.0 * 2  # chi2 2 dof: 3 sigma-ish
        runs[with_sensor] = (inside / 600, np.mean(errs[-100:]))
    assert runs[True][0] > 0.9 and runs[False][0] > 0.9
    assert runs[True][1] < 0.2 < runs[False][1]
