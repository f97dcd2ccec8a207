"""Camera calibration against ground truth: synthetic chessboard views of a known camera
(with lens distortion), as point sets with noise and as rendered images."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from ejsrl.vision import CameraModel, calibrate_camera, calibrate_chessboard, chessboard_points, find_chessboard

K = np.array([[610.0, 0.0, 331.0], [0.0, 604.0, 229.0], [0.0, 0.0, 1.0]])
DIST = np.array([-0.21, 0.07, 0.0, 0.0, 0.0])
PATTERN, SQUARE = (8, 5), 0.03


def board_poses(n: int, seed: int = 0, *, far: bool = False) -> list[np.ndarray]:
    """``T_camera_board`` of n views: the board 0.3-0.5 m away (``far``: 0.45-0.7 m, all of it in
    the image), tilted up to ~35 degrees."""
    rng = np.random.default_rng(seed)
    out = []
    centre = np.array([3.5 * SQUARE, 2.0 * SQUARE, 0.0])
    for _ in range(n):
        R = cv2.Rodrigues(rng.uniform(-0.6, 0.6, 3) * np.array([1.0, 1.0, 0.5]))[0]
        if far:
            t = np.array([rng.uniform(-0.06, 0.06), rng.uniform(-0.05, 0.05), rng.uniform(0.45, 0.7)])
        else:
            t = np.array([rng.uniform(-0.1, 0.1), rng.uniform(-0.07, 0.07), rng.uniform(0.3, 0.5)])
        t = t - R @ centre
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R, t
        out.append(T)
    return out


def render_board(cam: CameraModel, T_camera_board: np.ndarray, texels: int = 40) -> np.ndarray:
    """A grey image of a 9 x 6 board with a one-square white margin, warped from a fine texture."""
    cols, rows = PATTERN[0] + 1, PATTERN[1] + 1
    tex = np.full(((rows + 2) * texels, (cols + 2) * texels), 255, np.uint8)
    for r in range(rows):
        for c in range(cols):
            if (r + c) % 2 == 0:
                tex[(r + 1) * texels : (r + 2) * texels, (c + 1) * texels : (c + 2) * texels] = 0
    tex = cv2.GaussianBlur(tex, (0, 0), texels / 12)
    m = SQUARE / texels  # metres per texel; the first inner corner is 2 squares in
    A = np.array([[1 / m, 0, 2 * texels - 0.5], [0, 1 / m, 2 * texels - 0.5], [0, 0, 1]])  # texel from metric
    H = K @ np.column_stack([T_camera_board[:3, 0], T_camera_board[:3, 1], T_camera_board[:3, 3]]) @ np.linalg.inv(A)
    ideal = cv2.warpPerspective(tex, H, (cam.width, cam.height), flags=cv2.INTER_LINEAR, borderValue=140)
    return cam.distort(ideal)


def test_calibration_recovers_a_known_camera_from_noisy_points():
    cam = CameraModel(640, 480, K=K, distortion=DIST)
    board = chessboard_points(PATTERN, SQUARE)
    rng = np.random.default_rng(1)
    sigma = 0.1
    views = [cam.project(board, np.linalg.inv(T)) + rng.normal(0, sigma, (len(board), 2)) for T in board_poses(15)]
    cal = calibrate_camera([board] * len(views), views, (640, 480))
    np.testing.assert_allclose([cal.fx, cal.fy], [610, 604], rtol=3e-3)
    np.testing.assert_allclose([cal.cx, cal.cy], [331, 229], atol=1.5)
    np.testing.assert_allclose(cal.distortion[:2], DIST[:2], atol=0.03)
    # the reprojection error is the noise's (2-D RMS = sigma * sqrt(2)), slightly less for the fitted parameters
    assert 0.85 * sigma * np.sqrt(2) < cal.rms < 1.05 * sigma * np.sqrt(2)
    assert cal.per_view.shape == (15,) and np.all(cal.per_view < 3 * sigma)
    # the poses: the board's origin where the ground truth puts it
    for T, T_true in zip(cal.poses, board_poses(15)):
        assert np.linalg.norm(T[:3, 3] - T_true[:3, 3]) < 3e-3
    np.testing.assert_allclose(cal.camera.project_camera([[0.1, 0.05, 1.0]]), cam.project_camera([[0.1, 0.05, 1.0]]), atol=1.0)


def test_calibration_from_rendered_chessboard_images():
    cam = CameraModel(640, 480, K=K, distortion=DIST)
    poses = board_poses(10, seed=4, far=True)
    images = [render_board(cam, T) for T in poses]
    found = find_chessboard(images[0], PATTERN)
    assert found is not None and found.shape == (40, 2)
    # the corners are found where the camera projects them (either end first: the board is symmetric)
    truth = cam.project(chessboard_points(PATTERN, SQUARE), np.linalg.inv(poses[0]))
    err = min(np.abs(found - truth).max(), np.abs(found[::-1] - truth).max())
    assert err < 0.3
    cal = calibrate_chessboard(images, PATTERN, SQUARE, fix_k3=True)
    np.testing.assert_allclose([cal.fx, cal.fy], [610, 604], rtol=5e-3)
    np.testing.assert_allclose([cal.cx, cal.cy], [331, 229], atol=2.0)
    np.testing.assert_allclose(cal.distortion[:2], DIST[:2], atol=0.03)
    assert cal.rms < 0.25


def test_chessboard_points_follow_opencv_order():
    P = chessboard_points((3, 2), 0.5)
    np.testing.assert_array_equal(P, [[0, 0, 0], [0.5, 0, 0], [1, 0, 0], [0, 0.5, 0], [0.5, 0.5, 0], [1, 0.5, 0]])


def test_no_board_gives_none_and_bad_input_a_clear_error():
    assert find_chessboard(np.full((120, 160), 128, np.uint8), PATTERN) is None
    with pytest.raises(ValueError, match="at least 3 views"):
        calibrate_camera([chessboard_points(PATTERN, SQUARE)] * 2, [np.zeros((40, 2))] * 2, (640, 480))
    with pytest.raises(ValueError, match="inner corners"):
        chessboard_points((1, 5), SQUARE)
    with pytest.raises(ValueError, match="view 0"):
        calibrate_camera([np.zeros((4, 3))] * 3, [np.zeros((5, 2))] * 3, (640, 480))
    with pytest.raises(ValueError, match="found in 0 of 3"):
        calibrate_chessboard([np.zeros((50, 50), np.uint8)] * 3, PATTERN, SQUARE)
