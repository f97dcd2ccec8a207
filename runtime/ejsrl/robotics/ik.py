"""Inverse kinematics: closed-form seeds polished by Levenberg-Marquardt, and closed form (Puma type).

Both answer with an :class:`IKSolution`: ``q``, ``success``, ``iterations``, ``residual``
(norm of the weighted pose error) and ``reason`` when it fails.

Pose error (world frame): ``e = [p* - p, log(R* R^T)]`` (m, rad), the translation and the
angle-axis vector of the remaining rotation.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _ik_closed, _ik_fast
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
        success: True only when the (masked) position error norm is below ``tol`` m and
            the orientation error (rotation angle) below ``tol`` rad, checked by forward
            kinematics.
        iterations: total Levenberg-Marquardt iterations over all searches (0 when a
            closed-form solution was exact).
        searches: number of starts used: closed-form candidates tried, or 1 + restarts
            (0 when the pose was rejected before any search).
        residual: norm of the final weighted pose error.
        reason: why it failed ("" on success).
        pos_error, rot_error: norms of the position (m) and orientation (rad) errors.
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
    closed_form: bool = True,
) -> IKSolution:
    """Inverse kinematics: closed-form seeds where the arm has them, polished and
    otherwise searched by damped least squares (Levenberg-Marquardt).

    Solves ``robot.fkine(q) == T`` (tool and base included) to ``tol`` in position (m)
    and orientation (rad), each measured as the norm of its part of the pose error.

    - Arms with a closed form (Puma 560 type, Universal Robots type, 7R S-R-S arms such
      as the PA-10; see :mod:`._ik_closed`): all solutions are computed, moved into the
      joint limits by whole turns, and tried nearest to ``q0`` first; each is checked by
      forward kinematics and polished by a few LM steps if needed (near singularities).
      For a 7R arm joint 3 is the free angle: first ``q0``'s, then a sweep of its range.
      A pose no configuration reaches is rejected at once; one reached only outside the
      joint limits after a short search from the nearest solutions. Should no
      candidate polish to ``tol`` (never seen in the tests), the LM search below
      takes over from the best of them.
    - Other arms, or when ``mask`` is given or ``closed_form=False``: LM iterations
      ``(J^T W J + (E + lam) I) dq = J^T W e`` with ``E = e^T W e / 2`` (Sugihara's
      damping), steps accepted when they reduce E (the extra damping then divided by
      10) and otherwise damped 10x harder; joint values clamped to ``qlim``. A search that has not converged
      after ``ilimit`` iterations restarts from a random configuration within the
      limits, up to ``slimit`` searches. A position farther from the base than the arm's
      reach (the sum of its links' lengths) is rejected at once. With numba installed
      (``pip install 'ejsgen[fast]'``) these searches run compiled (:mod:`._ik_numba`,
      1-2 us an iteration; loaded in the background from the first search, see
      :mod:`._ik_fast`); there every other restart searches without clamping and moves its
      answer into the limits by whole turns, a clamped search's joints stop on their limits
      while the others go on (an active set), the extra damping follows each step's gain
      ratio, ill-conditioned steps are solved by QR, and a search within 1e-4 of its goal
      may take up to ``3 ilimit`` iterations (``10 ilimit`` while its error halves every
      ``ilimit``).

    Args:
        T: goal pose ``T_world_tool`` (4, 4).
        q0: initial guess / preferred configuration (n,); default the middle of the
            joint ranges.
        mask: (6,) weights on ``[x y z rx ry rz]``; for arms with fewer than 6 joints pass
            e.g. ``[1, 1, 0, 0, 0, 1]`` (planar x, y and yaw). Unweighted axes are ignored
            by the success test.
        tol: position (m) and orientation (rad) error below which the search succeeds.
        joint_limits: respect ``qlim`` (default True).
        seed: seed of the random restarts (reproducible by default).
        closed_form: use the arm's closed-form solutions as seeds (default True).
    """
    n = robot.n
    Tg = np.asarray(T, dtype=float)
    full = mask is None
    W = _FULL if full else np.asarray(mask, dtype=float).reshape(6)
    prob = _Problem(_setup(robot, joint_limits), Tg, W, tol, lam)
    lo, hi = prob.lo, prob.hi
    if q0 is None:
        q = prob.mid
    else:
        q = np.clip(np.asarray(q0, dtype=float).reshape(n), prob.qmin, prob.qmax).tolist()
    if prob.out_of_reach():
        return prob.fail(q, 0, 0, f"pose out of reach: the position is farther from the base than the arm's "
                         f"reach ({prob.setup.reach:.4g} m)")
    if closed_form and (full or bool(np.all(W == 1.0))) and prob.finite_goal():
        cf = prob.setup.closed
        if cf is not None:
            sol = _ikine_closed(prob, cf, Tg, q, ilimit)
            if isinstance(sol, IKSolution):
                return sol
            q = sol  # candidates within the limits that did not polish: search from the best
    compiled = _ik_fast.compiled_for(prob.setup)
    if compiled is not None:  # the same searches, compiled (numba)
        ok, total, searches, E, q, e = compiled.run(Tg, q, W, tol, lam, ilimit, slimit, seed, prob.joint_limits)
        if ok:
            return prob.success(q, e, E, total, searches)
        return prob.fail(q, total, slimit, "no solution within tolerance after {s} searches ({err}): the pose may be "
                         "out of reach or outside the joint limits", e=e, E=E)
    rng = np.random.default_rng(seed)
    total = 0
    best = None
    for search in range(1, slimit + 1):
        q, e, E, it, ok = prob.lm(q, ilimit)
        total += it
        if ok:
            return prob.success(q, e, E, total, search)
        if best is None or E < best[2]:
            best = (q, e, E)
        q = rng.uniform(lo, hi).tolist()
    return prob.fail(best[0], total, slimit, "no solution within tolerance after {s} searches ({err}): the pose may be "
                     "out of reach or outside the joint limits", e=best[1], E=best[2])


_FULL = np.ones(6)
_FULL_W = [1.0] * 6
_PIDX = [0, 1, 2]
_RIDX = [3, 4, 5]


def _ikine_closed(prob: "_Problem", cf: _ik_closed.ClosedForm, Tg: Array, q_ref: list[float],
                  ilimit: int) -> IKSolution | list[float]:
    """:func:`ikine` for an arm with a closed form (see there); the best candidate's
    joints instead of an answer when candidates within the limits did not polish."""
    tried = 0
    total = 0
    found = False
    best_inside: tuple[list[float], float] | None = None
    outside: list[list[float]] = []
    sweep: list[float] | None = None
    q3 = None
    while True:
        inside = 0
        for s, _ in cf.candidates(Tg, q_ref, q3):
            found = True
            qs = prob.into_limits(s, q_ref)
            if qs is None:
                outside.append(s)
                continue
            inside += 1
            tried += 1
            q, e, E, it, ok = prob.polish(qs, ilimit)
            total += it
            if ok:
                return prob.success(q, e, E, total, tried)
            if best_inside is None or E < best_inside[1]:
                best_inside = (q, E)
        if not found:  # no configuration reaches the pose, with or without limits
            return prob.fail(q_ref, 0, 0, "pose out of reach: no configuration of the arm reaches it "
                             "(errors at q0: {err}; closed_form=False searches for the closest approach)")
        if inside or cf.kind != "srs":
            break
        if sweep is None:
            sweep = _q3_sweep(prob, q_ref)
        if not sweep:
            break
        q3 = sweep.pop(0)  # 7R: no solution within the limits at this q3, try another
    if best_inside is not None:
        return best_inside[0]
    # reachable only outside the limits (or a singular family the seeds missed): short
    # LM searches from the nearest solutions clamped into the limits
    best = None
    outside.sort(key=lambda s: sum((a - b) ** 2 for a, b in zip(prob.clamp(s), q_ref)))
    compiled = _ik_fast.compiled_for(prob.setup) if cf.kind == "srs" and outside else None
    if compiled is not None:
        # a 7R arm's self-motion may reach the limits between the swept values of joint 3
        # (seen at a singular wrist with joint 3 near its limit): compiled searches, whose
        # steps stop on the limits, from the nearest solution clamped into them
        ok, it, searches, E, q, e = compiled.run(Tg, prob.clamp(outside[0]), np.asarray(prob.w, dtype=float),
                                                 prob.tol, prob.lam, ilimit, 10, 0, True)
        total += it
        tried += searches
        if ok:
            return prob.success(q, e, E, total, tried)
        best = (q, e, E)
    for s in outside[:2]:
        tried += 1
        q, e, E, it, ok = prob.lm(prob.clamp(s), min(ilimit, 10))
        total += it
        if ok:
            return prob.success(q, e, E, total, tried)
        if best is None or E < best[2]:
            best = (q, e, E)
    if best is None:
        q, e, E, it, _ = prob.lm(q_ref, min(ilimit, 10))
        best = (q, e, E)
        total += it
    return prob.fail(best[0], total, tried, "the pose is reachable, but no solution within the joint limits was "
                     "found ({err})", e=best[1], E=best[2])


def _q3_sweep(prob: "_Problem", q_ref: list[float]) -> list[float]:
    """Values of joint 3 to try on a 7R arm, nearest to ``q_ref`` first."""
    lo, hi = prob.lo[2], prob.hi[2]
    grid = [lo + (hi - lo) * (k + 0.5) / 16 for k in range(16)]
    grid.sort(key=lambda v: abs(v - q_ref[2]))
    return grid


_TWO_PI = 2.0 * math.pi


class _Setup:
    """What every IK call on one arm needs (cached with its generated kernels): limits as
    floats, the kernels, the closed-form solver and the reach."""

    def __init__(self, robot: "Robot", joint_limits: bool) -> None:
        n = self.n = robot.n
        self.robot = robot
        lim = robot.qlim
        finite = np.isfinite(lim)
        self.lo = np.where(finite[0], lim[0], -np.pi).tolist()
        self.hi = np.where(finite[1], lim[1], np.pi).tolist()
        self.mid = [0.5 * (a + b) for a, b in zip(self.lo, self.hi)]
        if not joint_limits:
            lim = np.vstack((np.full(n, -np.inf), np.full(n, np.inf)))
        self.joint_limits = joint_limits
        self.qmin, self.qmax = lim.tolist()
        self.fk = robot._kernel(("fkine",)).single
        self.closed = _ik_closed.solver(robot)
        self.base_inv_rows = None if robot._base_is_eye else np.linalg.inv(robot.base)[:3].tolist()
        self.reach = self._reach()

    @functools.cached_property
    def pose_jacob(self) -> Callable[..., tuple]:
        """Pose and Jacobian kernel, generated on first use (the closed form rarely needs it)."""
        return self.robot._kernel(("pose_jacob0",)).single

    @functools.cached_property
    def lm_step(self) -> Callable[..., tuple]:
        return self.robot._kernel(("lm_step",)).single

    def _reach(self) -> float:
        """Upper bound on the distance from the base origin to the tool point (m): the sum
        of the links' ``sqrt(a^2 + d^2)`` (largest ``d`` for a prismatic joint)."""
        r = self.robot
        total = 0.0
        for j in range(self.n):
            if r._prism[j]:
                lo, hi = self.qmin[j] + r._offset[j], self.qmax[j] + r._offset[j]
                dmax = max(abs(lo), abs(hi))
            else:
                dmax = abs(r._d[j])
            total += math.hypot(r._a[j], dmax)
            if r.ets:  # an ETSLink's constant transform (URDF arms) moves the joint too
                total += float(np.linalg.norm(r.links[j].origin[:3, 3]))
        return total + float(np.linalg.norm(r.tool[:3, 3]))


def _setup(robot: "Robot", joint_limits: bool) -> _Setup:
    robot._params()
    key = ("ik_setup", joint_limits)
    s = robot._kernels.get(key)
    if s is None:
        s = robot._kernels[key] = _Setup(robot, joint_limits)
    return s


class _Problem:
    """One inverse-kinematics problem on Python floats: the goal and weights, with the
    arm's :class:`_Setup` (limits, generated kernels)."""

    def __init__(self, setup: _Setup, Tg: Array, W: Array, tol: float, lam: float) -> None:
        self.setup = setup
        self.n = setup.n
        self.lo, self.hi, self.mid = setup.lo, setup.hi, setup.mid
        self.qmin, self.qmax = setup.qmin, setup.qmax
        self.joint_limits = setup.joint_limits
        self.fk = setup.fk
        self.Tg = Tg
        self.goal = Tg[:3, :].tolist()
        if W is _FULL:
            self.w, self.pidx, self.ridx = _FULL_W, _PIDX, _RIDX
        else:
            self.w = W.tolist()
            self.pidx = [k for k in range(3) if self.w[k] > 0]
            self.ridx = [k for k in range(3, 6) if self.w[k] > 0]
        self.tol = tol
        self.lam = lam

    def finite_goal(self) -> bool:
        return math.isfinite(sum(self.goal[0]) + sum(self.goal[1]) + sum(self.goal[2]))

    # ------------------------------------------------------------------ errors
    def _E(self, e: list[float]) -> float:
        if self.w is _FULL_W:
            return 0.5 * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2] + e[3] * e[3] + e[4] * e[4] + e[5] * e[5])
        return 0.5 * sum(wk * ek * ek for wk, ek in zip(self.w, e))

    def errors(self, e: list[float]) -> tuple[float, float]:
        """Norms of the (weighted-in) position and orientation errors."""
        if self.pidx is _PIDX and self.ridx is _RIDX:
            return (math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]),
                    math.sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5]))
        return (math.sqrt(sum(e[k] * e[k] for k in self.pidx)), math.sqrt(sum(e[k] * e[k] for k in self.ridx)))

    def converged(self, e: list[float]) -> bool:
        pe, re = self.errors(e)
        return pe < self.tol and re < self.tol

    def evaluate(self, q: list[float]) -> tuple[list[float], tuple, float]:
        v = self.setup.pose_jacob(*q)
        e = _pose_error_rows(self.goal, v)
        return e, v[16:], self._E(e)

    # ------------------------------------------------------------------ joint values
    def clamp(self, q: list[float]) -> list[float]:
        return [min(max(v, a), b) for v, a, b in zip(q, self.qmin, self.qmax)]

    def into_limits(self, q: list[float], ref: list[float]) -> list[float] | None:
        """``q`` with each angle moved by whole turns into the limits, nearest to ``ref``;
        None if a joint cannot be."""
        out = []
        for v, r, a, b in zip(q, ref, self.qmin, self.qmax):
            d = r - v
            if d > math.pi or d < -math.pi:
                v = v + _TWO_PI * round(d / _TWO_PI)  # nearest to the reference
            if v < a or v > b:
                best = None
                for k in (-2, -1, 1, 2):
                    u = v + k * _TWO_PI
                    if a - 1e-12 <= u <= b + 1e-12 and (best is None or abs(u - r) < abs(best - r)):
                        best = u
                if best is None:
                    return None
                v = min(max(best, a), b)
            out.append(v)
        return out

    # ------------------------------------------------------------------ searches
    def lm(self, q: list[float], ilimit: int) -> tuple[list[float], list[float], float, int, bool]:
        """One LM search from ``q``: ``(q, e, E, iterations, converged)``."""
        e, J, E = self.evaluate(q)
        damp = self.lam
        it = 0
        w = self.w
        lm_step = self.setup.lm_step
        clamp = self.joint_limits
        while not self.converged(e):
            if it >= ilimit:
                return q, e, E, it, False
            it += 1
            try:
                dq = lm_step(*J, *e, *w, E + damp)
            except (ZeroDivisionError, OverflowError, ValueError):
                dq = None
            if dq is not None:
                qn = [a + b for a, b in zip(q, dq)]
                if clamp:
                    qn = self.clamp(qn)
                en, Jn, En = self.evaluate(qn)
            if dq is not None and En < E:
                q, e, J, E = qn, en, Jn, En
                damp = max(damp * 0.1, 1e-20)
            else:
                damp *= 10.0
                if damp > 1e6:
                    return q, e, E, it, False
        return q, e, E, it, True

    def polish(self, q: list[float], ilimit: int) -> tuple[list[float], list[float], float, int, bool]:
        """Check a closed-form candidate by forward kinematics; LM steps if it misses."""
        e = _pose_error_rows(self.goal, self.fk(*q))
        if self.converged(e):
            return q, e, self._E(e), 0, True
        return self.lm(q, ilimit)

    # ------------------------------------------------------------------ reach
    def out_of_reach(self) -> bool:
        """True when the goal position is farther from the base than the arm's reach."""
        if len(self.pidx) < 3:
            return False
        reach = self.setup.reach
        if not math.isfinite(reach):
            return False
        g = self.goal
        x, y, z = g[0][3], g[1][3], g[2][3]
        B = self.setup.base_inv_rows
        if B is not None:
            x, y, z = (B[0][0] * x + B[0][1] * y + B[0][2] * z + B[0][3],
                       B[1][0] * x + B[1][1] * y + B[1][2] * z + B[1][3],
                       B[2][0] * x + B[2][1] * y + B[2][2] * z + B[2][3])
        return math.sqrt(x * x + y * y + z * z) > reach * (1.0 + 1e-9) + 1e-12

    # ------------------------------------------------------------------ answers
    def success(self, q: list[float], e: list[float], E: float, iterations: int, searches: int) -> IKSolution:
        pe, re = self.errors(e)
        return IKSolution(q=np.array(q), success=True, iterations=iterations, searches=searches,
                          residual=math.sqrt(2 * E), pos_error=pe, rot_error=re)

    def fail(self, q: list[float], iterations: int, searches: int, reason: str,
             e: list[float] | None = None, E: float | None = None) -> IKSolution:
        if e is None:
            e = _pose_error_rows(self.goal, self.fk(*q))
            E = self._E(e)
        pe, re = self.errors(e)
        err = f"best position error {pe:.3g} m, orientation error {re:.3g} rad"
        return IKSolution(q=np.array(q), success=False, iterations=iterations, searches=searches,
                          residual=math.sqrt(2 * E), reason=reason.format(s=searches, err=err),
                          pos_error=pe, rot_error=re)


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
def _puma_solver(robot: "Robot") -> _ik_closed.ClosedForm:
    cf = _ik_closed.solver(robot)
    if cf is None or cf.kind != "puma":
        raise ValueError(
            f"{robot.name}: ikine_a needs a Puma-type 6R arm (standard DH, alpha = [90, 0, -90, 90, -90, 0] deg, "
            "a1 = a4 = a5 = a6 = 0, d2 = d5 = 0, spherical wrist); use ikine() for this arm"
        )
    return cf


def _wrap(a: Array) -> Array:
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def ikine_a_all(robot: "Robot", T: ArrayLike) -> tuple[Array, list[str]]:
    """All closed-form solutions of a Puma-type arm: ``(k, 6)`` joint values (k <= 8, each
    angle in [-pi, pi)) and their configuration strings (see :func:`ikine_a`). Joint
    limits are not applied."""
    cf = _puma_solver(robot)
    sols, confs = cf.solve(np.asarray(T, dtype=float), [0.0] * 6)
    return (_wrap(np.array(sols)) if sols else np.empty((0, 6))), confs


def _config(config: str) -> str:
    """Robotics Toolbox's ``config_validate``: one letter of each pair, the first by default."""
    c = config.lower()
    bad = set(c) - set("lrudnf")
    if bad:
        raise ValueError(f"ikine_a: unknown configuration letter(s) {''.join(sorted(bad))!r} in {config!r}; "
                         "use l/r (left/right arm), u/d (elbow up/down), n/f (wrist not flipped/flipped)")
    out = ""
    for pair in ("lr", "ud", "nf"):
        if pair[0] in c and pair[1] in c:
            raise ValueError(f"ikine_a: configuration {config!r} has both {pair[0]!r} and {pair[1]!r}")
        out += pair[1] if pair[1] in c else pair[0]
    return out


def ikine_a(robot: "Robot", T: ArrayLike, config: str = "lun", *, tol: float = 1e-10) -> IKSolution:
    """Closed-form inverse kinematics of a Puma-type 6R arm with a spherical wrist.

    ``config`` picks one of the 8 solutions with up to three letters (any order), as
    Robotics Toolbox's ``Puma560.ikine_a``: ``l``/``r`` left/right-handed arm, ``u``/``d``
    elbow up/down, ``n``/``f`` wrist not flipped/flipped (``n``: ``q5 <= 0``); a missing
    pair defaults to ``l``, ``u``, ``n``. Angles are in [-pi, pi).

    ``success`` is True only when the solution reaches the pose to ``tol`` (position, m,
    and orientation, rad, by forward kinematics); otherwise ``reason`` says why (out of
    reach, or the residual). Joint limits are not enforced: a solution outside them
    succeeds with ``reason`` saying so.
    """
    want = _config(config)
    sols, confs = ikine_a_all(robot, T)
    for q, c in zip(sols, confs):
        if c != want:
            continue
        err = pose_error(T, robot.fkine(q))
        pe, re = float(np.linalg.norm(err[:3])), float(np.linalg.norm(err[3:]))
        res = float(np.linalg.norm(err))
        if not (pe < tol and re < tol):
            return IKSolution(q=q, success=False, residual=res, pos_error=pe, rot_error=re,
                              reason=f"the {want!r} solution misses the pose (position error {pe:.3g} m, "
                              f"orientation error {re:.3g} rad, tolerance {tol:g})")
        lim = robot.qlim
        inside = bool(np.all((q >= lim[0] - 1e-12) & (q <= lim[1] + 1e-12)))
        return IKSolution(q=q, success=True, iterations=0, residual=res,
                          reason="" if inside else "solution outside the joint limits", pos_error=pe, rot_error=re)
    return IKSolution(q=np.full(6, np.nan), success=False, reason=f"pose out of reach for configuration {want!r}")
