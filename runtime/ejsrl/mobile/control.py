"""Controllers of a wheeled vehicle (Corke, *Robotics, Vision and Control*, ch. 4): move to
a point, move to a pose, follow a line, follow a path (pure pursuit).

Each takes the current pose ``x = (x, y, theta)`` and returns the controls of a
:class:`~ejsrl.mobile.Bicycle`, ``(v, gamma)`` (speed m/s, steering angle rad); with
``L=None`` (no wheel base) the controls of a unicycle, ``(v, omega)`` (rad/s).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ._util import Array, angdiff, vector

__all__ = ["move_to_point", "move_to_pose", "pose_direction", "follow_line", "pure_pursuit", "lookahead_point"]


def _steer(v: float, omega: float, L: float | None) -> Array:
    """``(v, omega)`` as unicycle controls, or as bicycle ones ``(v, atan(omega L / v))``."""
    if L is None:
        return np.array([v, omega])
    if abs(v) < 1e-12:
        return np.array([v, 0.0])
    return np.array([v, math.atan(omega * L / v)])


def move_to_point(x: ArrayLike, goal: ArrayLike, *, Kv: float = 0.5, Kh: float = 4.0) -> Array:
    """Drive towards the point ``goal`` (2,): speed ``Kv * distance``, steering ``Kh *``
    (heading error to the goal) (the steering angle for a bicycle, the turn rate else)."""
    x = vector(x, 3, "x")
    g = vector(goal, 2, "goal")
    dx, dy = g[0] - x[0], g[1] - x[1]
    heading = angdiff(math.atan2(dy, dx), x[2])
    return np.array([Kv * math.hypot(dx, dy), Kh * heading])


def pose_direction(x: ArrayLike, goal: ArrayLike) -> int:
    """+1 if the goal lies ahead of the vehicle (its bearing within +-pi/2 of the
    heading), -1 if behind: the direction to give :func:`move_to_pose` for a whole
    manoeuvre (chosen once, so it cannot switch back and forth on the way)."""
    x = vector(x, 3, "x")
    g = np.asarray(goal, dtype=float)
    return 1 if abs(angdiff(math.atan2(g[1] - x[1], g[0] - x[0]), x[2])) <= math.pi / 2 else -1


def move_to_pose(x: ArrayLike, goal: ArrayLike, *, Krho: float = 1.0, Kalpha: float = 6.0, Kbeta: float = -6.0,
                 L: float | None = 1.0, direction: int = 0) -> Array:
    """Drive to the pose ``goal = (x, y, theta)`` in polar coordinates: ``rho`` the distance
    to the goal, ``alpha`` the goal's bearing from the heading, ``beta = theta* - theta -
    alpha``; ``v = Krho rho``, ``omega = Kalpha alpha + Kbeta beta`` (stable for ``Krho > 0``,
    ``Kbeta < 0``, ``Kalpha > Krho``). Linearised, alpha and beta decay with the roots of
    ``s^2 + (Kalpha - Krho) s - Krho Kbeta``: the defaults put them at -2 and -3, faster than
    rho's -Krho, so a car (whose turn rate vanishes with its speed) is aligned before it
    stops (Kalpha = 5, Kbeta = -2 leave up to 0.06 rad). A goal behind the vehicle
    (|alpha| > pi/2) is reached in reverse with ``direction=0`` (decided at each call:
    on a goal near the vehicle's side the choice can flip from one call to the next and
    the vehicle dither in place; a simulation should fix it for the manoeuvre with
    ``direction=pose_direction(x_start, goal)``: 1 forwards, -1 in reverse). Bicycle
    steering ``atan(omega L / v)``."""
    x = vector(x, 3, "x")
    g = vector(goal, 3, "goal")
    dx, dy = g[0] - x[0], g[1] - x[1]
    rho = math.hypot(dx, dy)
    bearing = math.atan2(dy, dx)
    th = x[2]
    alpha = angdiff(bearing, th)
    sign = 1.0
    if direction < 0 or (direction == 0 and abs(alpha) > math.pi / 2):
        th = th + math.pi  # drive the rear first: the same law seen from the back
        alpha = angdiff(bearing, th)
        sign = -1.0
    beta = angdiff(g[2] + (math.pi if sign < 0 else 0.0), th + alpha)
    v = sign * Krho * rho
    omega = Kalpha * alpha + Kbeta * beta
    return _steer(v, omega, L)


def follow_line(x: ArrayLike, line: ArrayLike, *, v: float = 1.0, Kd: float = 0.5, Kh: float = 1.0) -> Array:
    """Follow the line ``a x + b y + c = 0`` (``line = (a, b, c)``) at speed v: steering
    ``-Kd d + Kh (theta* - theta)``, d the signed distance to the line and ``theta* =
    atan2(-a, b)`` its direction."""
    x = vector(x, 3, "x")
    a, b, c = (float(t) for t in vector(line, 3, "line"))
    n = math.hypot(a, b)
    if n == 0:
        raise ValueError("follow_line: a line (a, b, c) needs a or b non-zero")
    d = (a * x[0] + b * x[1] + c) / n
    return np.array([v, -Kd * d + Kh * angdiff(math.atan2(-a, b), x[2])])


def lookahead_point(x: ArrayLike, path: ArrayLike, lookahead: float) -> Array:
    """The point of the polyline ``path`` (N, 2) at distance ``lookahead`` (m) from the
    vehicle, past the path point nearest to it (the last point when the path ends
    within the look-ahead)."""
    p = np.asarray(x, dtype=float)[:2]
    P = np.asarray(path, dtype=float)
    if P.ndim != 2 or P.shape[1] != 2 or len(P) < 2:
        raise ValueError(f"a path is (N, 2) points with N >= 2, got shape {P.shape}")
    k = int(np.argmin(np.hypot(*(P - p).T)))
    k = max(k - 1, 0)
    for i in range(k, len(P) - 1):
        a, b = P[i], P[i + 1]
        d = b - a
        f = a - p
        A, B, C = d @ d, 2 * (f @ d), f @ f - lookahead**2
        disc = B * B - 4 * A * C
        if A == 0 or disc < 0:
            continue
        t = (-B + math.sqrt(disc)) / (2 * A)  # the far intersection: ahead along the path
        if 0.0 <= t <= 1.0:
            return a + t * d
    return P[-1].copy()


def pure_pursuit(x: ArrayLike, path: ArrayLike, *, lookahead: float = 1.0, v: float = 1.0,
                 L: float | None = 1.0) -> Array:
    """Pure pursuit along the polyline ``path`` (N, 2): steer on the arc through the point
    ``lookahead`` ahead (:func:`lookahead_point`), curvature ``2 sin(alpha) / l_d`` with
    alpha its bearing and l_d its distance; bicycle steering ``atan(L kappa)``, unicycle
    turn rate ``v kappa``. On a circle of radius R the steady steering is ``atan(L / R)``."""
    x = vector(x, 3, "x")
    g = lookahead_point(x, path, lookahead)
    dx, dy = g[0] - x[0], g[1] - x[1]
    ld = math.hypot(dx, dy)
    if ld < 1e-12:
        return np.array([0.0, 0.0])
    alpha = angdiff(math.atan2(dy, dx), x[2])
    kappa = 2.0 * math.sin(alpha) / ld
    if L is None:
        return np.array([v, v * kappa])
    return np.array([v, math.atan(L * kappa)])
