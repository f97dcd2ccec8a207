"""Lens distortion and PnP in ``CameraModel``, against OpenCV (projectPoints, undistortPoints,
undistort) and against ground truth poses of synthetic scenes."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from ejsrl.vision import CameraModel, look_at

K = np.array([[520.0, 0.0, 318.2], [0.0, 515.0, 243.7], [0.0, 0.0, 1.0]])
DIST = np.array([-0.28, 0.11, 0.0012, -0.0008, -0.02])  # k1, k2, p1, p2, k3 (OpenCV's order)


def _rot(rx: float, ry: float, rz: float) -> np.ndarray:
    return cv2.Rodrigues(np.array([rx, ry, rz]))[0]


def _cloud(n: int = 50, seed: int = 0) -> np.ndarray:
    """Points in front of the camera, spread over most of the image."""
    rng = np.random.default_rng(seed)
    Z = rng.uniform(0.8, 3.0, n)
    xy = rng.uniform(-0.55, 0.55, (n, 2)) * np.array([1.0, 0.75])
    return np.column_stack([xy * Z[:, None], Z])


def test_projection_applies_distortion_as_opencv_projectpoints():
    cam = CameraModel(640, 480, K=K, distortion=DIST)
    P = _cloud()
    ref, _ = cv2.projectPoints(P, np.zeros(3), np.zeros(3), K, DIST)
    np.testing.assert_allclose(cam.project_camera(P), ref.reshape(-1, 2), atol=1e-9)
    assert (cam.k1, cam.k2, cam.p1, cam.p2, cam.k3) == tuple(DIST)
    # and the world-frame projection through a pose as projectPoints with (rvec, tvec)
    T = look_at([0.3, -2.0, 0.4], [0.0, 0.0, 0.0])
    Pw = np.random.default_rng(1).uniform(-0.5, 0.5, (30, 3))
    R_cw = T[:3, :3].T
    ref, _ = cv2.projectPoints(Pw, cv2.Rodrigues(R_cw)[0], -R_cw @ T[:3, 3], K, DIST)
    np.testing.assert_allclose(cam.project(Pw, T), ref.reshape(-1, 2), atol=1e-9)


def test_barrel_distortion_pulls_points_toward_the_centre():
    cam = CameraModel(640, 480, K=K, distortion=[-0.3, 0.0, 0.0, 0.0, 0.0])
    ideal = CameraModel(640, 480, K=K)
    P = _cloud()
    r_d = np.linalg.norm(cam.project_camera(P) - K[:2, 2], axis=1)
    r_i = np.linalg.norm(ideal.project_camera(P) - K[:2, 2], axis=1)
    assert np.all(r_d < r_i)


def test_normalized_and_backproject_invert_the_distortion():
    cam = CameraModel(640, 480, K=K, distortion=DIST)
    P = _cloud()
    px = cam.project_camera(P)
    np.testing.assert_allclose(cam.normalized(px), P[:, :2] / P[:, 2:], atol=1e-11)
    np.testing.assert_allclose(cam.backproject(px, P[:, 2]), P, atol=1e-10)
    # the same ideal coordinates as OpenCV's iterative undistortPoints (run to convergence)
    ref = cv2.undistortPoints(px.reshape(-1, 1, 2), K, DIST, criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-14))
    np.testing.assert_allclose(cam.normalized(px), ref.reshape(-1, 2), atol=1e-8)
    # undistort_points <-> distort_points round trip, in pixels
    np.testing.assert_allclose(cam.distort_points(cam.undistort_points(px)), px, atol=1e-8)


def test_undistort_image_matches_opencv():
    cam = CameraModel(640, 480, K=K, distortion=DIST)
    rng = np.random.default_rng(3)
    img = cv2.resize(rng.integers(0, 256, (60, 80), dtype=np.uint8), (640, 480), interpolation=cv2.INTER_LINEAR)
    ours = cam.undistort(img)
    ref = cv2.undistort(img, K, DIST)
    inner = (slice(20, -20), slice(20, -20))
    diff = np.abs(ours[inner].astype(int) - ref[inner].astype(int))
    assert np.percentile(diff, 99) <= 2 and diff.mean() < 0.5


def test_distort_puts_a_scene_point_where_the_lens_projects_it():
    """Draw a dot at ideal pixel p in a pinhole image; distort() moves it to distort_points(p)."""
    cam = CameraModel(640, 480, K=K, distortion=DIST)
    for p in [(80.0, 60.0), (560.0, 420.0), (320.0, 60.0), (600.0, 250.0)]:
        img = np.zeros((480, 640), np.float32)
        cv2.circle(img, (int(p[0] * 16), int(p[1] * 16)), 3 * 16, 1.0, -1, lineType=cv2.LINE_AA, shift=4)
        out = cam.distort(img)
        ys, xs = np.nonzero(out > 0.05)
        w = out[ys, xs]
        seen = np.array([np.sum(xs * w) / w.sum(), np.sum(ys * w) / w.sum()])
        expected = cam.distort_points([p])[0]
        assert np.linalg.norm(seen - expected) < 0.3, (p, seen, expected)
        assert np.linalg.norm(expected - p) > 3  # the lens really moved it
    # and undistort() brings the image back (away from the border)
    img = cv2.GaussianBlur(np.random.default_rng(0).integers(0, 256, (480, 640)).astype(np.uint8), (0, 0), 3)
    back = cam.undistort(cam.distort(img))
    inner = (slice(60, -60), slice(80, -80))
    assert np.abs(back[inner].astype(int) - img[inner].astype(int)).mean() < 1.0


def test_no_distortion_changes_nothing():
    cam = CameraModel(640, 480, K=K)
    assert not cam.distorted
    P = _cloud()
    uvw = P @ K.T
    np.testing.assert_allclose(cam.project_camera(P), uvw[:, :2] / uvw[:, 2:], atol=1e-12)
    img = np.arange(480 * 640, dtype=np.uint32).reshape(480, 640).astype(np.uint8)
    assert np.array_equal(cam.undistort(img), img)


@pytest.mark.parametrize("method", ["sqpnp", "iterative", "epnp"])
def test_estimate_pose_recovers_a_known_pose(method):
    cam = CameraModel(640, 480, K=K, distortion=DIST)
    rng = np.random.default_rng(7)
    P_obj = rng.uniform(-0.2, 0.2, (12, 3))
    T_true = np.eye(4)
    T_true[:3, :3] = _rot(0.3, -0.5, 1.2)
    T_true[:3, 3] = [0.05, -0.08, 1.1]
    P_cam = P_obj @ T_true[:3, :3].T + T_true[:3, 3]
    px = cam.project_camera(P_cam) + rng.normal(0, 0.05, (12, 2))
    T = cam.estimate_pose(P_obj, px, method=method)
    assert np.abs(T[:3, 3] - T_true[:3, 3]).max() < 2e-3
    angle = np.degrees(np.arccos(np.clip((np.trace(T[:3, :3].T @ T_true[:3, :3]) - 1) / 2, -1, 1)))
    assert angle < 0.2


def test_estimate_pose_of_a_planar_target_gives_the_camera_pose_in_the_world():
    """Four corners of a square on the floor (world frame): inv(T_camera_object) = T_world_camera."""
    cam = CameraModel(320, 240, fov_deg=50)
    square = np.array([[0.47, 0.07, 0.0], [0.63, 0.07, 0.0], [0.63, 0.23, 0.0], [0.47, 0.23, 0.0]])
    T_wc = look_at([0.6, 0.1, 0.5], [0.55, 0.15, 0.0], up=(1.0, 0.0, 0.0))
    px = cam.project(square, T_wc)
    for method in ("ippe", "sqpnp"):
        T = np.linalg.inv(cam.estimate_pose(square, px, method=method))
        np.testing.assert_allclose(T, T_wc, atol=1e-7)


def test_input_validation():
    with pytest.raises(ValueError, match="5 coefficients"):
        CameraModel(640, 480, K=K, distortion=[0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match="finite"):
        CameraModel(640, 480, K=K, distortion=[np.nan, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="3 x 3"):
        CameraModel(640, 480, K=np.eye(2))
    cam = CameraModel(640, 480, K=K)
    with pytest.raises(ValueError, match="at least 4"):
        cam.estimate_pose(np.zeros((3, 3)), np.zeros((3, 2)))
    with pytest.raises(ValueError, match="one pixel per point"):
        cam.estimate_pose(np.zeros((5, 3)), np.zeros((4, 2)))
    with pytest.raises(ValueError, match="finite"):
        cam.estimate_pose(np.ones((4, 3)), np.full((4, 2), np.nan))
    with pytest.raises(ValueError, match="method"):
        cam.estimate_pose(np.ones((4, 3)), np.ones((4, 2)), method="p3p-magic")
    with pytest.raises(ValueError, match="camera is 640 x 480"):
        CameraModel(640, 480, K=K, distortion=DIST).undistort(np.zeros((10, 10), np.uint8))
    with pytest.raises(ValueError, match=r"\(N, 2\)"):
        cam.normalized(np.zeros((4, 3)))
