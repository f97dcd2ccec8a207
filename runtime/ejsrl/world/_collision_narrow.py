"""Narrow-phase geometry for collision checking: closed forms, OBB SAT and GJK.

Plain functions on floats and small arrays; the public API is in ``collision.py``.
Every distance here is a separation distance in metres between two closed convex sets:
0 when they touch or overlap. GJK works on the shapes' *cores* (a point for a sphere, a
segment for a capsule, the solid for boxes, cylinders and hulls), so a sphere or capsule
radius is subtracted afterwards.

Hot paths use Python floats, not NumPy: for 3-vectors a NumPy call costs more than the
arithmetic it does.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

Vec = tuple[float, float, float]
Support = Callable[[float, float, float], Vec]

#: GJK stops when its upper and lower distance bounds agree to this relative tolerance
GJK_REL_TOL = 1e-9
#: two sets closer than this (metres) count as touching inside GJK
GJK_ABS_TOL = 1e-12
GJK_MAX_ITER = 128


# -- small vector helpers ----------------------------------------------------------------
def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _axpy(a: Vec, s: float, d: Vec) -> Vec:
    return (a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2])


# -- closed forms --------------------------------------------------------------------------
def segment_segment_distance(p1: Vec, q1: Vec, p2: Vec, q2: Vec) -> float:
    """Distance between segments [p1, q1] and [p2, q2] (either may be a point).

    Ericson, Real-Time Collision Detection, 5.1.9.
    """
    d1 = _sub(q1, p1)
    d2 = _sub(q2, p2)
    r = _sub(p1, p2)
    a = _dot(d1, d1)
    e = _dot(d2, d2)
    f = _dot(d2, r)
    eps = 1e-300
    if a <= eps and e <= eps:
        s = t = 0.0
    elif a <= eps:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = _dot(d1, r)
        if e <= eps:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = _dot(d1, d2)
            denom = a * e - b * b
            s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > 1e-14 * a * e else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    c1 = _axpy(p1, s, d1)
    c2 = _axpy(p2, t, d2)
    return math.sqrt(_dot(_sub(c1, c2), _sub(c1, c2)))


def segment_box_distance(p: Vec, q: Vec, half: Vec) -> float:
    """Distance from segment [p, q] to the box ``|x_i| <= half_i`` (both in the box frame).

    Exact: along the segment the squared distance is a piecewise quadratic in the
    parameter t, with pieces split where the segment crosses a face plane; each piece
    is minimised in closed form.
    """
    d = _sub(q, p)
    ts = [0.0, 1.0]
    for i in range(3):
        if d[i] != 0.0:
            for s in (-half[i], half[i]):
                t = (s - p[i]) / d[i]
                if 0.0 < t < 1.0:
                    ts.append(t)
    ts.sort()
    best = math.inf
    for k in range(len(ts) - 1):
        ta, tb = ts[k], ts[k + 1]
        tm = 0.5 * (ta + tb)
        A = B = C = 0.0
        for i in range(3):
            x = p[i] + tm * d[i]
            if x > half[i]:
                off = p[i] - half[i]
            elif x < -half[i]:
                off = p[i] + half[i]
            else:
                continue
            A += d[i] * d[i]
            B += 2.0 * d[i] * off
            C += off * off
        t = min(max(-B / (2.0 * A), ta), tb) if A > 0.0 else ta
        f = (A * t + B) * t + C
        if f < best:
            best = f
    return math.sqrt(max(best, 0.0))


def obb_overlap(half_a: NDArray[np.float64], T_a: NDArray[np.float64], half_b: NDArray[np.float64], T_b: NDArray[np.float64], tol: float = 1e-9) -> bool:
    """True if two oriented boxes touch or overlap: the 15-axis separating-axis test.

    ``half_*``: (3,) half edge lengths; ``T_*``: (4, 4) box poses in the world.
    Ericson, Real-Time Collision Detection, 4.4.1.
    """
    Ra = T_a[:3, :3]
    Rb = T_b[:3, :3]
    R = Ra.T @ Rb
    t = Ra.T @ (T_b[:3, 3] - T_a[:3, 3])
    absR = np.abs(R) + 1e-12  # cross products of near-parallel edges are not axes
    a = half_a
    b = half_b
    # face axes of A and of B
    if np.any(np.abs(t) > a + absR @ b + tol):
        return False
    if np.any(np.abs(t @ R) > absR.T @ a + b + tol):
        return False
    # the nine edge-edge axes A_i x B_j
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        ra = a[i1] * absR[i2] + a[i2] * absR[i1]
        rb = b[[1, 0, 0]] * absR[i, [2, 2, 1]] + b[[2, 2, 1]] * absR[i, [1, 0, 0]]
        dist = np.abs(t[i2] * R[i1] - t[i1] * R[i2])
        if np.any(dist > ra + rb + tol):
            return False
    return True


# -- GJK -------------------------------------------------------------------------------------
def _closest_segment(a: Vec, b: Vec) -> tuple[Vec, list[Vec]]:
    ab = _sub(b, a)
    den = _dot(ab, ab)
    t = -_dot(a, ab) / den if den > 0.0 else 0.0
    if t <= 0.0:
        return a, [a]
    if t >= 1.0:
        return b, [b]
    return _axpy(a, t, ab), [a, b]


def _closest_triangle(a: Vec, b: Vec, c: Vec) -> tuple[Vec, list[Vec]]:
    """Closest point of triangle abc to the origin and the smallest sub-simplex holding it."""
    ab = _sub(b, a)
    ac = _sub(c, a)
    d1 = -_dot(ab, a)
    d2 = -_dot(ac, a)
    if d1 <= 0.0 and d2 <= 0.0:
        return a, [a]
    d3 = -_dot(ab, b)
    d4 = -_dot(ac, b)
    if d3 >= 0.0 and d4 <= d3:
        return b, [b]
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        return _axpy(a, d1 / (d1 - d3), ab), [a, b]
    d5 = -_dot(ab, c)
    d6 = -_dot(ac, c)
    if d6 >= 0.0 and d5 <= d6:
        return c, [c]
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        return _axpy(a, d2 / (d2 - d6), ac), [a, c]
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return _axpy(b, w, _sub(c, b)), [b, c]
    den = va + vb + vc
    if den == 0.0:  # degenerate triangle: fall back to its edges
        return min((_closest_segment(a, b), _closest_segment(a, c), _closest_segment(b, c)), key=lambda r: _dot(r[0], r[0]))
    v = vb / den
    w = vc / den
    return (a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w), [a, b, c]


def _closest_tetra(a: Vec, b: Vec, c: Vec, d: Vec) -> tuple[Vec, list[Vec]]:
    """Closest point of tetrahedron abcd to the origin (the origin itself if inside)."""
    best: tuple[Vec, list[Vec]] | None = None
    best_d = math.inf
    inside = True
    for p, q, r, s in ((a, b, c, d), (a, c, d, b), (a, d, b, c), (b, d, c, a)):
        n = _cross(_sub(q, p), _sub(r, p))
        sign_o = -_dot(p, n)
        sign_s = _dot(_sub(s, p), n)
        scale = _dot(n, n)
        degenerate = sign_s * sign_s <= 1e-24 * scale * max(_dot(_sub(s, p), _sub(s, p)), 1e-300)
        if degenerate or sign_o * sign_s < 0.0:
            inside = False
            pt, simplex = _closest_triangle(p, q, r)
            dd = _dot(pt, pt)
            if dd < best_d:
                best_d = dd
                best = (pt, simplex)
    if inside:
        return (0.0, 0.0, 0.0), [a, b, c, d]
    assert best is not None
    return best


def gjk_distance(support_a: Support, support_b: Support, guess: Vec, stop_above: float = math.inf) -> float:
    """Distance between two convex sets given by their world-frame support functions.

    ``support_x(dx, dy, dz)`` returns the point of the set farthest along d. ``guess``: a
    first search direction (e.g. centre of A minus centre of B). Returns 0 when the sets
    touch or overlap. If ``stop_above`` is finite, returns early with a lower bound on the
    distance as soon as that bound exceeds ``stop_above``.
    """
    if _dot(guess, guess) == 0.0:
        guess = (1.0, 0.0, 0.0)
    sa = support_a(-guess[0], -guess[1], -guess[2])
    sb = support_b(guess[0], guess[1], guess[2])
    v = _sub(sa, sb)
    simplex: list[Vec] = [v]
    stop2 = stop_above * stop_above if stop_above < math.inf else math.inf
    for _ in range(GJK_MAX_ITER):
        vv = _dot(v, v)
        if vv <= GJK_ABS_TOL * GJK_ABS_TOL:
            return 0.0
        w = _sub(support_a(-v[0], -v[1], -v[2]), support_b(v[0], v[1], v[2]))
        vw = _dot(v, w)
        if vw > 0.0 and vw * vw > stop2 * vv:
            return vw / math.sqrt(vv)  # a separating plane farther than stop_above
        if vv - vw <= GJK_REL_TOL * vv or w in simplex:
            return math.sqrt(vv)
        simplex.append(w)
        n = len(simplex)
        if n == 2:
            v, simplex = _closest_segment(simplex[0], simplex[1])
        elif n == 3:
            v, simplex = _closest_triangle(simplex[0], simplex[1], simplex[2])
        else:
            v, simplex = _closest_tetra(simplex[0], simplex[1], simplex[2], simplex[3])
            if len(simplex) == 4:
                return 0.0
    return math.sqrt(_dot(v, v))
