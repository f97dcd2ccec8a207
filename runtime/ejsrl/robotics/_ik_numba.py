"""Levenberg-Marquardt inverse kinematics compiled with numba (the ``[fast]`` extra; private).

One compiled function runs a whole :func:`.ik.ikine` search for any serial arm: every
random restart, every iteration, forward kinematics, the world-frame Jacobian, the pose
error and the damped least-squares solve, with no Python in the loop. The arm is given as
constants: a chain ``T = C_0 J_0(q_0) C_1 J_1(q_1) ... J_{n-1}(q_{n-1}) C_n`` where each
joint ``J_j`` turns about (or slides along) its local z axis and the ``C_j`` are constant
(4, 4) transforms (base, the DH/MDH/URDF link transforms, tool) folded together once per
arm by :func:`chain_constants`. The code is generic, so it is compiled once per machine
(numba's on-disk cache) and serves every arm, DH or URDF.

The algorithm is the one of :meth:`.ik._Problem.lm`: Sugihara's damping
``(J^T W J + (E + lam) I) dq = J^T W e`` with ``E = e^T W e / 2``, steps accepted when they
lower E, else damped harder (a search gives up past 1e6); joint values clamped to the
limits; a search that has not converged after ``ilimit`` iterations restarts from a
uniformly random configuration within the limits (a SplitMix64 stream from ``seed``), up
to ``slimit`` searches. Three refinements, for targets at and near singularities:

- the step is solved from the normal equations by Cholesky; once such a step has failed
  (or been rejected) where the damping no longer keeps their condition number below 1e10
  (``E + lam < 1e-10 trace(J^T W J)``), the search solves such steps by a Householder QR
  of ``[W^1/2 J; (E + lam)^1/2 I]``, whose condition is the square root of theirs (twice
  the work of a step, so only where it is needed): near a wrist singularity the Jacobian's smallest singular value falls to
  ~1e-9, its square is lost in ``J^T W J``'s rounding, and the Cholesky steps stalled
  searches 1-2x above a 1e-10 tolerance (KR5 and IRB140 at q5 = 1e-7);
- the extra damping follows the gain ratio ``rho`` of each step (actual over predicted
  decrease of E; Nielsen's rule): times ``max(0.1, 1 - (2 rho - 1)^3)`` on an accepted
  step, times 2, 4, 8... on rejected ones, instead of /10 and x10, which near the Panda's
  stretched elbow swung between two values and took 4 % steps towards the solution;
- in a clamped search, the joints a step would take past a limit stop on it and the
  step of the others is solved again for the error left (an active set), where clamping
  the step alone turned it off the descent: on the Panda, whose joints 4 and 6 have
  ranges of 3 rad, searches stalled on a limit (0.2-0.4 % of targets failed with a
  joint near its limit) and took twice the iterations;
- a search within 1e-4 of its goal runs up to ``3 ilimit`` iterations, and on up to
  ``10 ilimit`` while its error halves every ``ilimit`` iterations (a target on a
  singular fold, where the Jacobian is singular at the answer, converges only linearly).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

Array = np.ndarray


def _jit(fn):
    """``numba.njit(nogil=True, cache=True)``; compiled again in each process when no
    cache directory is writable (numba refuses ``cache=True`` then)."""
    try:
        return nb.njit(nogil=True, cache=True, error_model="numpy")(fn)
    except RuntimeError:  # "cannot cache function ...: no locator available"
        return nb.njit(nogil=True, error_model="numpy")(fn)


def chain_constants(robot) -> tuple[Array, Array, Array]:  # type: ignore[no-untyped-def]
    """The arm as the compiled code takes it: ``C`` (n + 1, 4, 4) constant transforms,
    ``prism`` (n,) 1.0 for a prismatic joint, ``offset`` (n,) added to each joint value."""
    from .transforms import rotx, rotz, transl

    n = robot.n
    robot._params()

    def tz(d: float) -> Array:
        return transl(0.0, 0.0, d)

    def tx(a: float) -> Array:
        return transl(a, 0.0, 0.0)

    def r4(R: Array) -> Array:
        T = np.eye(4)
        T[:3, :3] = R
        return T

    pre, post = [], []
    for j in range(n):
        a, d, al, th = (float(v) for v in (robot._a[j], robot._d[j], robot._alpha[j], robot._theta[j]))
        prism = bool(robot._prism[j])
        if robot.ets:
            o = np.asarray(robot.links[j].origin, dtype=float)
            pre.append(o @ r4(rotz(th)) if prism else o)
            post.append(np.eye(4) if prism else tz(d))
        elif robot.mdh:
            base = r4(rotx(al)) @ tx(a)
            pre.append(base @ r4(rotz(th)) if prism else base)
            post.append(np.eye(4) if prism else tz(d))
        else:
            pre.append(r4(rotz(th)) if prism else np.eye(4))
            post.append((tx(a) if prism else tz(d) @ tx(a)) @ r4(rotx(al)))
    C = np.empty((n + 1, 4, 4))
    C[0] = np.asarray(robot.base, dtype=float) @ pre[0]
    for j in range(1, n):
        C[j] = post[j - 1] @ pre[j]
    C[n] = post[n - 1] @ np.asarray(robot.tool, dtype=float)
    return C, robot._prism.astype(float), robot._offset.astype(float)


@_jit
def _mul_joint(T, C, prism, q):  # pragma: no cover - compiled
    """T <- T @ Jz(q) @ C for a joint about (or along) z: T (4, 4) in place."""
    if prism > 0.5:
        for r in range(3):
            T[r, 3] += T[r, 2] * q
    else:
        c = math.cos(q)
        s = math.sin(q)
        for r in range(3):
            x = T[r, 0]
            y = T[r, 1]
            T[r, 0] = c * x + s * y
            T[r, 1] = c * y - s * x
    tmp = np.empty(4)
    for r in range(3):
        for k in range(4):
            tmp[k] = T[r, 0] * C[0, k] + T[r, 1] * C[1, k] + T[r, 2] * C[2, k] + T[r, 3] * C[3, k]
        for k in range(4):
            T[r, k] = tmp[k]


@_jit
def fkine_jacob(C, prism, offset, q, T, J, Z, P):  # pragma: no cover - compiled
    """Forward kinematics into T (4, 4) and the world-frame Jacobian into J (6, n);
    Z, P (n, 3) scratch: each joint's axis and origin in the world."""
    n = q.shape[0]
    for r in range(4):
        for k in range(4):
            T[r, k] = C[0, r, k]
    for j in range(n):
        for r in range(3):
            Z[j, r] = T[r, 2]
            P[j, r] = T[r, 3]
        _mul_joint(T, C[j + 1], prism[j], q[j] + offset[j])
    for j in range(n):
        zx, zy, zz = Z[j, 0], Z[j, 1], Z[j, 2]
        if prism[j] > 0.5:
            J[0, j], J[1, j], J[2, j] = zx, zy, zz
            J[3, j] = J[4, j] = J[5, j] = 0.0
        else:
            dx, dy, dz = T[0, 3] - P[j, 0], T[1, 3] - P[j, 1], T[2, 3] - P[j, 2]
            J[0, j] = zy * dz - zz * dy
            J[1, j] = zz * dx - zx * dz
            J[2, j] = zx * dy - zy * dx
            J[3, j], J[4, j], J[5, j] = zx, zy, zz


@_jit
def pose_error(G, T, e):  # pragma: no cover - compiled
    """``e`` (6,) <- ``[p* - p, log(R* R^T)]`` for the goal G and pose T (world frame)."""
    m = np.empty((3, 3))
    for i in range(3):
        for k in range(3):
            m[i, k] = G[i, 0] * T[k, 0] + G[i, 1] * T[k, 1] + G[i, 2] * T[k, 2]
        e[i] = G[i, 3] - T[i, 3]
    vx, vy, vz = m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]
    c = 0.5 * (m[0, 0] + m[1, 1] + m[2, 2] - 1.0)
    s = 0.5 * math.sqrt(vx * vx + vy * vy + vz * vz)
    if s > 1e-6:
        k = math.atan2(s, c) / (2.0 * s)
        e[3], e[4], e[5] = vx * k, vy * k, vz * k
    elif c > 0:
        e[3], e[4], e[5] = 0.5 * vx, 0.5 * vy, 0.5 * vz
    else:  # near pi: the axis from the symmetric part, its sign from the skew part
        theta = math.atan2(s, c)
        one_c = max(1.0 - c, 1e-300)
        big = 0
        for i in range(1, 3):
            if m[i, i] > m[big, big]:
                big = i
        ax = np.empty(3)
        ax[big] = math.sqrt(max(0.0, (m[big, big] - c) / one_c))
        for i in range(3):
            if i != big:
                ax[i] = (m[big, i] + m[i, big]) / (2.0 * one_c * ax[big])
        if ax[0] * vx + ax[1] * vy + ax[2] * vz < 0.0:
            theta = -theta
        e[3], e[4], e[5] = ax[0] * theta, ax[1] * theta, ax[2] * theta


@_jit
def _weighted(e, w, pidx_on, ridx_on):  # pragma: no cover - compiled
    """(E, position error norm, orientation error norm) of e with weights w."""
    E = 0.0
    pe = 0.0
    re = 0.0
    for k in range(6):
        E += w[k] * e[k] * e[k]
    for k in range(3):
        if w[k] > 0:
            pe += e[k] * e[k]
        if w[k + 3] > 0:
            re += e[k + 3] * e[k + 3]
    return 0.5 * E, math.sqrt(pe), math.sqrt(re)


@_jit
def _solve_spd(H, g, x):  # pragma: no cover - compiled
    """x <- H^-1 g by Cholesky (H (n, n) symmetric positive definite, overwritten); False if not SPD."""
    n = g.shape[0]
    for j in range(n):
        s = H[j, j]
        for k in range(j):
            s -= H[j, k] * H[j, k]
        if not s > 0.0:
            return False
        d = math.sqrt(s)
        H[j, j] = d
        for i in range(j + 1, n):
            t = H[i, j]
            for k in range(j):
                t -= H[i, k] * H[j, k]
            H[i, j] = t / d
    for i in range(n):
        t = g[i]
        for k in range(i):
            t -= H[i, k] * x[k]
        x[i] = t / H[i, i]
    for i in range(n - 1, -1, -1):
        t = x[i]
        for k in range(i + 1, n):
            t -= H[k, i] * x[k]
        x[i] = t / H[i, i]
    return True


@_jit
def _solve_lsq(J, w, e, mu, dq, A, b):  # pragma: no cover - compiled
    """dq (n,) <- argmin ``|W^1/2 (J dq - e)|^2 + mu |dq|^2`` by Householder QR of the
    stacked (6 + n, n) matrix ``[W^1/2 J; mu^1/2 I]`` (A, b scratch); False if singular."""
    n = dq.shape[0]
    m = 6 + n
    sm = math.sqrt(mu)
    for r in range(6):
        sw = math.sqrt(w[r])
        for k in range(n):
            A[r, k] = sw * J[r, k]
        b[r] = sw * e[r]
    for r in range(n):
        for k in range(n):
            A[6 + r, k] = 0.0
        A[6 + r, r] = sm
        b[6 + r] = 0.0
    for k in range(n):
        nrm = 0.0
        for r in range(k, m):
            nrm += A[r, k] * A[r, k]
        nrm = math.sqrt(nrm)
        if nrm == 0.0:
            return False
        alpha = -nrm if A[k, k] >= 0.0 else nrm
        A[k, k] -= alpha  # the Householder vector is A[k:, k]
        vv = 0.0
        for r in range(k, m):
            vv += A[r, k] * A[r, k]
        for c in range(k + 1, n):
            t = 0.0
            for r in range(k, m):
                t += A[r, k] * A[r, c]
            t = 2.0 * t / vv
            for r in range(k, m):
                A[r, c] -= t * A[r, k]
        t = 0.0
        for r in range(k, m):
            t += A[r, k] * b[r]
        t = 2.0 * t / vv
        for r in range(k, m):
            b[r] -= t * A[r, k]
        A[k, k] = alpha
    for i in range(n - 1, -1, -1):
        t = b[i]
        for k in range(i + 1, n):
            t -= A[i, k] * dq[k]
        dq[i] = t / A[i, i]
    return True


@_jit
def _normal_equations(J, w, e, H, g):  # pragma: no cover - compiled
    """The weighted normal equations of an LM step: g (n,) <- J^T W e and H (n, n) <- J^T W J
    (J (6, n), W = diag(w), e (6,)); returns H's trace (before any damping)."""
    n = g.shape[0]
    trace = 0.0
    for i in range(n):
        gi = 0.0
        for r in range(6):
            gi += J[r, i] * w[r] * e[r]
        g[i] = gi
        for k in range(i + 1):
            h = 0.0
            for r in range(6):
                h += J[r, i] * w[r] * J[r, k]
            H[i, k] = h
            H[k, i] = h
        trace += H[i, i]
    return trace


@_jit
def _stop_at_limits(J, w, e, mu, q, dq, qmin, qmax, H, g, fixed, act, e2):  # pragma: no cover - compiled
    """The joints the step dq (n,) takes past a limit stop on it, and the other joints'
    step is solved again for what is left of the error (H, g overwritten; fixed, act, e2
    scratch): clamping alone turns the step off the descent and stalls a search on a limit.
    False if the smaller system is singular."""
    n = dq.shape[0]
    nfix = 0
    for i in range(n):
        v = q[i] + dq[i]
        if v > qmax[i] or v < qmin[i]:
            fixed[i] = min(max(v, qmin[i]), qmax[i]) - q[i]
            act[i] = 0.0
            nfix += 1
        else:
            fixed[i] = 0.0
            act[i] = 1.0
    if nfix == 0 or nfix == n:
        return True
    for r in range(6):
        t = e[r]
        for i in range(n):
            t -= J[r, i] * fixed[i]
        e2[r] = t
    _normal_equations(J, w, e2, H, g)
    for i in range(n):  # the stopped joints' rows and columns: 0, and 1 on the diagonal
        g[i] *= act[i]
        for k in range(n):
            if act[i] * act[k] == 0.0:
                H[i, k] = 0.0
        H[i, i] += mu if act[i] > 0.0 else 1.0
    if not _solve_spd(H, g, dq):
        return False
    for i in range(n):
        if act[i] == 0.0:
            dq[i] = fixed[i]
    return True


@_jit
def _into_limits(q, prism, qmin, qmax):  # pragma: no cover - compiled
    """Move each revolute angle of q by whole turns into [qmin, qmax] (in place); False
    if one cannot be."""
    two_pi = 2.0 * math.pi
    for i in range(q.shape[0]):
        v = q[i]
        if v >= qmin[i] and v <= qmax[i]:
            continue
        if prism[i] > 0.5:
            return False
        k = math.ceil((qmin[i] - v) / two_pi)
        v = v + k * two_pi
        if v > qmax[i]:
            return False
        q[i] = v
    return True


@_jit
def _uniform(state):  # pragma: no cover - compiled
    """SplitMix64: the next float in [0, 1) from ``state`` (1,) uint64, advanced in place."""
    state[0] += np.uint64(0x9E3779B97F4A7C15)
    z = state[0]
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@_jit
def search(C, prism, offset, G, q0, lo, hi, qmin, qmax, w, tol, lam, ilimit, slimit, seed, clamp,
           q_out, e_out):  # pragma: no cover - compiled
    """LM searches with random restarts (see the module text). Writes the answer (or the
    best configuration found) to ``q_out`` (n,) and its pose error to ``e_out`` (6,);
    returns ``(converged, iterations, searches, E)``."""
    n = q0.shape[0]
    T = np.empty((4, 4))
    J = np.empty((6, n))
    Z = np.empty((n, 3))
    P = np.empty((n, 3))
    Tn = np.empty((4, 4))
    Jn = np.empty((6, n))
    e = np.empty(6)
    en = np.empty(6)
    H = np.empty((n, n))
    g = np.empty(n)
    dq = np.empty(n)
    A = np.empty((6 + n, n))
    b = np.empty(6 + n)
    fixed = np.empty(n)
    act = np.empty(n)
    e2 = np.empty(6)
    q = q0.copy()
    qn = np.empty(n)
    state = np.empty(1, dtype=np.uint64)
    state[0] = np.uint64(seed)
    best_E = np.inf
    total = 0
    for s in range(1, slimit + 1):
        # every other restart searches without clamping (a clamped search can stall on a
        # limit) and moves the answer into the limits by whole turns, if it can
        free = clamp and s % 2 == 0
        fkine_jacob(C, prism, offset, q, T, J, Z, P)
        pose_error(G, T, e)
        E, pe, re = _weighted(e, w, 0, 0)
        damp = lam
        grow = 2.0
        use_qr = False
        it = 0
        mark = pe + re
        ok = pe < tol and re < tol
        while not ok:
            if it >= ilimit and pe + re > 1e-4:
                break
            if it >= 3 * ilimit and it % ilimit == 0:
                # close to its goal: on while the error halves every ilimit iterations
                if it >= 10 * ilimit or pe + re > 0.5 * mark:
                    break
                mark = pe + re
            elif it == 3 * ilimit - ilimit:
                mark = pe + re
            it += 1
            trace = _normal_equations(J, w, e, H, g)
            mu = E + damp
            for i in range(n):
                H[i, i] += mu
            poor = mu < 1e-10 * trace  # the normal equations' condition may be above 1e10
            if poor and use_qr:
                solved = _solve_lsq(J, w, e, mu, dq, A, b)
            else:
                solved = _solve_spd(H, g, dq)
            if solved and clamp and not free:
                past = False
                for i in range(n):
                    v = q[i] + dq[i]
                    if v > qmax[i] or v < qmin[i]:
                        past = True
                        break
                if past:
                    solved = _stop_at_limits(J, w, e, mu, q, dq, qmin, qmax, H, g, fixed, act, e2)
            if solved:
                for i in range(n):
                    v = q[i] + dq[i]
                    if clamp and not free:
                        v = min(max(v, qmin[i]), qmax[i])
                    qn[i] = v
                fkine_jacob(C, prism, offset, qn, Tn, Jn, Z, P)
                pose_error(G, Tn, en)
                En, pen, ren = _weighted(en, w, 0, 0)
                if En < E:
                    # the gain ratio: actual over predicted decrease, dq . (g + mu dq) / 2
                    pred = 0.0
                    for i in range(n):
                        pred += dq[i] * (g[i] + mu * dq[i])
                    rho = 2.0 * (E - En) / pred if pred > 0.0 else 1.0
                    t = 2.0 * rho - 1.0
                    f = 1.0 - t * t * t
                    damp = max(damp * min(max(f, 0.1), 1.0), 1e-20)
                    grow = 2.0
                    q[:] = qn
                    e[:] = en
                    J[:, :] = Jn
                    E, pe, re = En, pen, ren
                    ok = pe < tol and re < tol
                    continue
            if poor:
                use_qr = True  # a step from the normal equations failed there: QR from now on
            damp *= grow
            grow *= 2.0
            if damp > 1e6:
                break
        total += it
        if ok and free:
            ok = _into_limits(q, prism, qmin, qmax)
            if not ok:
                E = np.inf  # reached, but outside the limits: not a best answer
        if ok:
            q_out[:] = q
            e_out[:] = e
            return True, total, s, E
        if E < best_E:
            best_E = E
            q_out[:] = q
            e_out[:] = e
        for i in range(n):
            q[i] = lo[i] + (hi[i] - lo[i]) * _uniform(state)
    return False, total, slimit, best_E


def warm_up() -> None:
    """Compile (or load from numba's cache) every function with the argument types of
    :meth:`._ik_fast.Compiled.run`, on a 2R arm with a prismatic joint."""
    C = np.tile(np.eye(4), (3, 1, 1))
    C[1, 0, 3] = C[2, 0, 3] = 0.5
    prism = np.array([0.0, 1.0])
    offset = np.zeros(2)
    G = np.eye(4)
    G[0, 3] = 0.7
    q_out, e_out = np.empty(2), np.empty(6)
    lo, hi = np.array([-3.0, 0.0]), np.array([3.0, 0.5])
    search(C, prism, offset, G, np.array([0.1, 0.1]), lo, hi, lo, hi, np.array([1.0, 1.0, 0.0, 0.0, 0.0, 1.0]),
           1e-10, 1e-3, 30, 3, 1, True, q_out, e_out)
