"""Wheeled vehicles as the Robotics Toolbox names them: :class:`Bicycle` (car-like),
:class:`Unicycle`, :class:`DiffSteer` (differential drive) and :class:`Omni`.

The state is the pose ``x = (x, y, theta)`` (m, m, rad) in the world; ``deriv(x, u)`` is
the kinematic model as an ODE (use it in a spec's ``equations``), ``step(u)`` moves the
vehicle one sample ``dt`` (Euler, as the Toolbox) and returns the odometry ``(distance,
heading change)`` with noise of covariance ``covar`` drawn from ``np.random.default_rng(seed)``
(the same numbers as the Toolbox's vehicle with the same seed). ``f``, ``Fx``, ``Fv`` are the
odometry motion model and its Jacobians for an EKF.
"""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np
from numpy.typing import ArrayLike

from ._util import Array, vector

__all__ = ["VehicleBase", "Bicycle", "Unicycle", "DiffSteer", "Omni"]

Control = Callable[["VehicleBase", float, Array], ArrayLike]


class VehicleBase:
    """What every vehicle shares: limits, the state, odometry with noise.

    Args:
        covar: (2, 2) covariance of the odometry noise (distance m, angle rad); None: none.
        speed_max: largest speed (m/s); accel_max: largest change of speed (m/s^2).
        x0: initial pose (3,); dt: sample time of ``step`` (s).
        control: default control for ``step``: a constant ``u`` or a function ``u(vehicle, t, x)``.
        seed: seed of the odometry noise (None: from the operating system).
    """

    nu = 2  # number of control inputs

    def __init__(self, *, covar: ArrayLike | None = None, speed_max: float = math.inf, accel_max: float = math.inf,
                 x0: ArrayLike = (0.0, 0.0, 0.0), dt: float = 0.1, control: ArrayLike | Control | None = None,
                 seed: int | None = 0) -> None:
        self.V = None if covar is None else np.asarray(covar, dtype=float).reshape(2, 2)
        self.speed_max = float(speed_max)
        self.accel_max = float(accel_max)
        if not dt > 0:
            raise ValueError(f"dt must be positive, got {dt!r}")
        self.dt = float(dt)
        self.x0 = vector(x0, 3, "x0")
        self.control = control
        self.seed = seed
        self.init()

    def init(self, x0: ArrayLike | None = None) -> None:
        """Back to ``x0`` (or the given pose) at t = 0, the noise generator re-seeded."""
        self.x = self.x0.copy() if x0 is None else vector(x0, 3, "x0")
        self.t = 0.0
        self.x_hist: list[Array] = []
        self._v_prev = [0.0]
        self.random = np.random.default_rng(self.seed)

    # ------------------------------------------------------------------ model
    def deriv(self, x: ArrayLike, u: ArrayLike, limits: bool = True) -> Array:  # pragma: no cover - abstract
        """Rate of the state ``(xdot, ydot, thetadot)`` at state x under controls u."""
        raise NotImplementedError

    def u_limited(self, u: ArrayLike) -> Array:  # pragma: no cover - abstract
        raise NotImplementedError

    def _limit_speed(self, v: float, prev: list[float]) -> float:
        """The Toolbox's ``limits_va``: acceleration, then speed limit."""
        vp = prev[0]
        if (v - vp) / self.dt > self.accel_max:
            v = vp + self.accel_max * self.dt
        elif (v - vp) / self.dt < -self.accel_max:
            v = vp - self.accel_max * self.dt
        prev[0] = v
        return min(max(v, -self.speed_max), self.speed_max)

    def f(self, x: ArrayLike, odo: ArrayLike, w: ArrayLike | None = None) -> Array:
        """The pose after odometry ``(d, dtheta)`` (plus noise w) from pose x (3,) or (m, 3)."""
        d, dth = (float(v) for v in vector(odo, 2, "odo"))
        X = np.asarray(x, dtype=float)
        if X.ndim == 2:
            th = X[:, 2]
            return X + np.column_stack((d * np.cos(th), d * np.sin(th), np.full(th.shape, dth)))
        if w is not None:
            d, dth = d + float(w[0]), dth + float(w[1])
        th = float(X[2])
        return X + np.array([d * math.cos(th), d * math.sin(th), dth])

    def Fx(self, x: ArrayLike, odo: ArrayLike) -> Array:
        """Jacobian (3, 3) of :meth:`f` with respect to the pose."""
        d = float(odo[0])
        th = float(x[2])
        return np.array([[1.0, 0.0, -d * math.sin(th)], [0.0, 1.0, d * math.cos(th)], [0.0, 0.0, 1.0]])

    def Fv(self, x: ArrayLike, odo: ArrayLike) -> Array:
        """Jacobian (3, 2) of :meth:`f` with respect to the odometry noise."""
        th = float(x[2])
        return np.array([[math.cos(th), 0.0], [math.sin(th), 0.0], [0.0, 1.0]])

    # ------------------------------------------------------------------ simulation
    def eval_control(self, u: ArrayLike | Control | None) -> Array:
        u = self.control if u is None else u
        if u is None:
            raise ValueError("no control: pass u to step() or give the vehicle a control")
        if callable(u):
            u = u(self, self.t, self.x)
        return self.u_limited(vector(u, self.nu, "the control"))

    def step(self, u: ArrayLike | Control | None = None) -> Array:
        """Move one sample: the new pose in ``self.x``; returns the odometry ``(d, dtheta)``
        (noisy when ``covar`` is given)."""
        ul = self.eval_control(u)
        xd = self.dt * self.deriv(self.x, ul)
        self.x = self.x + xd
        self.x_hist.append(self.x.copy())
        odo = np.array([math.hypot(xd[0], xd[1]), xd[2]])
        if self.V is not None:
            odo = odo + self.random.multivariate_normal((0.0, 0.0), self.V)
        self.t += self.dt
        return odo

    def run(self, T: float, u: ArrayLike | Control | None = None, x0: ArrayLike | None = None) -> Array:
        """Simulate for ``T`` s from x0: the poses (k + 1, 3), the first the start."""
        self.init(x0)
        out = [self.x.copy()]
        for _ in range(int(round(T / self.dt))):
            self.step(u)
            out.append(self.x.copy())
        return np.array(out)

    @property
    def q(self) -> Array:
        """The configuration ``(x, y, theta)`` (a copy of the state)."""
        return self.x.copy()


class _SpeedTurnLimited(VehicleBase):
    """A vehicle whose controls are ``(speed, turn)``: the speed limited as a speed, the turn
    (steering angle or turn rate) clipped to +-``steer_max``."""

    steer_max: float

    def u_limited(self, u: ArrayLike) -> Array:
        ul = np.array(u, dtype=float)
        ul[0] = self._limit_speed(ul[0], self._v_prev)
        ul[1] = min(max(ul[1], -self.steer_max), self.steer_max)
        return ul


class Bicycle(_SpeedTurnLimited):
    """Car-like vehicle (kinematic bicycle): controls ``u = (v, gamma)``, speed (m/s) and
    steering angle (rad) clipped to +-``steer_max``; wheel base ``L`` (m).
    ``xdot = v cos(theta), ydot = v sin(theta), thetadot = v tan(gamma) / L``."""

    def __init__(self, L: float = 1.0, steer_max: float = 0.45 * math.pi, **kwargs: Any) -> None:
        self.l = float(L)
        self.steer_max = float(steer_max)
        super().__init__(**kwargs)

    @property
    def radius_min(self) -> float:
        """Smallest turning radius (m): ``L / tan(steer_max)``."""
        return self.l / math.tan(self.steer_max)

    @property
    def curvature_max(self) -> float:
        return 1.0 / self.radius_min

    def deriv(self, x: ArrayLike, u: ArrayLike, limits: bool = True) -> Array:
        if limits:
            u = self.u_limited(u)
        th = float(x[2])
        v, g = float(u[0]), float(u[1])
        return v * np.array([math.cos(th), math.sin(th), math.tan(g) / self.l])


class Unicycle(_SpeedTurnLimited):
    """Unicycle: controls ``u = (v, omega)``, speed (m/s) and turn rate (rad/s, clipped to
    +-``steer_max``); ``W`` the wheel separation (m) for drawing."""

    def __init__(self, W: float = 1.0, steer_max: float = math.inf, **kwargs: Any) -> None:
        self.W = float(W)
        self.steer_max = float(steer_max)
        super().__init__(**kwargs)

    def deriv(self, x: ArrayLike, u: ArrayLike, limits: bool = True) -> Array:
        if limits:
            u = self.u_limited(u)
        th = float(x[2])
        v, w = float(u[0]), float(u[1])
        return np.array([v * math.cos(th), v * math.sin(th), w])


class DiffSteer(Unicycle):
    """Differential drive: controls ``u = (v_left, v_right)``, the wheels' speeds (m/s,
    each limited as a speed); ``W`` the wheel separation (m): ``thetadot = (vR - vL) / W``."""

    def init(self, x0: ArrayLike | None = None) -> None:
        super().init(x0)
        self._v_prev_L = [0.0]
        self._v_prev_R = [0.0]

    def u_limited(self, u: ArrayLike) -> Array:
        ul = np.array(u, dtype=float)
        ul[0] = self._limit_speed(ul[0], self._v_prev_L)
        ul[1] = self._limit_speed(ul[1], self._v_prev_R)
        return ul

    def deriv(self, x: ArrayLike, u: ArrayLike, limits: bool = True) -> Array:
        if limits:
            u = self.u_limited(u)
        th = float(x[2])
        vl, vr = float(u[0]), float(u[1])
        v = 0.5 * (vl + vr)
        return np.array([v * math.cos(th), v * math.sin(th), (vr - vl) / self.W])


class Omni(VehicleBase):
    """Omnidirectional base (Mecanum or Swedish wheels): controls ``u = (vx, vy, omega)``,
    the velocity in the vehicle's own frame (m/s, the speed limited to ``speed_max``) and
    the turn rate (rad/s)."""

    nu = 3

    def u_limited(self, u: ArrayLike) -> Array:
        ul = np.array(u, dtype=float)
        s = math.hypot(ul[0], ul[1])
        if s > self.speed_max:
            ul[:2] *= self.speed_max / s
        return ul

    def deriv(self, x: ArrayLike, u: ArrayLike, limits: bool = True) -> Array:
        if limits:
            u = self.u_limited(u)
        th = float(x[2])
        c, s = math.cos(th), math.sin(th)
        return np.array([c * u[0] - s * u[1], s * u[0] + c * u[1], u[2]])
