"""Point clouds from the virtual depth camera, checked against the scene's true geometry, and ICP
against transforms the test chose."""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.robotics.transforms import transl, trotx, troty, trotz
from ejsrl.vision import CameraModel, look_at
from ejsrl.vision.pointcloud import best_rigid_transform, depth_to_points, icp, transform_points, voxel_downsample
from ejsrl.world import World
from ejsrl.world.rendering import render, render_depth
from ejsrl.world.scene import Box, Sphere

CAM = CameraModel(160, 120, fov_deg=55)


def _scene() -> World:
    w = World()
    w.add(Box("floor", size=(2, 2, 0.02), color="gray", T_parent_local=transl(0, 0, -0.01)))
    w.add(Box("crate", size=(0.2, 0.3, 0.25), color="blue", T_parent_local=transl(0.1, 0.05, 0.125) @ trotz(0.4)))
    w.add(Sphere("ball", radius=0.1, color="red", T_parent_local=transl(-0.2, -0.1, 0.1)))
    return w


def test_the_cloud_lies_on_the_surfaces_the_camera_sees() -> None:
    T_cam = look_at([0.6, -0.7, 0.8], [0, 0, 0.1], [0, 0, 1])
    depth = render_depth(_scene(), CAM, T_cam, backend="numpy")
    P_cam = depth_to_points(depth, CAM)
    P = depth_to_points(depth, CAM, T_cam)
    assert len(P) == np.isfinite(depth).sum() > 0.6 * depth.size  # the floor ends below the horizon
    np.testing.assert_allclose(transform_points(T_cam, P_cam), P, atol=1e-12)
    assert np.all(P_cam[:, 2] > 0)  # in front of the camera (z forward)
    # every world point lies on the floor's top, the crate's faces or the ball's surface
    on_floor = np.abs(P[:, 2]) < 2e-3
    ball = np.abs(np.linalg.norm(P - [-0.2, -0.1, 0.1], axis=1) - 0.1) < 3e-3  # a faceted sphere
    local = transform_points(np.linalg.inv(transl(0.1, 0.05, 0.125) @ trotz(0.4)), P)
    half = np.array([0.1, 0.15, 0.125])
    inside = np.all(np.abs(local) <= half + 1e-3, axis=1)
    on_face = inside & np.any(np.abs(np.abs(local) - half) < 1e-3, axis=1)
    assert np.all(on_floor | ball | on_face)
    assert on_face.sum() > 300 and ball.sum() > 100
    # colours ride along, and a stride keeps every other row and column
    rgb, _ = render(_scene(), CAM, T_cam, backend="numpy")
    P2, C2 = depth_to_points(depth, CAM, T_cam, stride=2, rgb=rgb)
    assert len(P2) == np.isfinite(depth[::2, ::2]).sum() and C2.shape == (len(P2), 3)
    red = (C2[:, 0] > 120) & (C2[:, 1] < 60) & (C2[:, 2] < 60)
    assert np.abs(np.linalg.norm(P2[red] - [-0.2, -0.1, 0.1], axis=1) - 0.1).max() < 3e-3


def test_icp_recovers_a_known_transform_between_two_views() -> None:
    # the same scene seen by two cameras; the second view's cloud moved by a known transform
    w = _scene()
    T1 = look_at([0.6, -0.7, 0.8], [0, 0, 0.1], [0, 0, 1])
    T2 = look_at([0.7, -0.5, 0.8], [0, 0, 0.1], [0, 0, 1])
    A = voxel_downsample(depth_to_points(render_depth(w, CAM, T1, backend="numpy"), CAM, T1), 0.01)
    B = voxel_downsample(depth_to_points(render_depth(w, CAM, T2, backend="numpy"), CAM, T2), 0.01)
    T_known = transl(0.03, -0.02, 0.015) @ trotz(0.12) @ trotx(0.05) @ troty(-0.04)
    res = icp(transform_points(T_known, B), A, max_distance=0.05, trim=0.9)
    np.testing.assert_allclose(res.T[:3, 3], np.linalg.inv(T_known)[:3, 3], atol=4e-3)
    R_err = res.T[:3, :3] @ T_known[:3, :3]
    assert np.degrees(np.arccos(np.clip((np.trace(R_err) - 1) / 2, -1, 1))) < 0.5
    assert res.converged and res.rms < 0.008 and res.fitness > 0.8  # rms: the two views' 1 cm voxels differ


def test_best_rigid_transform_is_exact_on_paired_points_and_icp_from_identity() -> None:
    rng = np.random.default_rng(3)
    P = rng.uniform(-1, 1, (200, 3))
    T = transl(0.2, -0.1, 0.3) @ trotz(0.3) @ trotx(-0.2)
    np.testing.assert_allclose(best_rigid_transform(P, transform_points(T, P)), T, atol=1e-12)
    for method in ("point_to_plane", "point_to_point"):
        res = icp(P, transform_points(T, P), method=method)
        np.testing.assert_allclose(res.T, T, atol=1e-6)
        assert res.rms < 1e-6


def _floor_and_box(rng: np.random.Generator, n: int = 800) -> np.ndarray:
    """A 0.6 m floor patch and two faces of a 0.1 m box standing on it, sampled at random, 1 mm noise."""
    floor = np.c_[rng.uniform(-0.3, 0.3, n), rng.uniform(-0.3, 0.3, n), np.zeros(n)]
    front = np.c_[rng.uniform(0, 0.1, n // 4), np.zeros(n // 4), rng.uniform(0, 0.1, n // 4)]
    side = np.c_[np.zeros(n // 4), rng.uniform(0, 0.1, n // 4), rng.uniform(0, 0.1, n // 4)]
    return np.r_[floor, front, side] + rng.normal(0, 0.001, (n + 2 * (n // 4), 3))


@pytest.mark.parametrize("seed", [1, 17, 24])
def test_trimmed_icp_settles_where_its_pairs_flip(seed: int) -> None:
    """Two samplings of one scene, one moved by a known transform (2-8 degrees about z, up to
    2 cm): trimmed ICP's pairs end up flipping between two sets (the pose a few micrometres
    back and forth, the rms never still: it ran its 50 iterations and said it had not
    converged, the trial's finding); it now stops there, converged, at the better of them,
    within 1 mm and 0.5 degrees of the truth."""
    rng = np.random.default_rng(seed)
    target, sample = _floor_and_box(rng), _floor_and_box(rng)
    a = np.radians(rng.uniform(2, 8))
    T = trotz(a) @ np.eye(4)
    T[:3, 3] = rng.uniform(-0.02, 0.02, 3)
    r = icp(transform_points(T, sample), target, trim=0.9)
    assert r.converged and r.iterations < 30, (r.converged, r.iterations)
    E = r.T @ T  # r.T undoes T
    assert np.linalg.norm(E[:3, 3]) < 1e-3
    assert np.degrees(np.arccos(np.clip((np.trace(E[:3, :3]) - 1) / 2, -1, 1))) < 0.5
    moved = transform_points(r.T, transform_points(T, sample))
    from scipy.spatial import cKDTree

    d = np.sort(cKDTree(target).query(moved)[0])[: int(round(0.9 * len(moved)))]
    assert abs(np.sqrt(np.mean(d**2)) - r.rms) < 1e-9  # the rms returned is the pose's returned


def test_bad_clouds_say_what_is_wrong() -> None:
    with pytest.raises(ValueError, match=r"must be an \(N, 3\) array"):
        icp(np.zeros((5, 2)), np.zeros((5, 3)))
    with pytest.raises(ValueError, match="depth is 10x10 but the camera is 160x120"):
        depth_to_points(np.ones((10, 10)), CAM)
    with pytest.raises(ValueError, match="within max_distance"):
        icp(np.zeros((5, 3)), np.ones((5, 3)) * 10, max_distance=0.1)
