"""Monte Carlo localisation: from particles spread uniformly over the map (no idea where
the car is) the filter finds the true pose; resampling draws particles in proportion to
their weights (against the multinomial frequencies); vectorised range-bearing equals the
one-pose version."""

from __future__ import annotations

import math

import numpy as np

from ejsrl import mobile as M


def test_particle_filter_finds_the_car_from_a_uniform_start() -> None:
    V = np.diag([0.02, math.radians(0.5)]) ** 2
    W = np.diag([0.1, math.radians(1.0)]) ** 2
    lm = M.LandmarkMap(20, workspace=10, seed=0)
    veh = M.Bicycle(covar=V, control=lambda v, t, x: (1.0, 0.15), seed=1, x0=(2.0, -3.0, 0.5))
    sensor = M.RangeBearingSensor(veh, lm, covar=W, seed=3)
    pf = M.ParticleFilter(veh, sensor, R=np.diag([0.1, 0.1, math.radians(1.0)]) ** 2, L=np.diag([0.1, 0.1]),
                          nparticles=1000, seed=4)
    spread0 = pf.std[:2].max()
    assert spread0 > 4.0  # uniform over a 20 m square: about 5.8 m
    pf.run(20)
    est = pf.x_est
    assert math.hypot(est[0] - veh.x[0], est[1] - veh.x[1]) < 0.3
    assert abs(M.angdiff(est[2], veh.x[2])) < 0.1
    assert pf.std[:2].max() < 0.3
    assert len(pf.history) == 200 and pf.points.shape == (1000, 2)


def test_resampling_draws_in_proportion_to_the_weights() -> None:
    veh = M.Bicycle()
    sensor = M.RangeBearingSensor(veh, M.LandmarkMap(np.array([[1.0], [1.0]])))
    pf = M.ParticleFilter(veh, sensor, R=np.eye(3) * 1e-4, L=np.eye(2), nparticles=30000, seed=7, x0=np.zeros(3))
    pf.x = np.repeat(np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]]), 10000, axis=0)
    pf.weight = np.repeat([1.0, 2.0, 7.0], 10000)
    pf.resample()
    freq = np.array([(pf.x[:, 0] == k).mean() for k in range(3)])
    p = np.array([0.1, 0.2, 0.7])
    assert np.all(np.abs(freq - p) < 4 * np.sqrt(p * (1 - p) / 30000))


def test_range_bearing_of_many_poses_equals_one_at_a_time() -> None:
    lm = M.LandmarkMap(5, workspace=10, seed=2)
    s = M.RangeBearingSensor(M.Bicycle(), lm)
    X = np.random.default_rng(0).uniform(-5, 5, (50, 3))
    many = s.h(X, 3)
    one = np.array([s.h(x, 3) for x in X])
    np.testing.assert_allclose(many, one, atol=1e-15)
