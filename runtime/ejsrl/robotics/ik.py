"""Inverse kinematics: numerical (Levenberg-Marquardt) and closed form (Puma type).

Both answer with an :class:`IKSolution`: ``q``, ``success``, ``iterations``, ``residual``
(norm of the weighted pose error) and ``reason`` when it fails.

Pose error (world frame): ``e = [p* - p, log(R* R^T)]`` (m, rad), the translation and the
angle-axis vector of the remaining rotation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .transforms import tr2angvec_vec

if TYPE_CHECKING:
    from .robot import Robot

__all__ = ["IKSolution", "ikine", "ikine_a", "ikine_a_all", "pose_error"]

Array = NDArray[np.float64]


@dataclass
class IKSolution:
    """Result of an inverse-kinematics call.

    Attributes:
        q: (n,) joint values (the best found, even on failure).
        success: True only when the (masked) position error is below ``tol`` m and the
            orientation error below ``tol`` rad.
        iterations: total iterations over all searches.
        searches: number of starts used (1 + restarts).
        residual: norm of the final weighted pose error.
        reason: why it failed ("" on success).
    """

    q: Array
    success: bool
    iterations: int = 0
    searches: int = 1
    residual: float = np.inf
    reason: str = ""
    pos_error: float = field(default=np.inf, repr=False)
    rot_error: float = field(default=np.inf, repr=False)

    def __iter__(self):  # allows ``q, ok, *_ = robot.ikine(T)``
        return iter((self.q, self.success, self.iterations, self.searches, self.residual, self.reason))


_rot_error = tr2angvec_vec  # log of a rotation, robust near 0 and pi


def pose_error(T_goal: ArrayLike, T: ArrayLike) -> Array:
    """Pose error (6,) ``[p* - p, log(R* R^T)]`` between two (4, 4) poses, world frame."""
    Tg = np.asarray(T_goal, dtype=float)
    Tc = np.asarray(T, dtype=float)
    e = np.empty(6)
    e[:3] = Tg[:3, 3] - Tc[:3, 3]
    e[3:] = _rot_error(Tg[:3, :3] @ Tc[:3, :3].T)
    return e


def ikine(
    robot: "Robot",
    T: ArrayLike,
    q0: ArrayLike | None = None,
    *,
    mask: ArrayLike | None = None,
    tol: float = 1e-10,
    ilimit: int = 30,
    slimit: int = 100,
    joint_limits: bool = True,
    seed: int | None = 0,
    lam: float = 1e-3,
) -> IKSolution:
    """Numerical inverse kinematics by damped least squares (Levenberg-Marquardt).

    Solves ``robot.fkine(q) == T`` (tool and base included). Each iteration solves
    ``(J^T W J + (E + lam) I) dq = J^T W e`` with ``E = e^T W e / 2`` (Sugihara's damping:
    quadratic convergence near the solution), accepts steps that reduce E and otherwise
    raises the damping. Joint values are kept inside ``qlim``. A search that has not
    converged after ``ilimit`` iterations restarts from a random seed within the limits,
    up to ``slimit`` searches.

    Args:
        T: goal pose ``T_world_tool`` (4, 4).
        q0: initial guess (n,); default the middle of the joint ranges.
        mask: (6,) weights on ``[x y z rx ry rz]``; for arms with fewer than 6 joints pass
            e.g. ``[1, 1, 0, 0, 0, 1]`` (planar x, y and yaw). Unweighted axes are ignored
            by the success test.
        tol: position (m) and orientation (rad) error below which the search succeeds.
        joint_limits: respect ``qlim`` (default True).
        seed: seed of the random restarts (reproducible by default).
    """
    n = robot.n
    Tg = np.asarray(T, dtype=float)
    W = np.ones(6) if mask is None else np.asarray(mask, dtype=float).reshape(6)
    lim = robot.qlim
    finite = np.isfinite(lim)
    lo = np.where(finite[0], lim[0], -np.pi)
    hi = np.where(finite[1], lim[1], np.pi)
    if not joint_limits:
        lim = np.vstack((np.full(n, -np.inf), np.full(n, np.inf)))
    qmin, qmax = lim.tolist()
    if q0 is None:
        q = (0.5 * (lo + hi)).tolist()
    else:
        q = np.clip(np.asarray(q0, dtype=float).reshape(n), lim[0], lim[1]).tolist()
    rng = np.random.default_rng(seed)
    # One generated pass gives the pose and the Jacobian; the damped step is another.
    pose_jacob = robot._kernel(("pose_jacob0",)).single
    lm_step = robot._kernel(("lm_step",)).single
    w = W.tolist()
    pidx = [k for k in range(3) if w[k] > 0]
    ridx = [k for k in range(3, 6) if w[k] > 0]
    goal = Tg[:3, :].tolist()

    def evaluate(qv: list[float]) -> tuple[list[float], tuple, float]:
        v = pose_jacob(*qv)
        e = _pose_error_rows(goal, v)
        return e, v[16:], 0.5 * sum(wk * ek * ek for wk, ek in zip(w, e))

    def converged(e: list[float]) -> bool:
        return all(abs(e[k]) < tol for k in pidx) and all(abs(e[k]) < tol for k in ridx)

    total = 0
    best_q, best_E, best_e = list(q), np.inf, [np.inf] * 6
    for search in range(1, slimit + 1):
        e, J, E = evaluate(q)
        damp = lam
        for _ in range(ilimit):
            if converged(e):
                break
            total += 1
            dq = lm_step(*J, *e, *w, E + damp)
            if joint_limits:
                qn = [min(max(qi + di, a), b) for qi, di, a, b in zip(q, dq, qmin, qmax)]
            else:
                qn = [qi + di for qi, di in zip(q, dq)]
            en, Jn, En = evaluate(qn)
            if En < E:
                q, e, J, E = qn, en, Jn, En
                damp = max(damp * 0.5, 1e-9)
            else:
                damp *= 10.0
                if damp > 1e6:
                    break
        if E < best_E:
            best_q, best_E, best_e = list(q), E, list(e)
        if converged(e):
            pos_err = max((abs(e[k]) for k in pidx), default=0.0)
            rot_err = max((abs(e[k]) for k in ridx), default=0.0)
            return IKSolution(q=np.array(q), success=True, iterations=total, searches=search,
                              residual=float(np.sqrt(2 * E)), pos_error=pos_err, rot_error=rot_err)
        q = rng.uniform(lo, hi).tolist()
    pos_err = float(np.sqrt(sum(best_e[k] ** 2 for k in pidx)))
    rot_err = float(np.sqrt(sum(best_e[k] ** 2 for k in ridx)))
    return IKSolution(
        q=np.array(best_q), success=False, iterations=total, searches=slimit, residual=float(np.sqrt(2 * best_E)),
        reason=f"no solution within tolerance after {slimit} searches (best position error {pos_err:.3g} m, "
        f"orientation error {rot_err:.3g} rad): the pose may be out of reach or outside the joint limits",
        pos_error=pos_err, rot_error=rot_err,
    )


def _pose_error_rows(goal: list[list[float]], v: tuple) -> list[float]:
    """:func:`pose_error` on plain floats: ``goal`` the top rows (3, 4) of the goal pose,
    ``v`` the current pose row-major (first 12 values used)."""
    g0, g1, g2 = goal
    r0, r1, r2 = v[0:3], v[4:7], v[8:11]
    # M = R* R^T (only the entries the logarithm needs)
    m00 = g0[0] * r0[0] + g0[1] * r0[1] + g0[2] * r0[2]
    m11 = g1[0] * r1[0] + g1[1] * r1[1] + g1[2] * r1[2]
    m22 = g2[0] * r2[0] + g2[1] * r2[1] + g2[2] * r2[2]
    m01 = g0[0] * r1[0] + g0[1] * r1[1] + g0[2] * r1[2]
    m10 = g1[0] * r0[0] + g1[1] * r0[1] + g1[2] * r0[2]
    m02 = g0[0] * r2[0] + g0[1] * r2[1] + g0[2] * r2[2]
    m20 = g2[0] * r0[0] + g2[1] * r0[1] + g2[2] * r0[2]
    m12 = g1[0] * r2[0] + g1[1] * r2[1] + g1[2] * r2[2]
    m21 = g2[0] * r1[0] + g2[1] * r1[1] + g2[2] * r1[2]
    vx, vy, vz = m21 - m12, m02 - m20, m10 - m01
    c = 0.5 * (m00 + m11 + m22 - 1.0)
    s = 0.5 * math.sqrt(vx * vx + vy * vy + vz * vz)
    e = [g0[3] - v[3], g1[3] - v[7], g2[3] - v[11]]
    if s > 1e-6:
        k = math.atan2(s, c) / (2.0 * s)
        return e + [vx * k, vy * k, vz * k]
    if c > 0:
        return e + [0.5 * vx, 0.5 * vy, 0.5 * vz]
    M = np.array([[m00, m01, m02], [m10, m11, m12], [m20, m21, m22]])
    return e + _rot_error(M).tolist()  # near pi: the general logarithm


# ---------------------------------------------------------------------------- closed form
_PUMA_ALPHA = np.array([np.pi / 2, 0.0, -np.pi / 2, np.pi / 2, -np.pi / 2, 0.0])


def _check_puma(robot: "Robot") -> None:
    ok = (
        robot.n == 6
        and not robot.mdh
        and not robot._prism.any()
        and np.allclose(robot._alpha, _PUMA_ALPHA)
        and np.allclose(robot._a[[0, 3, 4, 5]], 0.0)
        and np.allclose(robot._d[[1, 4]], 0.0)
    )
    if not ok:
        raise ValueError(
            f"{robot.name}: ikine_a needs a Puma-type 6R arm (standard DH, alpha = [90, 0, -90, 90, -90, 0] deg, "
            "a1 = a4 = a5 = a6 = 0, d2 = d5 = 0, spherical wrist); use ikine() for this arm"
        )


def _wrap(a: Array | float) -> Array:
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def ikine_a_all(robot: "Robot", T: ArrayLike) -> tuple[Array, list[str]]:
    """All closed-form solutions of a Puma-type arm: ``(k, 6)`` joint values (k <= 8) and
    their configuration strings (see :func:`ikine_a`). Joint limits are not applied."""
    robot._params()
    _check_puma(robot)
    a2, a3 = robot._a[1], robot._a[2]
    d1, d3, d4, d6 = robot._d[0], robot._d[2], robot._d[3], robot._d[5]
    T06 = np.linalg.inv(robot.base) @ np.asarray(T, dtype=float) @ np.linalg.inv(robot.tool)
    pw = T06[:3, 3] - d6 * T06[:3, 2]  # wrist centre
    px, py, pz = pw[0], pw[1], pw[2] - d1
    rho2 = px * px + py * py
    sols: list[Array] = []
    confs: list[str] = []
    if rho2 < d3 * d3:
        return np.empty((0, 6)), []
    rho = np.sqrt(rho2)
    phi = np.arctan2(py, px)
    L3 = np.hypot(a3, d4)
    beta = np.arctan2(d4, a3)
    for arm in ("l", "r"):
        delta = np.arcsin(d3 / rho)
        th1 = phi + delta if arm == "r" else phi + np.pi - delta
        c1, s1 = np.cos(th1), np.sin(th1)
        X = px * c1 + py * s1
        Y = pz
        K = (X * X + Y * Y - a2 * a2 - a3 * a3 - d4 * d4) / (2 * a2)
        if abs(K) > L3 * (1 + 1e-12):
            continue
        g = np.arccos(np.clip(K / L3, -1.0, 1.0))
        for elbow in ("u", "d"):
            th3 = -beta + (g if elbow == "u" else -g)
            c3, s3 = np.cos(th3), np.sin(th3)
            u = a2 + a3 * c3 - d4 * s3
            v = a3 * s3 + d4 * c3
            th2 = np.arctan2(Y, X) - np.arctan2(v, u)
            q123 = np.array([th1, th2, th3, 0.0, 0.0, 0.0]) - robot._offset
            A = robot._A(q123)
            R03 = (A[0] @ A[1] @ A[2])[:3, :3]
            R = R03.T @ T06[:3, :3]  # = Rz(th4) Ry(-th5) Rz(th6)
            sb = np.hypot(R[0, 2], R[1, 2])
            for wrist in ("n", "f"):
                if sb < 1e-12:  # wrist singular: only th4 + th6 is determined
                    th4 = 0.0
                    th5 = 0.0 if R[2, 2] > 0 else np.pi
                    th6 = np.arctan2(R[1, 0], R[0, 0]) if R[2, 2] > 0 else np.arctan2(-R[1, 0], -R[0, 0])
                    if wrist == "f":
                        th4, th6 = th4 + np.pi, th6 + np.pi
                        th5 = -th5
                else:
                    sgn = 1.0 if wrist == "n" else -1.0
                    th5 = -np.arctan2(sgn * sb, R[2, 2])  # Euler Y angle is -th5
                    th4 = np.arctan2(sgn * R[1, 2], sgn * R[0, 2])
                    th6 = np.arctan2(sgn * R[2, 1], -sgn * R[2, 0])
                theta = np.array([th1, th2, th3, th4, th5, th6])
                sols.append(_wrap(theta - robot._offset))
                confs.append(arm + elbow + wrist)
    return (np.array(sols) if sols else np.empty((0, 6))), confs


def ikine_a(robot: "Robot", T: ArrayLike, config: str = "lun") -> IKSolution:
    """Closed-form inverse kinematics of a Puma-type 6R arm with a spherical wrist.

    ``config`` picks one of the 8 solutions with three letters (any order): ``l``/``r``
    shoulder branch (left/right arm), ``u``/``d`` elbow up/down, ``n``/``f`` wrist
    no-flip/flip (``n``: the Euler angle ``-q5`` of the wrist is taken in [0, pi]).
    ``success`` is False when the pose is out of reach; limits are reported in ``reason``
    but not enforced.
    """
    sols, confs = ikine_a_all(robot, T)
    want = {c for c in config.lower()}
    for q, c in zip(sols, confs):
        if set(c) <= want | set(c) and set(c) >= (want & set("lrudnf")):
            err = pose_error(T, robot.fkine(q))
            lim = robot.qlim
            inside = bool(np.all((q >= lim[0] - 1e-12) & (q <= lim[1] + 1e-12)))
            return IKSolution(q=q, success=True, iterations=0, residual=float(np.linalg.norm(err)),
                              reason="" if inside else "solution outside the joint limits",
                              pos_error=float(np.linalg.norm(err[:3])), rot_error=float(np.linalg.norm(err[3:])))
    return IKSolution(q=np.full(6, np.nan), success=False, reason=f"pose out of reach for configuration {config!r}")
