"""One robot's kinematics and dynamics as generated straight-line functions (private).

The algorithms below are written once on scalars and traced by :mod:`._codegen` with
the robot's constant parameters folded in (see there). :class:`Kernels` builds each
function on first use, keeps it until the robot's parameters change, and runs it:

- one configuration: on plain Python floats (``math.sin``), no NumPy call in the loop;
- a batch of ``m`` configurations: on ``(m,)`` arrays, one NumPy operation per scalar
  operation, in chunks that stay in cache; small batches loop over the float version.

The NumPy implementations in :mod:`._kinematics` and :mod:`._dynamics` stay the
reference; the tests check these kernels against them.

Conventions as in :mod:`.robot`: frames are listed as ``(x, y, z, p)`` (the columns of
the rotation and the origin, each a 3-list); poses are returned as their top three rows,
row-major (16 values); Jacobians row-major ``(6, n)``.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Sequence

import numpy as np

from ._codegen import Scalar, Var, compile_pair, cos, sin, snap, step, trace

Vec = list  # a 3-list of scalars
Frame = tuple  # (x, y, z, p)

SMALL_BATCH = 48  # up to this many configurations, loop over the float version
CHUNK = 4096  # configurations per vectorised pass (keeps temporaries in cache)


# ---------------------------------------------------------------------------- vector helpers
def _cross(u: Vec, v: Vec) -> Vec:
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def _dot(u: Vec, v: Vec) -> Scalar:
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def _add(*vs: Vec) -> Vec:
    return [sum((v[k] for v in vs[1:]), vs[0][k]) for k in range(3)]


def _scale(s: Scalar, v: Vec) -> Vec:
    return [s * v[0], s * v[1], s * v[2]]


def _combo(terms: Sequence[tuple[Scalar, Vec]]) -> Vec:
    """``sum s_k v_k``."""
    out: Vec = [0.0, 0.0, 0.0]
    for s, v in terms:
        out = [out[k] + s * v[k] for k in range(3)]
    return out


def _mv(R: list[Vec], v: Vec) -> Vec:
    """``R v`` for R given by rows."""
    return [_dot(R[0], v), _dot(R[1], v), _dot(R[2], v)]


def _mtv(R: list[Vec], v: Vec) -> Vec:
    """``R^T v`` for R given by rows."""
    return [R[0][k] * v[0] + R[1][k] * v[1] + R[2][k] * v[2] for k in range(3)]


# ---------------------------------------------------------------------------- parameters
class Params:
    """The robot's parameters as plain floats (trig of constant angles snapped)."""

    def __init__(self, robot: Any) -> None:
        robot._params()
        self.n = robot.n
        self.mdh = robot.mdh
        self.prism = [bool(x) for x in robot._prism]
        self.a = robot._a.tolist()
        self.d = robot._d.tolist()
        self.theta = robot._theta.tolist()
        self.offset = robot._offset.tolist()
        self.ca = [snap(x) for x in robot._ca]
        self.sa = [snap(x) for x in robot._sa]
        self.m = robot._m.tolist()
        self.r = robot._r.tolist()
        self.I = robot._I.tolist()
        self.armature = robot._armature.tolist()
        self.viscous = (robot._B * robot._G**2).tolist()
        self.coulomb = robot._coulomb  # (|G| Tc+, |G| Tc-) per joint
        self.base = _pose(robot.base)
        self.tool = _pose(robot.tool)


def _pose(T: np.ndarray) -> Frame:
    R = [[snap(x) for x in row] for row in T[:3, :3].tolist()]
    return ([R[0][0], R[1][0], R[2][0]], [R[0][1], R[1][1], R[2][1]], [R[0][2], R[1][2], R[2][2]],
            T[:3, 3].tolist())


_IDENTITY: Frame = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0])


# ---------------------------------------------------------------------------- kinematics
def _joint(P: Params, i: int, qi: Scalar) -> tuple[Scalar, Scalar, Scalar]:
    """cos and sin of link i's theta, and its d, at joint value qi."""
    if P.prism[i]:
        return snap(cos(P.theta[i])), snap(sin(P.theta[i])), qi + P.offset[i]
    th = qi + P.offset[i]
    return cos(th), sin(th), P.d[i]


def frames(P: Params, q: Sequence[Scalar], base: Frame) -> list[Frame]:
    """Frames 0..n in the world (frame 0 is ``base``), each ``(x, y, z, p)``."""
    if getattr(P, "ets", False):  # elementary-transform links (URDF arms): see ._ets
        return P.frames(q, base)
    x, y, z, p = base
    out = [base]
    for i in range(P.n):
        ct, st, d = _joint(P, i, q[i])
        ca, sa, a = P.ca[i], P.sa[i], P.a[i]
        if not P.mdh:  # Rz(theta) Tz(d) Tx(a) Rx(alpha)
            x1 = _combo([(ct, x), (st, y)])
            y1 = _combo([(-st, x), (ct, y)])
            p = _combo([(1.0, p), (d, z), (a, x1)])
            x, y, z = x1, _combo([(ca, y1), (sa, z)]), _combo([(-sa, y1), (ca, z)])
        else:  # Rx(alpha) Tx(a) Rz(theta) Tz(d)
            y1 = _combo([(ca, y), (sa, z)])
            z = _combo([(-sa, y), (ca, z)])
            p = _combo([(1.0, p), (a, x)])
            x, y = _combo([(ct, x), (st, y1)]), _combo([(-st, x), (ct, y1)])
            p = _combo([(1.0, p), (d, z)])
        out.append((x, y, z, p))
    return out


def compose(F: Frame, T: Frame) -> Frame:
    """``F @ T`` for frames given as columns and origin."""
    x, y, z, p = F
    cols = [_combo([(c[0], x), (c[1], y), (c[2], z)]) for c in T[:3]]
    t = T[3]
    return cols[0], cols[1], cols[2], _combo([(1.0, p), (t[0], x), (t[1], y), (t[2], z)])


def pose_rows(F: Frame) -> list[Scalar]:
    """The (4, 4) pose, row-major (16 values; the last row is constant)."""
    x, y, z, p = F
    return [v for k in range(3) for v in (x[k], y[k], z[k], p[k])] + [0.0, 0.0, 0.0, 1.0]


def jacobian(P: Params, F: list[Frame], pe: Vec) -> list[list[Scalar]]:
    """Columns ``[vx vy vz wx wy wz]`` of the world-frame geometric Jacobian."""
    cols = []
    for j in range(P.n):
        _, _, z, o = F[j + 1] if P.mdh else F[j]
        if P.prism[j]:
            cols.append(list(z) + [0.0, 0.0, 0.0])
        else:
            cols.append(_cross(z, _add(pe, _scale(-1.0, o))) + list(z))
    return cols


def _rows(cols: list[list[Scalar]], nrows: int = 6) -> list[Scalar]:
    return [c[r] for r in range(nrows) for c in cols]


def k_fkine(P: Params) -> Callable[[list], list]:
    def fn(q: list) -> list:
        F = frames(P, q, P.base)
        return pose_rows(compose(F[-1], P.tool))

    return fn


def k_fkine_all(P: Params) -> Callable[[list], list]:
    def fn(q: list) -> list:
        return [v for F in frames(P, q, P.base) for v in pose_rows(F)]

    return fn


def k_jacob(P: Params, kind: str) -> Callable[[list], list]:
    """``kind``: "jacob0", "jacobe" or "pose_jacob0" (pose rows then the Jacobian)."""

    def fn(q: list) -> list:
        F = frames(P, q, P.base)
        Te = compose(F[-1], P.tool)
        cols = jacobian(P, F, Te[3])
        if kind == "jacobe":
            x, y, z, _ = Te
            cols = [[_dot(x, c[:3]), _dot(y, c[:3]), _dot(z, c[:3]),
                     _dot(x, c[3:]), _dot(y, c[3:]), _dot(z, c[3:])] for c in cols]
        J = _rows(cols)
        return pose_rows(Te) + J if kind == "pose_jacob0" else J

    return fn


# ---------------------------------------------------------------------------- dynamics
def _local(P: Params, i: int, ct: Scalar, st: Scalar) -> list[Vec]:
    """Rotation of link i's transform ``A_i`` by rows."""
    ca, sa = P.ca[i], P.sa[i]
    if not P.mdh:
        return [[ct, -st * ca, st * sa], [st, ct * ca, -ct * sa], [0.0, sa, ca]]
    return [[ct, -st, 0.0], [ca * st, ca * ct, -sa], [sa * st, sa * ct, ca]]


def craig_outward(R: list[Vec], p: Vec, prism: bool, qd: Scalar, qdd: Scalar, w: Vec, wd: Vec, acc: Vec) -> tuple[Vec, Vec, Vec]:
    """One outward step of Newton-Euler in Craig's link frames (modified DH, elementary
    transforms): link i's angular velocity, angular and linear acceleration in frame i, from
    link i-1's, with ``R`` the rotation from frame i-1 to i, ``p`` origin i in frame i-1 and
    the joint turning about (or sliding along) z of frame i."""
    z = [0.0, 0.0, 1.0]
    a_t = _mtv(R, _add(acc, _cross(wd, p), _cross(w, _cross(w, p))))
    w_t, wd_t = _mtv(R, w), _mtv(R, wd)
    if prism:
        return w_t, wd_t, _add(a_t, _scale(2.0, _cross(w_t, _scale(qd, z))), _scale(qdd, z))
    return _add(w_t, _scale(qd, z)), _add(wd_t, _cross(w_t, _scale(qd, z)), _scale(qdd, z)), a_t


def link_wrench(m: Scalar, r: Vec, I: list[Vec], w: Vec, wd: Vec, acc: Vec) -> tuple[Vec, Vec]:
    """The force and moment (about the centre of mass ``r``) that move a link of mass ``m`` and
    inertia ``I`` (about its centre of mass) with ``w``, ``wd`` and origin acceleration ``acc``."""
    return _scale(m, _add(acc, _cross(wd, r), _cross(w, _cross(w, r)))), _add(_mv(I, wd), _cross(w, _mv(I, w)))


def rne(P: Params, q: Sequence[Scalar], qd: Sequence[Scalar], qdd: Sequence[Scalar], a0: Vec) -> list[Scalar]:
    """Rigid-body joint forces by recursive Newton-Euler, link quantities in link frames
    (the recursion of :func:`._dynamics.rne_rigid_single`). ``a0``: base acceleration
    (``-gravity``) in the base frame."""
    if getattr(P, "ets", False):  # elementary-transform links (URDF arms): see ._ets
        return P.rne(q, qd, qdd, a0)
    n = P.n
    w: Vec = [0.0, 0.0, 0.0]
    wd: Vec = [0.0, 0.0, 0.0]
    acc: Vec = list(a0)
    Rs, ps, zs, Fs, Ns = [], [], [], [], []
    for i in range(n):
        ct, st, d = _joint(P, i, q[i])
        R = _local(P, i, ct, st)
        Rs.append(R)
        ca, sa, a = P.ca[i], P.sa[i], P.a[i]
        if not P.mdh:
            z = [0.0, sa, ca]  # z_{i-1} in frame i
            p = [a, sa * d, ca * d]  # origin i-1 -> i in frame i
            w_t, wd_t, a_t = _mtv(R, w), _mtv(R, wd), _mtv(R, acc)
            if P.prism[i]:
                w, wd = w_t, wd_t
                acc = _add(a_t, _scale(qdd[i], z), _cross(wd, p), _scale(2.0, _cross(w, _scale(qd[i], z))),
                           _cross(w, _cross(w, p)))
            else:
                w = _add(w_t, _scale(qd[i], z))
                wd = _add(wd_t, _scale(qdd[i], z), _cross(w_t, _scale(qd[i], z)))
                acc = _add(a_t, _cross(wd, p), _cross(w, _cross(w, p)))
        else:
            z = [0.0, 0.0, 1.0]
            p = [a, -sa * d, ca * d]  # origin i-1 -> i in frame i-1
            w, wd, acc = craig_outward(R, p, P.prism[i], qd[i], qdd[i], w, wd, acc)
        ps.append(p)
        zs.append(z)
        F, N = link_wrench(P.m[i], P.r[i], P.I[i], w, wd, acc)
        Fs.append(F)
        Ns.append(N)
    tau: list[Scalar] = [0.0] * n
    f: Vec = [0.0, 0.0, 0.0]
    nn: Vec = [0.0, 0.0, 0.0]
    for i in range(n - 1, -1, -1):
        if i < n - 1:
            fR, nR = _mv(Rs[i + 1], f), _mv(Rs[i + 1], nn)
        else:
            fR, nR = f, nn
        r = P.r[i]
        if not P.mdh:
            nn = _add(nR, _cross(ps[i], fR), _cross(_add(ps[i], r), Fs[i]), Ns[i])
        elif i < n - 1:
            nn = _add(nR, _cross(ps[i + 1], fR), _cross(r, Fs[i]), Ns[i])
        else:
            nn = _add(_cross(r, Fs[i]), Ns[i])
        f = _add(fR, Fs[i])
        tau[i] = _dot(f if P.prism[i] else nn, zs[i])
    return tau


def friction(P: Params, qd: Sequence[Scalar]) -> list[Scalar]:
    """Torques spent on joint friction (the negative of ``Robot.friction``): viscous
    ``B G^2 qd`` plus Coulomb ``|G| Tc+`` when ``qd > 0``, ``|G| Tc-`` when ``qd < 0``."""
    cp, cn = P.coulomb
    return [P.viscous[i] * v + cp[i] * step(v, 1.0) + cn[i] * step(v, -1.0) for i, v in enumerate(qd)]


def k_rne(P: Params, has_qd: bool, has_qdd: bool, armature: bool, with_friction: bool) -> Callable[..., list]:
    """Inputs q, qd, qdd (each n; zero and unused when ``has_*`` is False), a0 (3)."""

    def fn(q: list, qd: list, qdd: list, a0: list) -> list:
        qd = qd if has_qd else [0.0] * P.n
        qdd = qdd if has_qdd else [0.0] * P.n
        tau = rne(P, q, qd, qdd, a0)
        if armature:
            tau = [t + P.armature[i] * qdd[i] for i, t in enumerate(tau)]
        if with_friction:
            tau = [t + f for t, f in zip(tau, friction(P, qd))]
        return tau

    return fn


def inertia(P: Params, q: Sequence[Scalar]) -> list[list[Scalar]]:
    """Joint-space inertia (n, n) with armature: composite rigid bodies in the base frame.

    Composite body k (links k..n-1) accelerated by joint k alone has the momentum rate
    ``P_k = z x (h - M o)``, ``L_k = J z - h x (z x o)`` about the origin (revolute; for a
    prismatic joint ``P_k = M z``, ``L_k = h x z``), with M, h, J its mass, first moment and
    inertia about the origin. Then ``M[i][k] = z_i . L_k + (o_i x z_i) . P_k`` (revolute i)
    or ``z_i . P_k`` (prismatic i), for i <= k."""
    n = P.n
    F = frames(P, q, _IDENTITY)
    axes = [F[j + 1] if P.mdh else F[j] for j in range(n)]
    Jl, hl = [], []
    for k in range(n):
        x, y, z, p = F[k + 1]
        R = [x, y, z]
        mk = P.m[k]
        c = _combo([(1.0, p)] + [(P.r[k][j], R[j]) for j in range(3)])
        u = [_combo([(P.I[k][i][j], R[i]) for i in range(3)]) for j in range(3)]  # R I, by columns
        mc = _scale(mk, c)
        cc = _dot(mc, c)
        J = {}
        for a in range(3):
            for b in range(a, 3):
                J[a, b] = sum((u[j][a] * R[j][b] for j in range(1, 3)), u[0][a] * R[0][b]) - mc[a] * c[b] \
                    + (cc if a == b else 0.0)
        Jl.append(J)
        hl.append(mc)
    M: list[list[Scalar]] = [[0.0] * n for _ in range(n)]
    Jc = {key: 0.0 for key in Jl[0]}
    hc: Vec = [0.0, 0.0, 0.0]
    mass = 0.0
    for k in range(n - 1, -1, -1):
        Jc = {key: Jc[key] + Jl[k][key] for key in Jc}
        hc = _add(hc, hl[k])
        mass += P.m[k]
        _, _, z, o = axes[k]
        if P.prism[k]:
            Pk, Lk = _scale(mass, z), _cross(hc, z)
        else:
            Pk = _cross(z, _add(hc, _scale(-mass, o)))
            Jz = [sum((Jc[min(a, b), max(a, b)] * z[b] for b in range(1, 3)), Jc[0, a] * z[0]) for a in range(3)]
            Lk = _add(Jz, _scale(-1.0, _cross(hc, _cross(z, o))))
        for i in range(k + 1):
            _, _, zi, oi = axes[i]
            v = _dot(zi, Pk) if P.prism[i] else _dot(zi, Lk) + _dot(_cross(oi, zi), Pk)
            M[i][k] = M[k][i] = v + (P.armature[k] if i == k else 0.0)
    return M


def k_inertia(P: Params) -> Callable[[list], list]:
    def fn(q: list) -> list:
        return [v for row in inertia(P, q) for v in row]

    return fn


def ldl_solve(M: list[list[Scalar]], b: Sequence[Scalar], pivots: list[Scalar] | None = None) -> list[Scalar]:
    """Solve ``M x = b`` for symmetric positive definite M by ``L D L^T`` (no pivoting);
    the diagonal of D is appended to ``pivots`` when given (all > 0 iff M is positive
    definite, and ``max(D) / min(D)`` is a lower bound of M's condition number)."""
    n = len(b)
    L = [[0.0] * n for _ in range(n)]
    W = [[0.0] * n for _ in range(n)]  # W[i][k] = L[i][k] D[k]
    inv: list[Scalar] = []
    for j in range(n):
        dj = M[j][j]
        for k in range(j):
            dj = dj - L[j][k] * W[j][k]
        inv.append(1.0 / dj if isinstance(dj, Var) or dj != 0.0 else math.inf)  # inf: singular, caught later
        if pivots is not None:
            pivots.append(dj)
        for i in range(j + 1, n):
            s = M[i][j]
            for k in range(j):
                s = s - L[i][k] * W[j][k]
            W[i][j] = s
            L[i][j] = s * inv[j]
    y = list(b)
    for i in range(n):
        for k in range(i):
            y[i] = y[i] - L[i][k] * y[k]
    x = [y[i] * inv[i] for i in range(n)]
    for i in range(n - 1, -1, -1):
        for k in range(i + 1, n):
            x[i] = x[i] - L[k][i] * x[k]
    return x


def k_accel(P: Params) -> Callable[..., list]:
    """Inputs q, qd, tau, a0; outputs qdd (n) then the n pivots of M's ``L D L^T``
    (the caller refuses a singular or ill-conditioned M from them)."""

    def fn(q: list, qd: list, tau: list, a0: list) -> list:
        bias = [b + f for b, f in zip(rne(P, q, qd, [0.0] * P.n, a0), friction(P, qd))]
        pivots: list[Scalar] = []
        qdd = ldl_solve(inertia(P, q), [t - b for t, b in zip(tau, bias)], pivots)
        return qdd + pivots

    return fn


def k_lm_step(n: int) -> Callable[..., list]:
    """Damped least-squares step: solve ``(J^T W J + lam I) dq = J^T W e``; inputs J (6n,
    row-major), e (6), w (6), lam (1)."""

    def fn(J: list, e: list, w: list, lam: list) -> list:
        rows = [J[r * n:(r + 1) * n] for r in range(6)]
        WJ = [[w[r] * v for v in rows[r]] for r in range(6)]
        H = [[0.0] * n for _ in range(n)]
        for i in range(n):
            for j in range(i, n):
                H[i][j] = H[j][i] = sum((rows[r][i] * WJ[r][j] for r in range(1, 6)), rows[0][i] * WJ[0][j]) \
                    + (lam[0] if i == j else 0.0)
        g = [sum((WJ[r][i] * e[r] for r in range(1, 6)), WJ[0][i] * e[0]) for i in range(n)]
        return ldl_solve(H, g)

    return fn


# ---------------------------------------------------------------------------- runner
def build(P: Params, key: tuple) -> "Kernel":
    """The kernel named by ``key``: ``("fkine",)``, ``("fkine_all",)``, ``("jacob0",)``,
    ``("jacobe",)``, ``("pose_jacob0",)``, ``("inertia",)``, ``("accel",)``,
    ``("rne", has_qd, has_qdd, armature, friction)`` or ``("lm_step",)``."""
    n = P.n
    kind = key[0]
    q = [("q", n)]
    if kind == "fkine":
        return Kernel(k_fkine(P), kind, q)
    if kind == "fkine_all":
        return Kernel(k_fkine_all(P), kind, q)
    if kind in ("jacob0", "jacobe", "pose_jacob0"):
        return Kernel(k_jacob(P, kind), kind, q)
    if kind == "inertia":
        return Kernel(k_inertia(P), kind, q)
    if kind == "rne":
        return Kernel(k_rne(P, *key[1:]), kind, q + [("qd", n), ("qdd", n), ("a", 3)])
    if kind == "accel":
        return Kernel(k_accel(P), kind, q + [("qd", n), ("tau", n), ("a", 3)])
    if kind == "lm_step":
        return Kernel(k_lm_step(n), kind, [("J", 6 * n), ("e", 6), ("w", 6), ("lam", 1)])
    raise KeyError(key)


class Kernel:
    """A generated function with a float and an array version; inputs are groups of
    scalars (e.g. q, qd, a0), outputs a flat tuple of ``size`` values."""

    def __init__(self, fn: Callable[..., list], name: str, groups: Sequence[tuple[str, int]]) -> None:
        self.source = trace(fn, name, groups)
        self.single, self.vector = compile_pair(self.source, name)
        self.groups = groups

    def fallback(self, args: Sequence[float]) -> tuple:
        """The array version on one configuration: for the inputs on which ``math``
        raises (``sin(inf)``, a zero pivot) NumPy gives ``nan``/``inf`` as the reference
        path does."""
        with np.errstate(all="ignore"):
            return tuple(float(v) for v in self.vector(*[np.float64(a) for a in args]))

    def batch(self, args: Sequence[np.ndarray], size: int) -> np.ndarray:
        """Run on ``(m, k)`` input arrays (one per group); returns ``(m, size)``."""
        m = len(args[0])
        if m <= SMALL_BATCH:
            f = self.single
            rows = [sum((a[i].tolist() for a in args), []) for i in range(m)]
            return np.array([f(*r) for r in rows], dtype=float).reshape(m, size)
        cols = np.ascontiguousarray(np.concatenate([np.asarray(a, float) for a in args], axis=1).T)
        out = np.empty((m, size))
        f = self.vector
        for s in range(0, m, CHUNK):
            e = min(s + CHUNK, m)
            for k, v in enumerate(f(*cols[:, s:e])):
                out[s:e, k] = v  # strided writes beat a transposed copy (4x for a Jacobian)
        return out
