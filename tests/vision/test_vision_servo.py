"""Visual servoing: the interaction matrix against finite differences, and closed loops with the
runtime's renderer and SUSAN in the loop (a free-flying camera and a Puma 560 eye-in-hand)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import corners_world, square_world

from ejsrl.robotics import models
from ejsrl.robotics.transforms import r2t, rotx, roty, rotz, transl
from ejsrl.vision import (
    CameraModel,
    ServoMonitor,
    eih_joint_velocities,
    ibvs_velocity,
    integrate_twist,
    interaction_matrix,
    match_points,
    pbvs_velocity,
    susan_corners,
    theta_u,
    to_gray,
    twist_transform,
)
from ejsrl.world import render

CAM = CameraModel(320, 240, fov_deg=50)


def _log_body_twist(T0: np.ndarray, T1: np.ndarray, dt: float) -> np.ndarray:
    """Body twist (v, w) taking T0 to T1 in dt, to first order (a finite-difference reference)."""
    D = np.linalg.inv(T0) @ T1
    R = D[:3, :3]
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / 2.0
    return np.concatenate([D[:3, 3], w]) / dt


def test_interaction_matrix_matches_finite_differences(rng):
    P_cam = np.column_stack([rng.uniform(-0.3, 0.3, (5, 2)), rng.uniform(0.5, 2.0, 5)])
    xy = P_cam[:, :2] / P_cam[:, 2:3]
    L = interaction_matrix(xy, P_cam[:, 2])
    assert L.shape == (10, 6)
    for _ in range(3):
        v = rng.normal(size=6)
        dt = 1e-6
        T1 = integrate_twist(np.eye(4), v, dt)  # the camera moves; the points stay
        P1 = (P_cam - T1[:3, 3]) @ T1[:3, :3]
        xy1 = P1[:, :2] / P1[:, 2:3]
        np.testing.assert_allclose((xy1 - xy).ravel() / dt, L @ v, rtol=1e-4, atol=1e-6)


def test_ibvs_velocity_is_the_pseudo_inverse_law():
    s = np.array([[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.1, -0.1]])
    s_star = s * 1.2  # the points must spread out: move forwards along z
    v = ibvs_velocity(s, s_star, 1.0, lam=0.5)
    assert v[2] > 0 and np.allclose(v[[0, 1, 3, 4, 5]], 0, atol=1e-12)
    L = interaction_matrix(s, 1.0)
    np.testing.assert_allclose(L @ v, -0.5 * (s - s_star).ravel(), atol=1e-12)  # square system here
    # pixels through the camera give the same twist
    vp = ibvs_velocity(CAM.denormalized(s), CAM.denormalized(s_star), 1.0, lam=0.5, camera=CAM)
    np.testing.assert_allclose(vp, v, atol=1e-12)


def test_twist_transform_moves_a_twist_between_frames(rng):
    T = r2t(rotx(0.3) @ rotz(1.1), [0.2, -0.5, 0.7])
    v_b = rng.normal(size=6)
    dt = 1e-6
    # the same rigid motion seen from frame a: T_a(t) = T_a_b(t) ... compare point velocities
    Tb1 = integrate_twist(np.eye(4), v_b, dt)  # motion of frame b in its own initial frame
    Ta1 = T @ Tb1 @ np.linalg.inv(T)  # the same motion of a body fixed to b, seen in a
    v_a = _log_body_twist(np.eye(4), Ta1, dt)
    np.testing.assert_allclose(twist_transform(T) @ v_b, v_a, rtol=1e-4, atol=1e-5)


def test_eye_in_hand_joint_rates_reproduce_the_camera_twist(rng):
    robot = models.puma560()
    q = robot.qn + rng.uniform(-0.2, 0.2, 6)
    T_tool_cam = transl(0.03, 0.0, 0.08) @ r2t(rotz(np.pi / 2))
    qd = rng.normal(size=6) * 0.3
    dt = 1e-6
    Tc0 = robot.fkine(q) @ T_tool_cam
    Tc1 = robot.fkine(q + qd * dt) @ T_tool_cam
    v_cam = _log_body_twist(Tc0, Tc1, dt)  # the camera twist those joint rates make (camera frame)
    back = eih_joint_velocities(v_cam, robot.jacob0(q), robot.fkine(q), T_tool_cam)
    np.testing.assert_allclose(back, qd, rtol=1e-4, atol=1e-5)
    damped = eih_joint_velocities(v_cam, robot.jacob0(q), robot.fkine(q), T_tool_cam, damping=1e-4)
    np.testing.assert_allclose(damped, qd, rtol=1e-3, atol=1e-4)


def _pose_error(T, T_goal):
    """(position error in metres, rotation error in degrees)"""
    cos = (np.trace(T[:3, :3].T @ T_goal[:3, :3]) - 1) / 2
    return float(np.linalg.norm(T[:3, 3] - T_goal[:3, 3])), float(np.degrees(np.arccos(np.clip(cos, -1, 1))))


def _features(T_world_camera, world):
    rgb, depth = render(world, CAM, T_world_camera)
    pts = susan_corners(to_gray(rgb), t=25, max_corners=4)
    return pts, depth


def _depth_at(depth, pts):
    out = []
    for x, y in pts:
        xi, yi = int(round(x)), int(round(y))
        win = depth[max(0, yi - 2) : yi + 3, max(0, xi - 2) : xi + 3]
        out.append(float(np.min(win)))
    return np.array(out)


def _servo(world, step, T_start, T_goal, lam=0.8, dt=0.1, iters=200):
    s_star, _ = _features(T_goal, world)
    assert len(s_star) == 4
    s, _ = _features(T_start, world)
    prev = match_points(s, s_star)
    errors = []
    T = T_start
    for _ in range(iters):
        pts, depth = _features(T, world)
        assert len(pts) == 4, "lost a corner"
        s = match_points(pts, prev)
        prev = s
        err = np.abs(s - s_star).max()
        errors.append(err)
        if err < 0.2:
            break
        v = ibvs_velocity(s, s_star, _depth_at(depth, s), lam, camera=CAM)
        T = step(T, v, dt)
    return T, s, s_star, errors


def test_free_flying_camera_converges_to_the_desired_view():
    T_sq = np.eye(4)
    world = square_world(T_sq)
    T_goal = r2t(rotx(np.pi), [0.0, 0.0, 0.5])
    T_start = transl(0.05, -0.04, 0.12) @ T_goal @ r2t(rotz(0.35) @ roty(0.08) @ rotx(-0.06))
    T, s, s_star, errors = _servo(world, integrate_twist, T_start, T_goal)
    assert errors[0] > 30  # it had a long way to go
    assert errors[-1] < 0.5
    # the true corner projections agree with the desired view's, and the camera is where it should be
    true_now = CAM.project(corners_world(T_sq), T)
    true_goal = CAM.project(corners_world(T_sq), T_goal)
    assert np.abs(true_now - true_goal).max() < 1.0
    # a pixel of feature error leaves millimetres of pose error (sideways motion and tilt nearly
    # cancel in the image of a small square); the start was 13 cm and 20 degrees away
    assert _pose_error(T, T_goal)[0] < 0.015 and _pose_error(T, T_goal)[1] < 1.5


def test_puma_eye_in_hand_converges_through_its_jacobian():
    robot = models.puma560()
    T_tool_cam = transl(0.0, 0.0, 0.05) @ r2t(rotz(np.pi / 2))
    q_goal = robot.qn.copy()
    T_goal = robot.fkine(q_goal) @ T_tool_cam
    T_sq = T_goal @ transl(0, 0, 0.5) @ r2t(rotx(np.pi))  # facing the camera, 0.5 m ahead
    world = square_world(T_sq)
    q = q_goal + np.array([0.06, -0.05, 0.07, 0.12, -0.1, 0.15])
    state = {"q": q}

    def step(T, v, dt):
        qq = state["q"]
        qd = eih_joint_velocities(v, robot.jacob0(qq), robot.fkine(qq), T_tool_cam)
        state["q"] = qq + qd * dt
        return robot.fkine(state["q"]) @ T_tool_cam

    T_start = robot.fkine(q) @ T_tool_cam
    T, s, s_star, errors = _servo(world, step, T_start, T_goal)
    assert errors[0] > 20
    assert errors[-1] < 0.5
    true_now = CAM.project(corners_world(T_sq), T)
    true_goal = CAM.project(corners_world(T_sq), T_goal)
    assert np.abs(true_now - true_goal).max() < 1.0
    assert _pose_error(T, T_goal)[0] < 0.015 and _pose_error(T, T_goal)[1] < 1.5
    np.testing.assert_allclose(state["q"], q_goal, atol=0.03)


@pytest.mark.parametrize("bad", [0.0, -1.0])
def test_interaction_matrix_rejects_points_behind(bad):
    with pytest.raises(ValueError, match="positive"):
        interaction_matrix([[0, 0]], [bad])


# -- PBVS, theta u and the servo monitor -------------------------------------------------------

# four coplanar points (a 0.2 m square) in the world, seen by cameras looking down -z
SQUARE = np.array([[-0.1, -0.1, 0.0], [0.1, -0.1, 0.0], [0.1, 0.1, 0.0], [-0.1, 0.1, 0.0]])
T_DESIRED = r2t(rotx(np.pi), [0.0, 0.0, 0.5])


@pytest.mark.parametrize("angle", [0.0, 1e-9, 0.4, 2.0, np.pi - 1e-7, np.pi])
def test_theta_u_is_the_rotation_vector(angle, rng):
    from scipy.spatial.transform import Rotation

    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    rv = angle * axis
    R = Rotation.from_rotvec(rv).as_matrix()
    got = theta_u(R)
    if angle > np.pi - 1e-6:  # at pi, u and -u are the same rotation
        assert min(np.linalg.norm(got - rv), np.linalg.norm(got + rv)) < 1e-6
    else:
        np.testing.assert_allclose(got, rv, atol=1e-9)


def _simulate(T_start, law, *, lam=1.0, dt=0.02, seconds=8.0, monitor=None):
    """A free-flying camera servoed on the exact projections of SQUARE (fixed correspondences)."""
    s_star = CAM.project(SQUARE, T_DESIRED)
    T = T_start
    path, errs, warnings = [T[:3, 3].copy()], [], []
    for _ in range(int(seconds / dt)):
        s = CAM.project(SQUARE, T)
        Z = CAM.world_to_camera(SQUARE, T)[:, 2]
        if monitor is not None:
            warnings += monitor.check(s, Z)
        errs.append(float(np.abs(s - s_star).max()))
        if law == "ibvs":
            v = ibvs_velocity(s, s_star, Z, lam, camera=CAM)
        else:  # PBVS from the pose PnP estimates from the same pixels
            T_c_obj = CAM.estimate_pose(SQUARE, s)
            T_d_obj = np.linalg.inv(T_DESIRED)
            v = pbvs_velocity(T_c_obj @ np.linalg.inv(T_d_obj), lam)
        T = integrate_twist(T, v, dt)
        path.append(T[:3, 3].copy())
    return T, np.array(path), np.array(errs), warnings


def test_pbvs_from_pnp_converges_on_a_straight_line():
    T_start = T_DESIRED @ transl(0.08, -0.05, -0.15) @ r2t(rotz(1.2) @ rotx(0.15))
    T, path, errs, _ = _simulate(T_start, "pbvs")
    pos, ang = _pose_error(T, T_DESIRED)
    assert pos < 1e-4 and ang < 0.05  # e^-8 of 0.16 m and 70 degrees
    # the camera centre moves on the straight line from start to goal (the law's signature)
    a, b = path[0], T_DESIRED[:3, 3]
    d = b - a
    off = np.linalg.norm(np.cross(path - a, d), axis=1) / np.linalg.norm(d)
    assert off.max() < 1e-3
    # the pose error decays exponentially at rate lambda = 1/s: after 2 s about e^-2 of it is left
    k = int(2.0 / 0.02)
    assert np.linalg.norm(path[k] - b) == pytest.approx(np.exp(-2.0) * np.linalg.norm(a - b), rel=0.05)


def test_ibvs_at_180_degrees_retreats_and_the_monitor_says_so_while_pbvs_converges():
    T_start = T_DESIRED @ r2t(rotz(np.pi))  # the classic case: a half turn about the optical axis
    monitor = ServoMonitor(CAM.width, CAM.height, 4)
    T, path, errs, warnings = _simulate(T_start, "ibvs", monitor=monitor, seconds=3.0)
    depth = path[:, 2]  # the camera looks down -z at the square on z = 0: height = depth
    first = depth[: int(0.8 / 0.02)]
    assert np.all(np.diff(first) > 0) and np.all(np.diff(first, 2) > 0)  # it backs away, ever faster
    assert first[-1] > 5 * depth[0] and depth[-1] > 1e3  # to "infinity" within seconds
    assert errs[-1] > 0.4 * errs[0]  # the image shrinks to a point: the error never goes
    assert len(warnings) == 1 and "retreating" in warnings[0] and "PBVS" in warnings[0]
    # PBVS from the same start turns about the optical axis and arrives
    T, path, errs, _ = _simulate(T_start, "pbvs")
    assert _pose_error(T, T_DESIRED)[1] < 0.1 and errs[-1] < 0.1  # e^-8 of 180 degrees
    assert np.ptp(path[:, 2]) < 1e-6  # without moving along the axis


def test_a_converging_ibvs_run_gives_no_warning():
    T_start = T_DESIRED @ transl(0.03, 0.02, -0.1) @ r2t(rotz(0.5))
    monitor = ServoMonitor(CAM.width, CAM.height, 4)
    T, path, errs, warnings = _simulate(T_start, "ibvs", monitor=monitor)
    assert errs[-1] < 0.05 and warnings == []


def test_the_monitor_warns_once_when_features_leave_the_image_and_again_after_they_return():
    m = ServoMonitor(320, 240, 4)
    inside = np.array([[100, 100], [200, 100], [200, 150], [100, 150]], float)
    assert m.check(inside, [0.5] * 4) == []
    out = inside + [150, 0]  # two corners past the right border
    first = m.check(out, [0.5] * 4)
    assert len(first) == 1 and "leaving the image" in first[0] and "2 of 4" in first[0]
    assert m.check(out, [0.5] * 4) == []  # once, not every step
    assert m.check(inside[:3]) == []  # three found: still leaving (already said)
    assert m.check(inside, [0.5] * 4) == []
    again = m.check(inside[:3])  # a corner lost after they came back: a new warning
    assert len(again) == 1 and "3 of 4" in again[0]
