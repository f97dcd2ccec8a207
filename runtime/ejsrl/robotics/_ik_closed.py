"""Closed-form inverse kinematics for the arm families that have one (private).

Three families are recognised from the DH parameters (standard DH, revolute joints):

- ``"puma"``: 6R with a shoulder offset and a spherical wrist (Puma 560): alpha
  ``[90, 0, -90, 90, -90, 0]`` deg, ``a1 = a4 = a5 = a6 = 0``, ``d2 = d5 = 0``. 8 solutions,
  labelled as Robotics Toolbox's ``Puma560.ikine_a`` does (``l``/``r`` arm, ``u``/``d``
  elbow, ``n``/``f`` wrist).
- ``"ur"``: 6R with three parallel axes (Universal Robots UR3/5/10 and e-series): alpha
  ``[90, 0, 0, 90, -90, 0]`` deg, ``a1 = a4 = a5 = a6 = 0``, ``d2 = d3 = 0``. 8 solutions
  (Hawkins, "Analytic inverse kinematics for the Universal Robots UR-5/UR-10 arms", 2013).
- ``"srs"``: 7R spherical-shoulder, revolute-elbow, spherical-wrist arm (Mitsubishi PA-10,
  KUKA LWR-IV): every ``a = 0``, ``d2 = d4 = d6 = 0``, alpha ``±90`` deg for joints 1-6. The
  redundancy is taken up by joint 3 (the upper-arm roll): for a chosen ``q3`` there are
  up to 8 solutions (Shimizu et al., "Analytical inverse kinematic computation for 7-DOF
  redundant manipulators with joint limits", IEEE T-RO 2008, parametrise by the arm angle
  instead; a fixed ``q3`` gives the same family of solutions).

Everything runs on Python floats (``math``): a solution costs a few microseconds. The
solutions are exact up to round-off except at singular configurations (wrist axes
aligned, shoulder over its own axis), where the free angle is taken from a reference
configuration; :func:`.ik.ikine` checks every candidate by forward kinematics and polishes
it with Levenberg-Marquardt steps, so they are only seeds there.

Rotations are 9-tuples, row-major.
"""

from __future__ import annotations

import math
from typing import Any, Iterator, Sequence

import numpy as np

Rot = tuple  # 9 floats, row-major

_PI = math.pi
_TWO_PI = 2.0 * math.pi
_SING = 1e-9  # |sin| below which a wrist or shoulder is treated as singular


# ---------------------------------------------------------------------------- 3x3 helpers
def _rzrx(th: float, ca: float, sa: float) -> Rot:
    """``Rz(th) @ Rx(alpha)`` with ``ca, sa = cos, sin(alpha)``."""
    c, s = math.cos(th), math.sin(th)
    return (c, -s * ca, s * sa, s, c * ca, -c * sa, 0.0, sa, ca)


def _mul(A: Rot, B: Rot) -> Rot:
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = A
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = B
    return (a0 * b0 + a1 * b3 + a2 * b6, a0 * b1 + a1 * b4 + a2 * b7, a0 * b2 + a1 * b5 + a2 * b8,
            a3 * b0 + a4 * b3 + a5 * b6, a3 * b1 + a4 * b4 + a5 * b7, a3 * b2 + a4 * b5 + a5 * b8,
            a6 * b0 + a7 * b3 + a8 * b6, a6 * b1 + a7 * b4 + a8 * b7, a6 * b2 + a7 * b5 + a8 * b8)


def _tmul(A: Rot, B: Rot) -> Rot:
    """``A^T @ B``."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = A
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = B
    return (a0 * b0 + a3 * b3 + a6 * b6, a0 * b1 + a3 * b4 + a6 * b7, a0 * b2 + a3 * b5 + a6 * b8,
            a1 * b0 + a4 * b3 + a7 * b6, a1 * b1 + a4 * b4 + a7 * b7, a1 * b2 + a4 * b5 + a7 * b8,
            a2 * b0 + a5 * b3 + a8 * b6, a2 * b1 + a5 * b4 + a8 * b7, a2 * b2 + a5 * b5 + a8 * b8)


def _chain(thetas: Sequence[float], cs: Sequence[tuple[float, float]]) -> Rot:
    """``Rz(th0) Rx(alpha0) Rz(th1) Rx(alpha1) ...``; a zero alpha merges two z turns."""
    th = thetas[0]
    R = None
    for k in range(len(thetas)):
        c = cs[k]
        if c[1] == 0.0 and c[0] == 1.0 and k + 1 < len(thetas):
            th += thetas[k + 1]
            continue
        A = _rzrx(th, c[0], c[1])
        R = A if R is None else _mul(R, A)
        if k + 1 < len(thetas):
            th = thetas[k + 1]
    return R


def _wrap(a: float) -> float:
    return (a + _PI) % (2 * _PI) - _PI


def _acos2(x: float) -> float | None:
    """``acos(x)``, with x up to 1e-9 outside [-1, 1] taken as ±1 (round-off at the
    boundary of the workspace); None beyond."""
    if x > 1.0:
        return 0.0 if x < 1.0 + 1e-9 else None
    if x < -1.0:
        return _PI if x > -1.0 - 1e-9 else None
    return math.acos(x)


def wrist(M: Rot, c1: tuple[float, float], c2: tuple[float, float], a_ref: float) -> list[tuple[float, float, float]]:
    """The two solutions ``(a, b, c)`` of ``M = Rz(a) Rx(alpha1) Rz(b) Rx(alpha2) Rz(c)``
    (a spherical wrist; ``c1``, ``c2`` are cos and sin of alpha1 and alpha2, both alphas
    ±90 deg or any value with nonzero sine). When the first and last axes align
    (``sin b = 0``) only ``a + c`` (or ``a - c``) is determined: ``a`` is then ``a_ref``."""
    ca1, sa1 = c1
    ca2, sa2 = c2
    cb = (ca1 * ca2 - M[8]) / (sa1 * sa2)
    cb = 1.0 if cb > 1.0 else (-1.0 if cb < -1.0 else cb)
    if ca1 == 0.0 and ca2 == 0.0:
        # alphas ±90 deg: M[:, 2] = (cos a, sin a) s2 sin b and M[2, :2] = s1 sin b (cos c, -sin c),
        # so |sin b| is exact where acos is not (b near 0 or pi, the wrist singularity)
        sb = math.hypot(M[2], M[5])
        b0 = math.atan2(sb, cb)
        if sb > 1e-6:
            out = []
            for sign in (1.0, -1.0):
                k, kc = sign * sa2, sign * sa1
                out.append((math.atan2(k * M[5], k * M[2]), sign * b0, math.atan2(-kc * M[7], kc * M[6])))
            return out
    else:
        b0 = math.acos(cb)
    out = []
    for sign in (1.0, -1.0):
        b = sign * b0
        sb = math.sin(b)
        if abs(sb) > _SING:
            a = math.atan2(M[5], M[2]) - math.atan2(-ca1 * cb * sa2 - sa1 * ca2, sb * sa2)
        else:
            a = a_ref
        # c from the full remaining rotation: it absorbs the round-off of a near sin b = 0
        X = _tmul(_mul(_rzrx(a, ca1, sa1), _rzrx(b, ca2, sa2)), M)
        out.append((a, b, math.atan2(X[3], X[0])))
        if abs(sb) <= _SING:
            break  # b = 0 or pi: the second solution is the first
    return out


def _pose_arm(solver: "ClosedForm", T: np.ndarray) -> tuple[Rot, list[float]]:
    """Rotation and position of the flange in the arm's base frame (base and tool removed)."""
    T06 = T
    if solver.base_inv is not None:
        T06 = solver.base_inv @ T06
    if solver.tool_inv is not None:
        T06 = T06 @ solver.tool_inv
    r = T06[:3, :].tolist()
    return (r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2]), \
        [r[0][3], r[1][3], r[2][3]]


# ---------------------------------------------------------------------------- families
def _close(x: Sequence[float], y: Sequence[float]) -> bool:
    return all(abs(a - b) < 1e-9 for a, b in zip(x, y))


def family(robot: Any) -> str | None:
    """``"puma"``, ``"ur"``, ``"srs"`` or None (no closed form known for this arm)."""
    robot._params()
    if robot.mdh or robot._prism.any():
        return None
    al = (robot._alpha / (_PI / 2)).tolist()
    a, d = robot._a.tolist(), robot._d.tolist()
    if robot.n == 6:
        if _close(al, [1, 0, -1, 1, -1, 0]) and _close([a[0], a[3], a[4], a[5], d[1], d[4]], [0] * 6):
            return "puma"
        if _close(al, [1, 0, 0, 1, -1, 0]) and _close([a[0], a[3], a[4], a[5], d[1], d[2]], [0] * 6) \
                and a[1] != 0.0 and a[2] != 0.0 and d[5] != 0.0:
            return "ur"
    if robot.n == 7 and _close(a, [0] * 7) and _close([d[1], d[3], d[5]], [0] * 3) \
            and all(abs(abs(x) - 1) < 1e-9 for x in al[:6]) and d[2] > 0 and d[4] > 0:
        return "srs"
    return None


class ClosedForm:
    """All closed-form solutions of one arm (cached per robot parameters)."""

    def __init__(self, robot: Any, kind: str) -> None:
        robot._params()
        self.kind = kind
        self.n = robot.n
        self.a = robot._a.tolist()
        self.d = robot._d.tolist()
        self.cs = list(zip(robot._ca.tolist(), robot._sa.tolist()))
        self.cs = [(0.0 if abs(c) < 1e-12 else c, 0.0 if abs(s) < 1e-12 else s) for c, s in self.cs]
        self.offset = robot._offset.tolist()
        self.has_offset = any(self.offset)
        self._family = getattr(self, "_" + kind)
        self.base_inv = None if robot._base_is_eye else np.linalg.inv(robot.base)
        self.tool_inv = None if robot._tool_is_eye else np.linalg.inv(robot.tool)

    def solve(self, T: np.ndarray, q_ref: Sequence[float]) -> tuple[list[list[float]], list[str]]:
        """Joint vectors (offsets removed, angles not wrapped to the limits) reaching ``T``
        (``T_world_tool`` (4, 4)) and their labels; empty when the pose is out of reach.
        ``q_ref``: the reference configuration giving the free angles (singular wrist,
        ``q3`` of a 7R arm)."""
        out = list(self.candidates(T, q_ref))
        return [q for q, _ in out], [c for _, c in out]

    def candidates(self, T: np.ndarray, q_ref: Sequence[float],
                   q3: float | None = None) -> Iterator[tuple[list[float], str]]:
        """The solutions of :meth:`solve` one by one, computed lazily, roughly nearest to
        ``q_ref`` first (the arm branches by their first joints, then the wrist's pair).
        ``q3``: joint 3 of a 7R arm (default ``q_ref``'s)."""
        R, p = _pose_arm(self, T)
        off = self.offset
        if not self.has_offset:
            ref = q_ref if isinstance(q_ref, list) else list(q_ref)
            if self.kind == "srs":
                return self._srs(R, p, ref, ref[2] if q3 is None else q3)
            return self._family(R, p, ref)
        ref = [q + o for q, o in zip(q_ref, off)]
        if self.kind == "srs":
            gen = self._srs(R, p, ref, ref[2] if q3 is None else q3 + off[2])
        else:
            gen = self._family(R, p, ref)
        return (([t - o for t, o in zip(th, off)], label) for th, label in gen)

    def _wrist_centre(self, R: Rot, p: list[float]) -> list[float]:
        """Flange position minus the last link's ``d`` along the last joint's axis."""
        c, s = self.cs[-1]
        dn = self.d[-1]
        # z_{n-1} = R Rx(-alpha_n) e_z = s R[:, 1] + c R[:, 2]
        return [p[0] - dn * (s * R[1] + c * R[2]), p[1] - dn * (s * R[4] + c * R[5]),
                p[2] - dn * (s * R[7] + c * R[8])]

    # ------------------------------------------------------------------ Puma 560 type
    def _puma(self, R: Rot, p: list[float], ref: list[float]) -> Iterator[tuple[list[float], str]]:
        a2, a3 = self.a[1], self.a[2]
        d1, d3, d4 = self.d[0], self.d[2], self.d[3]
        px, py, pz = self._wrist_centre(R, p)
        pz -= d1
        rho = math.hypot(px, py)
        if rho < abs(d3) or rho == 0.0:
            return
        phi = math.atan2(py, px)
        delta = math.asin(d3 / rho)
        beta = math.atan2(a3, d4)
        r1, r2, r3 = ref[0], ref[1], ref[2]
        arms = []
        for arm in ("l", "r"):
            th1 = phi + delta if arm == "r" else phi + _PI - delta
            e1 = (th1 - r1 + _PI) % _TWO_PI - _PI
            arms.append((e1 * e1, th1, arm))
        if arms[1][0] < arms[0][0]:
            arms.reverse()
        cs = self.cs
        for _, th1, arm in arms:  # the arm nearest the reference first, then its elbows
            c1, s1 = math.cos(th1), math.sin(th1)
            X = px * c1 + py * s1
            r = math.hypot(X, pz)
            if r == 0.0:
                continue
            # Paul and Zhang 1986 as Robotics Toolbox's Puma560.ikine_a: the elbow sign n2
            psi = _acos2((a2 * a2 - d4 * d4 - a3 * a3 + X * X + pz * pz) / (2.0 * a2 * r))
            if psi is None:
                continue
            gamma = math.atan2(pz, X)
            elbows = []
            for elbow in ("u", "d"):
                n2 = 1.0 if elbow == "u" else -1.0
                if arm == "l":
                    n2 = -n2
                th2 = gamma + n2 * psi
                c2, s2 = math.cos(th2), math.sin(th2)
                th3 = beta - math.atan2(c2 * X + s2 * pz - a2, c2 * pz - s2 * X)
                u = (th2 - r2 + _PI) % _TWO_PI - _PI
                w = (th3 - r3 + _PI) % _TWO_PI - _PI
                elbows.append((u * u + w * w, th2, th3, elbow))
            if elbows[1][0] < elbows[0][0]:
                elbows.reverse()
            for _, th2, th3, elbow in elbows:
                # R03 = Rz(q1) Rx(90 deg) Rz(q2 + q3) Rx(-90 deg) (alpha2 = 0 merges q2 and q3)
                c23, s23 = math.cos(th2 + th3), math.sin(th2 + th3)
                M = _tmul((c1 * c23, -s1, -c1 * s23, s1 * c23, c1, -s1 * s23, s23, 0.0, c23), R)
                for a, b, c in _nearest(wrist(M, cs[3], cs[4], ref[3]), ref[3:6]):
                    # Robotics Toolbox: wrist "n" when the Euler angle -q5 is in [0, pi] (alpha4 > 0)
                    flip = (b > 0) == (cs[3][1] > 0)
                    yield [th1, th2, th3, a, b, c], arm + elbow + ("f" if flip else "n")

    # ------------------------------------------------------------------ UR type
    def _ur(self, R: Rot, p: list[float], ref: list[float]) -> Iterator[tuple[list[float], str]]:
        d4 = self.d[3]
        x5, y5, z5 = self._wrist_centre(R, p)  # origin of frame 5
        rho = math.hypot(x5, y5)
        if rho < abs(d4) or rho == 0.0:
            return
        phi = math.atan2(y5, x5)
        beta = math.acos(max(-1.0, min(1.0, d4 / rho)))
        shoulders = []
        for sh, th1 in (("l", phi + beta + _PI / 2), ("r", phi - beta + _PI / 2)):
            e1 = (th1 - ref[0] + _PI) % _TWO_PI - _PI
            shoulders.append((e1 * e1, th1, sh))
        if shoulders[1][0] < shoulders[0][0]:
            shoulders.reverse()
        r5, r6 = ref[4], ref[5]
        for _, th1, sh in shoulders:  # the shoulder nearest the reference first
            c1, s1 = math.cos(th1), math.sin(th1)
            # cos q5 = z6 . z1, z1 = (s1, -c1, 0) the axis of joints 2-4; |sin q5| from the
            # other two components (accurate near q5 = 0, where acos is not)
            g = math.atan2(math.hypot(R[2] * c1 + R[5] * s1, R[8]), R[2] * s1 - R[5] * c1)
            wrists = []
            for wr, th5 in (("n", g), ("f", -g)):
                s5 = math.sin(th5)
                if abs(s5) > _SING:
                    k = 1.0 if s5 > 0 else -1.0
                    th6 = math.atan2(k * (-R[1] * s1 + R[4] * c1), k * (R[0] * s1 - R[3] * c1))
                else:
                    th6 = r6
                u = (th5 - r5 + _PI) % _TWO_PI - _PI
                w = (th6 - r6 + _PI) % _TWO_PI - _PI
                wrists.append((u * u + w * w, th5, th6, wr))
            if wrists[1][0] < wrists[0][0]:
                wrists.reverse()
            for _, th5, th6, wr in wrists:
                if abs(math.sin(th5)) > _SING:
                    elbows = self._ur_arm(R, (x5, y5, z5), th1, th5, th6, ref)
                else:
                    # joint 6 parallel to joints 2-4: q6 trades against q2 + q3 + q4; take
                    # the one nearest the reference for which the 2R elbow reaches
                    elbows = []
                    for k in range(24):
                        th6 = r6 + (k + 1) // 2 * (1 if k % 2 else -1) * (2 * _PI / 24)
                        elbows = self._ur_arm(R, (x5, y5, z5), th1, th5, th6, ref)
                        if elbows:
                            break
                for _, th2, th3, th4, th6e, el in elbows:
                    yield [th1, th2, th3, th4, th5, th6e], sh + el + wr

    def _ur_arm(self, R: Rot, o5: tuple[float, float, float], th1: float, th5: float, th6: float,
                ref: list[float]) -> list[tuple]:
        """UR joints 2-4 given 1, 5 and 6: ``(distance, q2, q3, q4, q6, label)`` sorted.

        ``R04 = R06 R46^T`` with ``R46 = Rz(q5) Rx(alpha5) Rz(q6)`` (alpha6 = 0): only its
        x and z columns are needed, from R46's first and last rows."""
        a2, a3 = self.a[1], self.a[2]
        d1, d5 = self.d[0], self.d[4]
        (ca1, sa1), _, _, _, (ca5, sa5), _ = self.cs
        x5, y5, z5 = o5
        c1, s1 = math.cos(th1), math.sin(th1)
        c5, s5 = math.cos(th5), math.sin(th5)
        c6, s6 = math.cos(th6), math.sin(th6)
        r0 = (c5 * c6 - s5 * ca5 * s6, -c5 * s6 - s5 * ca5 * c6, s5 * sa5)  # R46[0, :]
        r2 = (sa5 * s6, sa5 * c6, ca5)  # R46[2, :]
        x4 = (R[0] * r0[0] + R[1] * r0[1] + R[2] * r0[2], R[3] * r0[0] + R[4] * r0[1] + R[5] * r0[2],
              R[6] * r0[0] + R[7] * r0[1] + R[8] * r0[2])
        z4 = (R[0] * r2[0] + R[1] * r2[1] + R[2] * r2[2], R[3] * r2[0] + R[4] * r2[1] + R[5] * r2[2],
              R[6] * r2[0] + R[7] * r2[1] + R[8] * r2[2])
        # frame 1's x and y axes: A1 = Rz(q1) Rx(alpha1)
        ex = (c1, s1, 0.0)
        ey = (-s1 * ca1, c1 * ca1, sa1)
        # origin of frame 4 = origin of frame 5 - d5 z4, less frame 1's origin (0, 0, d1):
        # a planar 2R problem in frame 1's x-y plane
        v0, v1, v2 = x5 - d5 * z4[0], y5 - d5 * z4[1], z5 - d5 * z4[2] - d1
        X = ex[0] * v0 + ex[1] * v1
        Y = ey[0] * v0 + ey[1] * v1 + ey[2] * v2
        c3 = _acos2((X * X + Y * Y - a2 * a2 - a3 * a3) / (2.0 * a2 * a3))
        if c3 is None:
            return []
        th234 = math.atan2(ey[0] * x4[0] + ey[1] * x4[1] + ey[2] * x4[2], ex[0] * x4[0] + ex[1] * x4[1])
        elbows = []
        base = math.atan2(Y, X)
        for el, th3 in (("u", c3), ("d", -c3)):
            th2 = base - math.atan2(a3 * math.sin(th3), a2 + a3 * math.cos(th3))
            th4 = _wrap(th234 - th2 - th3)
            elbows.append((_dist((th2, th3, th4), ref[1:4]), th2, th3, th4, th6, el))
        if elbows[1][0] < elbows[0][0]:
            elbows.reverse()
        return elbows

    # ------------------------------------------------------------------ 7R S-R-S
    def _srs(self, R: Rot, p: list[float], ref: list[float], th3: float) -> Iterator[tuple[list[float], str]]:
        d1, d3, d5 = self.d[0], self.d[2], self.d[4]
        cs = self.cs
        w = self._wrist_centre(R, p)
        v = [w[0], w[1], w[2] - d1]  # shoulder -> wrist, base frame
        L2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
        (ca1, sa1), (ca2, sa2), (ca3, sa3), (ca4, sa4) = cs[:4]
        c4 = _acos2(((L2 - d3 * d3 - d5 * d5) / (2.0 * d3 * d5) - ca3 * ca4) / (-sa3 * sa4))
        if c4 is None:
            return
        c3, s3 = math.cos(th3), math.sin(th3)
        branches = []
        for el, th4 in (("u", c4), ("d", -c4)):
            # shoulder -> wrist in frame 2: Rz(q3) (d3 e_z + Rx(alpha3) d5 z4), z4 in frame 3
            z4 = [sa4 * math.sin(th4), -sa4 * math.cos(th4), ca4]
            u = [d5 * z4[0], d5 * (ca3 * z4[1] - sa3 * z4[2]), d3 + d5 * (sa3 * z4[1] + ca3 * z4[2])]
            v2 = [c3 * u[0] - s3 * u[1], s3 * u[0] + c3 * u[1], u[2]]
            wv = [v2[0], ca2 * v2[1] - sa2 * v2[2], sa2 * v2[1] + ca2 * v2[2]]  # Rx(alpha2) v2
            # z of Rz(q1) Rx(alpha1) Rz(q2) wv must be v's: A sin q2 + B cos q2 = C
            A, B, C = sa1 * wv[0], sa1 * wv[1], v[2] - ca1 * wv[2]
            rAB = math.hypot(A, B)
            if rAB < _SING:
                th2s = [ref[1]] if abs(C) < 1e-9 else []
            else:
                g = _acos2(C / rAB)
                if g is None:
                    continue
                base2 = math.atan2(A, B)
                th2s = [base2 + g, base2 - g] if g > 0 else [base2]
            for k, th2 in enumerate(th2s):
                c2, s2 = math.cos(th2), math.sin(th2)
                x = [c2 * wv[0] - s2 * wv[1], s2 * wv[0] + c2 * wv[1], wv[2]]
                xp = [x[0], ca1 * x[1] - sa1 * x[2]]
                if math.hypot(v[0], v[1]) < _SING and math.hypot(*xp) < _SING:
                    th1 = ref[0]
                else:
                    th1 = math.atan2(v[1], v[0]) - math.atan2(xp[1], xp[0])
                branches.append((_dist((th1, th2, th4), (ref[0], ref[1], ref[3])), th1, th2, th4,
                                 ("s" if k == 0 else "t") + el))
        branches.sort(key=_first)
        for _, th1, th2, th4, label in branches:
            R04 = _chain([th1, th2, th3, th4], cs[:4])
            M = _tmul(R04, R)
            if cs[6][1] != 0.0:
                M = _mul(M, _rzrx(0.0, cs[6][0], -cs[6][1]))  # Rx(-alpha7)
            for a, b, c in _nearest(wrist(M, cs[4], cs[5], ref[4]), ref[4:7]):
                yield [th1, th2, th3, th4, a, b, c], label + ("n" if b >= 0 else "f")


def _first(x: tuple) -> float:
    return x[0]


def _dist(th: Sequence[float], ref: Sequence[float]) -> float:
    """Squared distance between three angles, each difference wrapped to [-pi, pi)."""
    a = (th[0] - ref[0] + _PI) % _TWO_PI - _PI
    b = (th[1] - ref[1] + _PI) % _TWO_PI - _PI
    c = (th[2] - ref[2] + _PI) % _TWO_PI - _PI
    return a * a + b * b + c * c


def _nearest(sols: list[tuple[float, float, float]], ref: Sequence[float]) -> list[tuple[float, float, float]]:
    if len(sols) == 2 and _dist(sols[1], ref) < _dist(sols[0], ref):
        return [sols[1], sols[0]]
    return sols


def solver(robot: Any) -> ClosedForm | None:
    """The arm's closed-form solver, cached with its generated kernels; None if none."""
    robot._params()
    key = ("ik_closed",)
    cached = robot._kernels.get(key, False)
    if cached is False:
        kind = family(robot)
        cached = robot._kernels[key] = None if kind is None else ClosedForm(robot, kind)
    return cached
