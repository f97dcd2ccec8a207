"""Stereo against ground truth: a textured plane at a known depth seen by two cameras a
known baseline apart; rectification of a verged pair puts corresponding points on one row
with the disparity f b / Z; triangulation returns the 3-D points."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from ejsrl.vision import CameraModel, depth_from_disparity, disparity, stereo_rectify, triangulate

K = np.array([[500.0, 0.0, 319.5], [0.0, 500.0, 239.5], [0.0, 0.0, 1.0]])


def _texture(h: int = 480, w: int = 640, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.integers(0, 256, (h, w)).astype(np.uint8), (0, 0), 1.2)


@pytest.mark.parametrize("method", ["sgbm", "bm"])
def test_disparity_of_a_fronto_parallel_plane_is_f_b_over_z(method):
    """A plane at Z = 2.5 m, baseline 0.2 m, f = 500 px: d = 40 px everywhere."""
    f, b, Z = 500.0, 0.2, 2.5
    d_true = f * b / Z
    left = _texture()
    right = cv2.warpAffine(left, np.float32([[1, 0, -d_true], [0, 1, 0]]), (640, 480), borderMode=cv2.BORDER_REFLECT)
    d = disparity(left, right, max_disparity=64, block_size=7, method=method)
    inner = d[40:-40, 100:-40]
    assert np.mean(np.isfinite(inner)) > 0.9
    assert abs(np.nanmedian(inner) - d_true) < 0.2
    depth = depth_from_disparity(d, f, b)
    assert abs(np.nanmedian(depth[40:-40, 100:-40]) - Z) < 0.02


def test_rectification_puts_matches_on_one_row_with_the_right_disparity():
    cam = CameraModel(640, 480, K=K, distortion=[-0.1, 0.02, 0.0, 0.0, 0.0])
    # the right camera 0.15 m to the right, verged 4 degrees inwards and slightly rolled
    T_lr = np.eye(4)
    T_lr[:3, :3] = cv2.Rodrigues(np.array([0.01, -np.radians(4), 0.02]))[0]
    T_lr[:3, 3] = [0.15, 0.005, 0.0]
    rect = stereo_rectify(cam, cam, T_lr)
    rng = np.random.default_rng(2)
    P = np.column_stack([rng.uniform(-0.5, 0.5, (40, 2)), rng.uniform(1.5, 4.0, 40)])
    pl = cam.project_camera(P)
    pr = cam.project(P, T_lr)
    ql, qr = rect.rectify_points(pl, "left"), rect.rectify_points(pr, "right")
    assert np.abs(ql[:, 1] - qr[:, 1]).max() < 1e-6  # same row
    assert abs(rect.baseline - np.linalg.norm(T_lr[:3, 3])) < 1e-9
    # depth along the rectified left camera's axis, from the disparity
    Z_rect = (P @ rect.R1.T)[:, 2]
    np.testing.assert_allclose(depth_from_disparity(ql[:, 0] - qr[:, 0], rect.f, rect.baseline), Z_rect, rtol=1e-6)
    # and the images: a dot at the same point lands on the same rectified row in both
    imgs = []
    for px in (pl[0], pr[0]):
        img = np.zeros((480, 640), np.uint8)
        cv2.circle(img, (int(px[0] * 16), int(px[1] * 16)), 4 * 16, 255, -1, cv2.LINE_AA, shift=4)
        imgs.append(img)
    rl, rr = rect.rectify(*imgs)
    rows = [np.average(np.nonzero(im)[0], weights=im[np.nonzero(im)]) for im in (rl, rr)]
    assert abs(rows[0] - rows[1]) < 0.3


def test_triangulate_recovers_points():
    cam = CameraModel(640, 480, K=K)
    T_lr = np.eye(4)
    T_lr[:3, 3] = [0.3, 0.0, 0.0]
    P = np.random.default_rng(5).uniform([-0.5, -0.4, 2.0], [0.5, 0.4, 5.0], (30, 3))
    P1 = K @ np.eye(3, 4)
    T_rl = np.linalg.inv(T_lr)
    P2 = K @ T_rl[:3]
    X = triangulate(P1, P2, cam.project_camera(P), cam.project(P, T_lr))
    np.testing.assert_allclose(X, P, atol=1e-8)


def test_input_validation():
    with pytest.raises(ValueError, match="same size"):
        disparity(np.zeros((10, 10), np.uint8), np.zeros((10, 12), np.uint8))
    with pytest.raises(ValueError, match="odd"):
        disparity(np.zeros((10, 10), np.uint8), np.zeros((10, 10), np.uint8), block_size=4)
    with pytest.raises(ValueError, match="method"):
        disparity(np.zeros((10, 10), np.uint8), np.zeros((10, 10), np.uint8), method="magic")
    with pytest.raises(ValueError, match="positive"):
        depth_from_disparity(np.ones(3), 0.0, 0.1)
    with pytest.raises(ValueError, match="same resolution"):
        stereo_rectify(CameraModel(640, 480), CameraModel(320, 240), np.eye(4))
