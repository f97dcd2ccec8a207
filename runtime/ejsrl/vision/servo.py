"""Visual servoing with point features: image-based (IBVS), position-based (PBVS), eye-in-hand.

The control law of the EjsRL paper (equations 1-3):

    v_c = -lambda * pinv(L) (s - s*)

with ``s`` the stacked normalised image coordinates (x1, y1, x2, y2, ...) of the points,
``L`` (2N, 6) their stacked interaction matrices (equation 2, one (2, 6) block per point
at depth Z) and ``v_c = (vx, vy, vz, wx, wy, wz)`` the camera twist expressed in the
camera frame (x right, y down, z forward; metres/s and rad/s).

For a camera carried by an arm (eye-in-hand), ``eih_joint_velocities`` maps that twist to
joint rates through the arm's world-frame Jacobian and the tool-to-camera transform.

PBVS (``pbvs_velocity``) servos on the pose instead: from the desired camera pose seen
from the current one (for example by PnP, ``CameraModel.estimate_pose``) it commands the
classic law of Chaumette and Hutchinson (2006), ``v = -lambda R^T t``, ``w = -lambda theta u``
with ``(R, t)`` the current camera's pose in the desired camera frame: a straight-line path
of the camera centre, and no retreat.

``ServoMonitor`` watches a running servo and words what a student should be told: the
features leaving the image, or the camera retreating without bound (point IBVS at a
rotation near 180 degrees about the optical axis, the classic case of Chaumette 1998).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision.camera import CameraModel

__all__ = [
    "interaction_matrix",
    "ibvs_velocity",
    "feature_error",
    "skew",
    "twist_transform",
    "camera_twist_to_world",
    "eih_joint_velocities",
    "integrate_twist",
    "match_points",
    "theta_u",
    "pbvs_velocity",
    "ServoMonitor",
]

Array = NDArray[np.float64]


def interaction_matrix(xy: ArrayLike, Z: ArrayLike) -> Array:
    """The stacked interaction matrix (2N, 6) of N image points (the paper's equations 2 and 3).

    ``xy``: (N, 2) normalised image coordinates (x = X/Z, y = Y/Z, see
    ``CameraModel.normalized``); ``Z``: (N,) depths in metres (or one depth for all). Row
    pair i is ``[[-1/Z, 0, x/Z, x y, -(1 + x^2), y], [0, -1/Z, y/Z, 1 + y^2, -x y, -x]]``,
    so that ``d(x, y)/dt = L v_c``.
    """
    p = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    z = np.broadcast_to(np.asarray(Z, dtype=np.float64).reshape(-1), (len(p),))
    if np.any(z <= 0):
        raise ValueError("interaction_matrix: every depth Z must be positive (the point in front of the camera)")
    x, y = p[:, 0], p[:, 1]
    iz = 1.0 / z
    L = np.zeros((len(p), 2, 6))
    L[:, 0] = np.column_stack([-iz, np.zeros_like(x), x * iz, x * y, -(1 + x * x), y])
    L[:, 1] = np.column_stack([np.zeros_like(x), -iz, y * iz, 1 + y * y, -x * y, -x])
    return L.reshape(-1, 6)


def feature_error(s: ArrayLike, s_star: ArrayLike) -> Array:
    """``s - s*`` stacked (2N,) from two (N, 2) point sets in the same order."""
    return (np.asarray(s, dtype=np.float64).reshape(-1, 2) - np.asarray(s_star, dtype=np.float64).reshape(-1, 2)).reshape(-1)


def ibvs_velocity(
    s: ArrayLike,
    s_star: ArrayLike,
    Z: ArrayLike,
    lam: float = 0.5,
    *,
    camera: CameraModel | None = None,
    Z_star: ArrayLike | None = None,
    L_mode: str = "current",
) -> Array:
    """The IBVS camera twist ``v_c = -lam pinv(L) (s - s*)`` (6,) in the camera frame.

    ``s``, ``s_star``: current and desired points (N, 2) in the same order, normalised
    image coordinates, or pixels (x, y) when ``camera`` is given (then converted with its
    K). ``Z``: current depths (N,) or one value (metres; from the renderer's depth image,
    or an estimate). ``lam``: gain (1/s). ``L_mode``: "current" (L at s, Z; the paper's
    law), "desired" (L at s*, ``Z_star``) or "mean" (the mean of both, smoother paths).
    Returns (vx, vy, vz, wx, wy, wz) in m/s and rad/s.
    """
    cur = np.asarray(s, dtype=np.float64).reshape(-1, 2)
    des = np.asarray(s_star, dtype=np.float64).reshape(-1, 2)
    if cur.shape != des.shape:
        raise ValueError(f"s and s_star must have the same shape, got {cur.shape} and {des.shape}")
    if camera is not None:
        cur, des = camera.normalized(cur), camera.normalized(des)
    Zs = Z if Z_star is None else Z_star
    if L_mode == "current":
        L = interaction_matrix(cur, Z)
    elif L_mode == "desired":
        L = interaction_matrix(des, Zs)
    elif L_mode == "mean":
        L = 0.5 * (interaction_matrix(cur, Z) + interaction_matrix(des, Zs))
    else:
        raise ValueError(f"L_mode must be 'current', 'desired' or 'mean', got {L_mode!r}")
    return -float(lam) * (np.linalg.pinv(L) @ feature_error(cur, des))


def skew(w: ArrayLike) -> Array:
    """The (3, 3) matrix ``[w]x`` with ``[w]x v = w x v``."""
    a, b, c = np.asarray(w, dtype=np.float64).reshape(3)
    return np.array([[0.0, -c, b], [c, 0.0, -a], [-b, a, 0.0]])


def twist_transform(T_a_b: ArrayLike) -> Array:
    """The (6, 6) matrix that maps a twist (v, w) of frame b expressed in b to frame a's origin and axes.

    ``T_a_b``: (4, 4) pose of frame b in frame a. The twist of the same rigid body at a's
    origin, in a's axes, is ``[[R, [t]x R], [0, R]] @ (v_b, w_b)``.
    """
    T = np.asarray(T_a_b, dtype=np.float64)
    R, t = T[:3, :3], T[:3, 3]
    X = np.zeros((6, 6))
    X[:3, :3] = R
    X[:3, 3:] = skew(t) @ R
    X[3:, 3:] = R
    return X


def camera_twist_to_world(v_camera: ArrayLike, T_world_camera: ArrayLike) -> Array:
    """A camera twist (6,) in the camera frame -> (v of the camera origin, w) (6,) in world axes."""
    T = np.asarray(T_world_camera, dtype=np.float64)
    v = np.asarray(v_camera, dtype=np.float64).reshape(6)
    R = T[:3, :3]
    return np.concatenate([R @ v[:3], R @ v[3:]])


def eih_joint_velocities(
    v_camera: ArrayLike,
    J0: ArrayLike,
    T_world_tool: ArrayLike,
    T_tool_camera: ArrayLike,
    *,
    damping: float = 0.0,
) -> Array:
    """Joint rates (n,) that move an eye-in-hand camera with the twist ``v_camera``.

    ``v_camera``: (6,) (vx, vy, vz, wx, wy, wz) expressed in the camera frame (what
    ``ibvs_velocity`` gives). ``J0``: (6, n) world-frame Jacobian of the tool (rows vx vy
    vz wx wy wz: the tool origin's velocity and the angular velocity, world axes).
    ``T_world_tool``: (4, 4) tool pose; ``T_tool_camera``: (4, 4) camera pose on the tool.
    ``damping``: lambda of a damped least-squares inverse (0: the pseudo-inverse).

    The camera's world twist is ``(R v, R w)`` with ``R`` its world orientation; the tool
    origin, at ``r = p_camera - p_tool`` behind it, must then move with ``v_cam + r x w``.
    """
    Twt = np.asarray(T_world_tool, dtype=np.float64)
    Twc = Twt @ np.asarray(T_tool_camera, dtype=np.float64)
    vw = camera_twist_to_world(v_camera, Twc)
    r = Twc[:3, 3] - Twt[:3, 3]
    tool = np.concatenate([vw[:3] + np.cross(r, vw[3:]), vw[3:]])
    J = np.asarray(J0, dtype=np.float64)
    if damping > 0:
        JJt = J @ J.T + (float(damping) ** 2) * np.eye(6)
        return J.T @ np.linalg.solve(JJt, tool)
    return np.linalg.pinv(J) @ tool


def integrate_twist(T_world_camera: ArrayLike, v_camera: ArrayLike, dt: float) -> Array:
    """The camera pose (4, 4) after moving with the constant body twist ``v_camera`` (camera frame) for ``dt`` s.

    Exact SE(3) exponential: ``T @ expm(dt [v])``.
    """
    T = np.asarray(T_world_camera, dtype=np.float64)
    xi = np.asarray(v_camera, dtype=np.float64).reshape(6) * float(dt)
    v, w = xi[:3], xi[3:]
    th = float(np.linalg.norm(w))
    W = skew(w)
    if th < 1e-12:
        R = np.eye(3) + W
        V = np.eye(3) + 0.5 * W
    else:
        A = np.sin(th) / th
        B = (1 - np.cos(th)) / th**2
        Cc = (th - np.sin(th)) / th**3
        R = np.eye(3) + A * W + B * W @ W
        V = np.eye(3) + B * W + Cc * W @ W
    E = np.eye(4)
    E[:3, :3] = R
    E[:3, 3] = V @ v
    return T @ E


def match_points(points: ArrayLike, reference: ArrayLike) -> Array:
    """Reorder ``points`` (N, 2) to best match ``reference`` (N, 2) (minimum total distance).

    Detectors return features in their own order; servoing needs them in the order of the
    desired features. Uses the Hungarian algorithm (scipy).
    """
    from scipy.optimize import linear_sum_assignment

    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    r = np.asarray(reference, dtype=np.float64).reshape(-1, 2)
    cost = np.linalg.norm(r[:, None, :] - p[None, :, :], axis=2)
    rows, cols = linear_sum_assignment(cost)
    out = np.full_like(r, np.nan)
    out[rows] = p[cols]
    return out


def theta_u(R: ArrayLike) -> Array:
    """The rotation vector ``theta u`` (3,) of a rotation matrix (axis times angle, angle in [0, pi]).

    Accurate near 0 and near pi (where the axis comes from the symmetric part of R).
    """
    Rm = np.asarray(R, dtype=np.float64).reshape(3, 3)
    c = np.clip((np.trace(Rm) - 1.0) / 2.0, -1.0, 1.0)
    th = float(np.arccos(c))
    w = np.array([Rm[2, 1] - Rm[1, 2], Rm[0, 2] - Rm[2, 0], Rm[1, 0] - Rm[0, 1]])
    if th < 1e-8:
        return 0.5 * w
    if np.pi - th > 1e-4:
        return th * w / (2.0 * np.sin(th))
    # near pi: R ~ 2 u u^T - I; take the best column of (R + I) / 2 for u, its sign from w
    B = 0.5 * (Rm + np.eye(3))
    u = B[:, int(np.argmax(np.diag(B)))]
    u = u / np.linalg.norm(u)
    if np.dot(u, w) < 0:
        u = -u
    return th * u


def pbvs_velocity(T_camera_desired: ArrayLike, lam: float = 0.5) -> Array:
    """The classic PBVS camera twist (6,) in the current camera frame (Chaumette and Hutchinson 2006).

    ``T_camera_desired`` (4, 4): the desired camera pose expressed in the current camera's
    frame (with an object seen by PnP: ``T_camera_object @ inv(T_desired_object)``). With
    ``(R, t)`` the current camera's pose in the desired frame (the inverse), the law is
    ``v = -lam R^T t`` and ``w = -lam theta u(R)``: the error (t, theta u) decays
    exponentially and the camera centre moves on a straight line. Returns
    (vx, vy, vz, wx, wy, wz) in m/s and rad/s.
    """
    T = np.asarray(T_camera_desired, dtype=np.float64).reshape(4, 4)
    if not np.isfinite(T).all():
        raise ValueError("pbvs_velocity: T_camera_desired must be a finite 4 x 4 pose")
    Rcd, tcd = T[:3, :3], T[:3, 3]
    R = Rcd.T  # the current camera in the desired frame: R = Rcd^T, t = -Rcd^T tcd
    t = -R @ tcd
    return np.concatenate([-float(lam) * (R.T @ t), -float(lam) * theta_u(R)])


class ServoMonitor:
    """Watches a servo loop step by step and words the warnings a student should see.

    ``width``, ``height``: the image size in pixels; ``n_points``: how many features the
    loop needs; ``margin``: pixels from the border counted as leaving the image;
    ``retreat_factor``: warn when the mean depth of the features exceeds this multiple of
    its value at the first check (the camera retreating, as point IBVS does for rotations
    near 180 degrees about the optical axis).

    ``check(pixels, Z)`` returns the warnings that start at this step (each is given once,
    and again only after its condition has cleared); show them with ``alert``. With
    ``Z_goal`` (the features' depth at the goal) the retreat is measured from the larger of
    the start's depth and the goal's, so a goal farther away than the start is no retreat.
    ``reset()`` forgets the history (call it when the loop restarts).
    """

    def __init__(self, width: int, height: int, n_points: int, *, margin: float = 2.0, retreat_factor: float = 2.0) -> None:
        self.width, self.height, self.n_points = int(width), int(height), int(n_points)
        self.margin = float(margin)
        self.retreat_factor = float(retreat_factor)
        self.reset()

    def reset(self) -> None:
        """Forget the starting depth and the warnings given."""
        self.Z0: float | None = None
        self._last_Z: float | None = None
        self.active: set[str] = set()

    def check(self, pixels: ArrayLike, Z: ArrayLike | None = None, Z_goal: float | None = None) -> list[str]:
        """The new warnings at this step: ``pixels`` (N, 2) the features found (x, y), ``Z`` their depths (m),
        ``Z_goal`` their mean depth at the goal (m), if known."""
        p = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        now: dict[str, str] = {}
        m = self.margin
        inside = np.isfinite(p).all(axis=1) & (p[:, 0] >= m) & (p[:, 0] <= self.width - 1 - m) & (p[:, 1] >= m) & (p[:, 1] <= self.height - 1 - m)
        if len(p) < self.n_points or not inside.all():
            seen = int(inside.sum())
            now["leaving"] = (
                f"Features are leaving the image: {seen} of {self.n_points} inside it. The servo cannot "
                "see the whole target; move it back into view (a smaller gain or another start)."
            )
        if Z is not None and len(p) == self.n_points:
            z = np.asarray(Z, dtype=np.float64).reshape(-1)
            zm = float(np.mean(z)) if len(z) and np.isfinite(z).all() and (z > 0).all() else float("nan")
            if np.isfinite(zm):
                if self.Z0 is None:
                    self.Z0 = zm
                growing = self._last_Z is not None and zm > self._last_Z
                self._last_Z = zm
                ref = self.Z0 if Z_goal is None or not Z_goal > self.Z0 else float(Z_goal)
                if zm > self.retreat_factor * ref and (growing or "retreat" in self.active):
                    where = f"their {self.Z0:.2f} m at the start" if ref == self.Z0 else f"their {ref:.2f} m at the goal"
                    now["retreat"] = (
                        f"The camera is retreating: the features are {zm:.2f} m away, {zm / ref:.1f} times "
                        f"{where}, and still moving away. Point-feature IBVS does this "
                        "for rotations near 180 degrees about the optical axis (without bound at 180); "
                        "try PBVS, or start closer to the goal's orientation."
                    )
        new = [text for key, text in now.items() if key not in self.active]
        keep = self.active & {"retreat"} if Z is None or len(p) != self.n_points else set()
        self.active = set(now) | keep
        return new
