"""Features, matching and RANSAC two-view geometry against ground truth: an image warped by a
known homography, and point clouds seen by two cameras with a known relative pose (with
outliers mixed in)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from ejsrl.vision import (
    detect_features,
    epipolar_distances,
    find_essential,
    find_fundamental,
    find_homography,
    match_features,
    recover_pose,
)

K = np.array([[520.0, 0.0, 320.0], [0.0, 520.0, 240.0], [0.0, 0.0, 1.0]])


def _scene(seed: int = 0) -> np.ndarray:
    """A textured grey image: random rectangles and discs (corners and blobs to detect)."""
    rng = np.random.default_rng(seed)
    img = np.full((480, 640), 128, np.uint8)
    for _ in range(120):
        x, y = rng.integers(0, 640), rng.integers(0, 480)
        if rng.random() < 0.5:
            cv2.rectangle(img, (int(x), int(y)), (int(x + rng.integers(8, 50)), int(y + rng.integers(8, 50))), int(rng.integers(0, 256)), -1)
        else:
            cv2.circle(img, (int(x), int(y)), int(rng.integers(4, 25)), int(rng.integers(0, 256)), -1)
    return cv2.GaussianBlur(img, (0, 0), 1.0)


H_TRUE = np.array([[0.9, 0.12, 30.0], [-0.08, 0.95, 20.0], [2e-4, -1e-4, 1.0]])


@pytest.mark.parametrize("method", ["orb", "sift"])
def test_features_matched_and_ransac_recover_a_known_homography(method):
    img1 = _scene()
    img2 = cv2.warpPerspective(img1, H_TRUE, (640, 480))
    f1, f2 = detect_features(img1, method), detect_features(img2, method)
    assert len(f1) > 200 and len(f2) > 200
    assert f1.descriptors.shape[0] == len(f1) and (f1.binary == (method == "orb"))
    m = match_features(f1, f2, ratio=0.8)
    assert len(m) > 50
    H, inliers = find_homography(f1.points[m[:, 0]], f2.points[m[:, 1]], threshold=2.0)
    assert inliers.mean() > 0.6
    corners = np.array([[0, 0], [639, 0], [639, 479], [0, 479], [320, 240]], float)
    ref = cv2.perspectiveTransform(corners.reshape(-1, 1, 2), H_TRUE).reshape(-1, 2)
    got = cv2.perspectiveTransform(corners.reshape(-1, 1, 2), H).reshape(-1, 2)
    assert np.abs(got - ref).max() < 1.5
    # the inliers really are correct matches (where H_TRUE sends them)
    p1, p2 = f1.points[m[inliers, 0]], f2.points[m[inliers, 1]]
    err = np.linalg.norm(cv2.perspectiveTransform(p1.reshape(-1, 1, 2), H_TRUE).reshape(-1, 2) - p2, axis=1)
    assert np.median(err) < 1.0


def test_homography_ransac_rejects_planted_outliers():
    rng = np.random.default_rng(3)
    p1 = rng.uniform(0, 640, (100, 2))
    p2 = cv2.perspectiveTransform(p1.reshape(-1, 1, 2), H_TRUE).reshape(-1, 2) + rng.normal(0, 0.3, (100, 2))
    bad = rng.choice(100, 30, replace=False)
    p2[bad] = rng.uniform(0, 640, (30, 2))
    H, inliers = find_homography(p1, p2, threshold=2.0)
    np.testing.assert_allclose(H, H_TRUE, rtol=0.02, atol=2e-5)
    truth = np.ones(100, bool)
    truth[bad] = False
    assert (inliers == truth).mean() > 0.97


def _two_views(n: int = 120, seed: int = 1):
    rng = np.random.default_rng(seed)
    X1 = np.column_stack([rng.uniform(-1.5, 1.5, (n, 2)), rng.uniform(3.0, 7.0, n)])  # camera-1 frame
    R = cv2.Rodrigues(np.array([0.05, -0.2, 0.03]))[0]
    t = np.array([-0.8, 0.1, 0.2])
    X2 = X1 @ R.T + t
    def proj(X):
        uvw = X @ K.T
        return uvw[:, :2] / uvw[:, 2:]
    p1 = proj(X1) + rng.normal(0, 0.3, (n, 2))
    p2 = proj(X2) + rng.normal(0, 0.3, (n, 2))
    bad = rng.choice(n, n // 5, replace=False)
    p2[bad] = rng.uniform([0, 0], [640, 480], (len(bad), 2))
    return p1, p2, R, t, bad


def _skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def test_fundamental_matrix_matches_the_true_geometry():
    p1, p2, R, t, bad = _two_views()
    F, inliers = find_fundamental(p1, p2, threshold=1.0)
    Kinv = np.linalg.inv(K)
    F_true = Kinv.T @ _skew(t) @ R @ Kinv
    F_true /= np.linalg.norm(F_true)
    assert min(np.abs(F - F_true).max(), np.abs(F + F_true).max()) < 0.02
    assert abs(np.linalg.det(F)) < 1e-10  # rank 2
    good = np.setdiff1d(np.arange(len(p1)), bad)
    assert np.median(epipolar_distances(F, p1[good], p2[good])) < 0.5
    assert inliers[good].mean() > 0.9 and inliers[bad].mean() < 0.1


def test_essential_matrix_and_relative_pose():
    p1, p2, R, t, bad = _two_views(seed=4)
    E, inliers = find_essential(p1, p2, K)
    assert inliers[bad].mean() < 0.15
    T, _ = recover_pose(E, p1[inliers], p2[inliers], K)
    angle = np.degrees(np.arccos(np.clip((np.trace(T[:3, :3].T @ R) - 1) / 2, -1, 1)))
    assert angle < 0.5
    cos = T[:3, 3] @ (t / np.linalg.norm(t))
    assert cos > np.cos(np.radians(2.0))  # the direction of travel, not its length


def test_input_validation():
    with pytest.raises(ValueError, match="method"):
        detect_features(np.zeros((50, 50), np.uint8), "surf")
    with pytest.raises(ValueError, match="at least 4"):
        find_homography(np.zeros((3, 2)), np.zeros((3, 2)))
    with pytest.raises(ValueError, match="same N"):
        find_fundamental(np.zeros((9, 2)), np.zeros((8, 2)))
    blank = detect_features(np.zeros((50, 50), np.uint8))
    assert len(blank) == 0 and len(match_features(blank, blank)) == 0
    with pytest.raises(ValueError, match="cannot match"):
        match_features(detect_features(_scene(), "orb"), detect_features(_scene(), "sift"))
