"""The Toolbox's further Jacobian and dynamics functions, on a Robot's own methods (private).

``Robot.hessian0``, ``jacob0_dot``, ``jacobm``, ``fdyn``, ``cinertia``, ``itorque``,
``gravjac``, ``paycap``, ``vellipse``/``fellipse`` and the robot-object collision checks
call these. Each is built from the generated ``jacob0``/``rne``/``inertia``/``accel``
(for one configuration or a batch) and follows Corke's Robotics Toolbox.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]

_ROWS = {"all": slice(0, 6), "trans": slice(0, 3), "rot": slice(3, 6)}


def hessian0(robot: Any, q: Array, J0: Array | None = None) -> Array:
    """Manipulator Hessian (n, 6, n) in the world frame: ``H[j, :, i] = dJ[:, i]/dq_j``
    (batched: (m, n, 6, n)). For joint columns ``v_i, w_i`` of ``jacob0``:
    ``H[j, :3, i] = w_j x v_i`` (j <= i) or ``w_i x v_j`` (j > i); ``H[j, 3:, i] = w_j x w_i``
    (j < i), else 0. Prismatic joints have ``w = 0`` (and move points along ``v = z``)."""
    J = robot.jacob0(q) if J0 is None else np.asarray(J0, dtype=float)
    n = J.shape[-1]
    v = np.swapaxes(J[..., :3, :], -1, -2)  # (..., n, 3) joint columns
    w = np.swapaxes(J[..., 3:, :], -1, -2)
    A = np.cross(w[..., :, None, :], v[..., None, :, :])  # (..., j, i, 3): w_j x v_i
    B = np.cross(w[..., :, None, :], w[..., None, :, :])  # w_j x w_i
    upper = np.triu(np.ones((n, n), dtype=bool))[..., None]  # j <= i
    lin = np.where(upper, A, np.swapaxes(A, -2, -3))
    ang = np.where(np.triu(np.ones((n, n), dtype=bool), 1)[..., None], B, 0.0)
    H = np.concatenate((lin, ang), axis=-1)  # (..., j, i, 6)
    return np.swapaxes(H, -1, -2)  # (..., j, 6, i)


def jacob0_dot(robot: Any, q: Array, qd: ArrayLike, H: Array | None = None) -> Array:
    """Time derivative of ``jacob0`` (6, n) at joint velocities qd: ``sum_j H[j] qd_j``."""
    H = hessian0(robot, q) if H is None else np.asarray(H, dtype=float)
    qd = np.asarray(qd, dtype=float)
    return np.einsum("...jri,...j->...ri", H, np.broadcast_to(qd, H.shape[:-3] + (H.shape[-3],)))


def jacobm(robot: Any, q: Array, axes: str = "all") -> Array:
    """Manipulability Jacobian (n, 1): ``dm/dq_i = m vec(J H_i^T) . vec((J J^T)^-1)`` for
    Yoshikawa's ``m = sqrt(det(J J^T))`` over the chosen rows (as the Toolbox)."""
    rows = _ROWS[axes]
    J = robot.jacob0(q)
    H = hessian0(robot, q, J)[:, rows, :]
    J = J[rows, :]
    JJ = J @ J.T
    m = float(np.sqrt(max(np.linalg.det(JJ), 0.0)))
    b = np.linalg.inv(JJ)
    out = np.array([m * float(np.sum((J @ H[i].T) * b)) for i in range(robot.n)])
    return out[:, None]


class FdynResult(NamedTuple):
    """``fdyn``'s answer: times ``t`` (k,), joint positions ``q`` and velocities ``qd`` (k, n)."""

    t: Array
    q: Array
    qd: Array


def fdyn(robot: Any, T: float, q0: ArrayLike, Q: Callable[..., ArrayLike] | None = None, Q_args: dict | None = None,
         qd0: ArrayLike | None = None, solver: str = "RK45", solver_args: dict | None = None,
         dt: float | None = None) -> FdynResult:
    """Integrate the forward dynamics for ``T`` seconds (the Toolbox's ``fdyn``): scipy's
    ``solver`` steps ``[q, qd]' = [qd, accel(q, qd, Q(robot, t, q, qd, **Q_args))]`` (zero
    torque without ``Q``); with ``dt`` the steps are resampled linearly on ``0, dt, ... < T``."""
    from scipy import integrate, interpolate

    n = robot.n
    q0 = np.asarray(q0, dtype=float).reshape(n)
    qd0 = np.zeros(n) if qd0 is None else np.asarray(qd0, dtype=float).reshape(n)
    if Q is not None and not callable(Q):
        raise ValueError("fdyn: Q must be a function Q(robot, t, q, qd) giving the joint torques")
    Q_args = Q_args or {}
    if not hasattr(integrate, solver):
        raise ValueError(f"fdyn: unknown scipy.integrate solver {solver!r} (RK45, RK23, DOP853, Radau, BDF, LSODA)")

    def rate(t: float, y: Array) -> Array:
        q, qd = y[:n], y[n:]
        tau = np.zeros(n) if Q is None else np.asarray(Q(robot, t, q, qd, **Q_args), dtype=float)
        if tau.shape != (n,) or not np.all(np.isfinite(tau)):
            raise RuntimeError(f"fdyn: the torque function must give {n} finite values, got {tau!r}")
        try:
            return np.concatenate((qd, robot.accel(q, qd, tau)))
        except np.linalg.LinAlgError as exc:
            raise np.linalg.LinAlgError(f"fdyn at t = {t:.6g} s: {exc}") from None

    integ = getattr(integrate, solver)(rate, t0=0.0, y0=np.concatenate((q0, qd0)), t_bound=float(T),
                                       **(solver_args or {}))
    ts, ys = [0.0], [np.concatenate((q0, qd0))]
    while integ.status == "running":
        integ.step()
        if integ.status == "failed":
            raise RuntimeError(f"fdyn: the {solver} solver failed at t = {integ.t:.6g} s")
        ts.append(integ.t)
        ys.append(integ.y.copy())
    t, y = np.array(ts), np.array(ys)
    if dt is not None:
        tn = np.arange(0.0, float(T), float(dt))
        y = interpolate.interp1d(t, y, axis=0)(tn)
        t = tn
    return FdynResult(t, y[:, :n], y[:, n:])


def cinertia(robot: Any, q: Array) -> Array:
    """Cartesian (operational-space) inertia (6, 6): ``J^-T M J^-1`` with the world-frame
    geometric Jacobian (a 6-joint arm away from singularities), so that the kinetic energy
    is ``1/2 nu^T Mx nu`` for the tool's spatial velocity ``nu = J qd``."""
    J = robot.jacob0(q)
    if J.shape[-1] != 6:
        raise ValueError(f"{robot.name}: cinertia needs a 6-joint arm (J square), this one has {J.shape[-1]}")
    Ji = np.linalg.inv(J)
    return np.swapaxes(Ji, -1, -2) @ robot.inertia(q) @ Ji


def gravjac(robot: Any, q: Array, gravity: ArrayLike | None = None) -> tuple[Array, Array]:
    """Gravity torques from the links' centre-of-mass Jacobians, ``tau = -sum_i m_i
    Jv_ci^T g``, and ``jacob0(q)``: (tau (n,), J (6, n)). A second method for ``gravload``
    (payload included, as in ``rne``)."""
    robot._params()
    g = robot.gravity if gravity is None else np.asarray(gravity, dtype=float)
    F = robot.fkine_all(q)  # (n+1, 4, 4) world frames
    n = robot.n
    axes = F[1:] if robot.mdh else F[:-1]
    z, o = axes[:, :3, 2], axes[:, :3, 3]
    tau = np.zeros(n)
    for i in range(n):
        c = F[i + 1][:3, :3] @ robot._r[i] + F[i + 1][:3, 3]
        f = robot._m[i] * g  # gravity force on link i
        for j in range(i + 1):
            jv = z[j] if robot._prism[j] else np.cross(z[j], c - o[j])
            tau[j] -= jv @ f
    return tau, robot.jacob0(q)


def paycap(robot: Any, q: Array, w: ArrayLike, tlim: ArrayLike, frame: str = "base") -> tuple[Any, Any]:
    """Static payload capacity (MATLAB Toolbox's ``paycap``): the largest multiple ``s`` of
    the wrench direction ``w`` (6,) that the tool can hold at q without any joint torque
    (gravity load included) leaving its limits ``tlim`` ((n,) symmetric, or (2, n) rows
    min, max). ``w`` is the wrench the payload applies to the tool, in the world frame
    (``frame="base"``) or the tool frame (``"ee"``). Returns ``(wmax, joint)``: the
    capacity and the joint (0-based) that reaches its limit first (per row for a batch)."""
    s = payload_capacity(robot, q, tlim, w, frame)
    s = np.where(np.isnan(s) | (s < 0), -np.inf, s)
    s = np.where(s == -np.inf, np.nan, s)
    with np.errstate(invalid="ignore"):
        joint = np.where(np.all(np.isnan(s), axis=-1), -1, np.nanargmin(np.where(np.isnan(s), np.inf, s), axis=-1))
    wmax = np.where(joint >= 0, np.take_along_axis(s, np.maximum(joint, 0)[..., None], axis=-1)[..., 0], np.nan)
    if np.ndim(q) == 1:
        return float(wmax[0]), int(joint[0])
    return wmax, joint


def payload_capacity(robot: Any, q: Array, tau_m: ArrayLike, w: ArrayLike, frame: str = "base") -> Array:
    """The Toolbox's ``payload_capacity``: per joint (m, n) the multiple ``s`` of ``w`` that
    takes it to its torque limit (inf if w does not load it, nan if gravity alone exceeds it)."""
    n = robot.n
    tm = np.asarray(tau_m, dtype=float).reshape(-1, n)
    tmin, tmax = (-tm[0], tm[0]) if tm.shape[0] == 1 else (tm[0], tm[1])
    w = np.asarray(w, dtype=float).reshape(6)
    if frame not in ("base", "ee"):
        raise ValueError(f"frame is {frame!r}, choose from: 'base', 'ee'")
    out = []
    for qk in np.atleast_2d(q):
        tg = robot.gravload(qk)
        J = robot.jacob0(qk) if frame == "base" else robot.jacobe(qk)
        tp = -J.T @ w
        bound = np.where(tp > 0, tmax, tmin)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(np.abs(tp) > 1e-10, (bound - tg) / tp, np.inf)
        s[(tg > tmax) | (tg < tmin)] = np.nan
        out.append(s)
    return np.array(out)


@dataclass
class Ellipsoid:
    """A velocity or force ellipsoid at the tool: ``centre`` (3,) in the world, semi-axes
    ``radii`` (3,) along the columns of ``axes`` (3, 3), and ``matrix`` E (3, 3): the points
    x with ``(x - centre)^T E^-1 (x - centre) <= 1`` (``E = J J^T`` for velocities, ``(J
    J^T)^-1`` for forces, J the chosen rows of ``jacob0``)."""

    centre: Array
    radii: Array
    axes: Array
    matrix: Array
    kind: str

    def contains(self, x: ArrayLike, tol: float = 1e-9) -> bool:
        """True when the point x (3,) (world frame) is inside or on the ellipsoid."""
        d = np.asarray(x, dtype=float) - self.centre
        return float(d @ np.linalg.solve(self.matrix, d)) <= 1.0 + tol

    def points(self, n: int = 24) -> Array:
        """Points (n*n, 3) on the surface, for drawing."""
        u, v = np.meshgrid(np.linspace(0, 2 * np.pi, n), np.linspace(0, np.pi, n))
        s = np.stack((np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)), axis=-1).reshape(-1, 3)
        return self.centre + (s * self.radii) @ self.axes.T


def ellipse(robot: Any, q: Array, opt: str, kind: str, centre: ArrayLike | str | None) -> Ellipsoid:
    """The velocity (``kind="velocity"``) or force ellipsoid of the translational
    (``opt="trans"``) or rotational (``"rot"``) rows of ``jacob0`` at q."""
    if opt not in ("trans", "rot"):
        raise ValueError(f"opt must be 'trans' or 'rot', got {opt!r}")
    J = robot.jacob0(q)[_ROWS[opt], :]
    U, sv, _ = np.linalg.svd(J)
    if kind == "velocity":
        E = J @ J.T
        radii = sv
    else:
        E = np.linalg.inv(J @ J.T)
        radii = 1.0 / sv
    if centre is None or (isinstance(centre, str) and centre == "ee"):
        c = robot.fkine(q)[:3, 3] if opt == "trans" else np.zeros(3)
    else:
        c = np.asarray(centre, dtype=float).reshape(3)
    return Ellipsoid(c, radii, U, E, kind)


# ---------------------------------------------------------------------------- collisions
def link_shapes(robot: Any) -> list[list[tuple[Any, Array]]]:
    """Collision shapes of each link frame 0..n: ``(CollisionShape, T_link_shape)`` pairs;
    the convex hull of each visual piece for a model with ``visuals`` (a URDF arm), else
    the capsules and cylinders of the automatic link geometry. Cached per parameters."""
    from ejsrl.world.collision import CollisionShape
    from ejsrl.world.robot_node import _geometry_key, robot_geometry

    key = _geometry_key(robot)
    cache = robot.__dict__.get("_shapes_cache")
    if cache is not None and cache[0] == key:
        return cache[1]
    eye = np.eye(4)
    out: list[list[tuple[Any, Array]]] = []
    if getattr(robot, "visuals", None):
        for pieces in robot.visuals:
            out.append([(CollisionShape.convex(m.vertices), eye) for vis in pieces for m in vis.trimeshes()])
    else:
        _, shapes = robot_geometry(robot)
        for sh in shapes:
            row = []
            for s in sh:
                if s.kind == "capsule":
                    row.append((CollisionShape.capsule(s.p0, s.p1, s.radius), eye))
                else:
                    row.append((CollisionShape.cylinder(s.radius, s.height), s.T_link_shape))
            out.append(row)
    robot.__dict__["_shapes_cache"] = (key, out)
    return out


def collided_links(robot: Any, q: Array, shape: Any, T_world_shape: ArrayLike | None, margin: float,
                   skip_base: bool) -> list[int]:
    """Indices of the link frames (0 = base) whose shapes touch ``shape`` placed at
    ``T_world_shape`` (or come closer than ``margin``)."""
    from ejsrl.world.collision import CollisionShape, intersects

    if not isinstance(shape, CollisionShape):
        raise TypeError("shape must be an ejsrl.world.collision.CollisionShape, e.g. CollisionShape.box([0.1, 0.1, 0.1])")
    Ts = np.eye(4) if T_world_shape is None else np.asarray(T_world_shape, dtype=float)
    F = robot.fkine_all(q)
    hits = []
    for i, pieces in enumerate(link_shapes(robot)):
        if skip_base and i == 0:
            continue
        if any(intersects(s, F[i] @ T, shape, Ts, margin=margin) for s, T in pieces):
            hits.append(i)
    return hits
