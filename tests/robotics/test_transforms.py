"""Spatial helpers: conventions stated in the module, round trips, and scipy as a reference."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

from ejsrl.robotics import transforms as tf


def test_rpy_is_zyx_and_matches_scipy():
    rng = np.random.default_rng(0)
    for r, p, y in rng.uniform(-1.5, 1.5, (20, 3)):
        R = tf.rpy2r(r, p, y)
        np.testing.assert_allclose(R, tf.rotz(y) @ tf.roty(p) @ tf.rotx(r), atol=1e-15)
        np.testing.assert_allclose(R, Rotation.from_euler("ZYX", [y, p, r]).as_matrix(), atol=1e-14)
        np.testing.assert_allclose(tf.tr2rpy(tf.rpy2tr([r, p, y])), [r, p, y], atol=1e-12)


def test_euler_zyz_round_trip_and_singularity():
    rng = np.random.default_rng(1)
    for phi, th, psi in rng.uniform([-3, 0.05, -3], [3, 3.0, 3], (20, 3)):
        R = tf.eul2r(phi, th, psi)
        np.testing.assert_allclose(R, Rotation.from_euler("ZYZ", [phi, th, psi]).as_matrix(), atol=1e-14)
        np.testing.assert_allclose(tf.tr2eul(R), [phi, th, psi], atol=1e-12)
        np.testing.assert_allclose(tf.eul2r(tf.tr2eul(R, flip=True)), R, atol=1e-12)
    for th in (0.0, np.pi):
        R = tf.eul2r(0.3, th, 0.5)
        np.testing.assert_allclose(tf.eul2r(tf.tr2eul(R)), R, atol=1e-12)


def test_angle_axis_and_quaternions_match_scipy():
    rng = np.random.default_rng(2)
    for _ in range(20):
        v = rng.normal(size=3)
        th = rng.uniform(0, np.pi)
        R = tf.angvec2r(th, v)
        np.testing.assert_allclose(R, Rotation.from_rotvec(th * v / np.linalg.norm(v)).as_matrix(), atol=1e-14)
        th2, ax = tf.tr2angvec(R)
        np.testing.assert_allclose(th2 * ax, th * v / np.linalg.norm(v), atol=1e-9)
        q = tf.r2q(R)
        xyzw = Rotation.from_matrix(R).as_quat()
        np.testing.assert_allclose(np.abs(q @ np.roll(xyzw, 1)), 1.0, atol=1e-12)  # wxyz vs xyzw
        np.testing.assert_allclose(tf.q2r(q), R, atol=1e-14)
    # near pi the log is still exact
    R = tf.angvec2r(np.pi - 1e-9, [1, 2, 3])
    np.testing.assert_allclose(tf.angvec2r(*tf.tr2angvec(R)), R, atol=1e-8)
    assert tf.tr2angvec(tf.rotx(np.pi))[0] == pytest.approx(np.pi)


def test_quaternion_product_and_slerp():
    rng = np.random.default_rng(3)
    a, b = tf.r2q(tf.rpy2r(rng.normal(size=3))), tf.r2q(tf.rpy2r(rng.normal(size=3)))
    np.testing.assert_allclose(tf.q2r(tf.qmul(a, b)), tf.q2r(a) @ tf.q2r(b), atol=1e-14)
    np.testing.assert_allclose(tf.qmul(a, tf.qconj(a)), [1, 0, 0, 0], atol=1e-15)
    ref = Slerp([0, 1], Rotation.from_quat([np.roll(a, -1), np.roll(b, -1)]))
    for s in (0.0, 0.25, 0.5, 0.9, 1.0):
        np.testing.assert_allclose(tf.q2r(tf.qslerp(a, b, s)), ref([s]).as_matrix()[0], atol=1e-12)


def test_transforms_and_pose_interpolation():
    T = tf.transl(1, 2, 3) @ tf.trotx(0.3) @ tf.troty(-0.2) @ tf.trotz(1.0)
    np.testing.assert_allclose(tf.trinv(T) @ T, np.eye(4), atol=1e-15)
    np.testing.assert_allclose(tf.transl([1, 2, 3])[:3, 3], [1, 2, 3])
    np.testing.assert_allclose(tf.trinterp(np.eye(4), T, 0.0), np.eye(4), atol=1e-15)
    np.testing.assert_allclose(tf.trinterp(np.eye(4), T, 1.0), T, atol=1e-14)
    mid = tf.trinterp(np.eye(4), T, 0.5)
    np.testing.assert_allclose(mid[:3, 3], [0.5, 1, 1.5])
    np.testing.assert_allclose(mid[:3, :3] @ mid[:3, :3], T[:3, :3], atol=1e-12)  # half rotation
    np.testing.assert_allclose(tf.skew([1, 2, 3]) @ [4, 5, 6], np.cross([1, 2, 3], [4, 5, 6]))
    np.testing.assert_allclose(tf.vex(tf.skew([1, 2, 3])), [1, 2, 3])
