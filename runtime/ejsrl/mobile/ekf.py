"""Extended Kalman filter for a vehicle with odometry and a range-bearing sensor, as the
Toolbox's ``EKF``: dead reckoning (no sensor), localisation (a known landmark map) and
EKF-SLAM (``map=None``: landmarks are added to the state as they are first seen).

State: the vehicle pose ``(x, y, theta)`` then, for SLAM, each landmark's ``(x, y)`` in the
order first seen (``landmarks[id] = [position in that order, times seen]``); ``P`` its
covariance. ``step()`` moves the vehicle one sample, then predicts and updates;
``predict(odo)`` and ``update(z, id)`` do one half each, for a model that steps itself.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import block_diag

from ._util import Array, wrap

__all__ = ["EKF", "EKFLog"]


class EKFLog(NamedTuple):
    t: float
    x_est: Array
    odo: Array
    P: Array
    innov: Array | None
    lm_id: int


class EKF:
    """Args:
        robot: ``(vehicle, V_est)``: the vehicle and the odometry covariance (2, 2) the filter
            assumes (None: the vehicle pose is known, only the map is estimated).
        sensor: ``(RangeBearingSensor, W_est)``, the sensor and its covariance (2, 2).
        map: the landmark map for localisation; None with a sensor: SLAM.
        P0: initial covariance (3, 3) of the pose; x0: initial pose estimate (3,).
        joseph: update P in Joseph form (default, as the Toolbox).
    """

    def __init__(self, robot: tuple[Any, ArrayLike | None], sensor: tuple[Any, ArrayLike] | None = None,
                 map: Any = None, P0: ArrayLike | None = None, x0: ArrayLike = (0.0, 0.0, 0.0),
                 joseph: bool = True, history: bool = True) -> None:
        self.robot, V = robot
        self.V_est = None if V is None else np.asarray(V, dtype=float).reshape(2, 2)
        self.sensor, W = (None, None) if sensor is None else sensor
        self.W_est = None if W is None else np.asarray(W, dtype=float).reshape(2, 2)
        self.map = map
        self.est_vehicle = self.V_est is not None
        self.est_map = map is None and self.sensor is not None
        self.P0 = None if P0 is None else np.asarray(P0, dtype=float)
        self.x0 = np.asarray(x0, dtype=float)
        self.joseph = joseph
        self.keep_history = history
        self.init()

    def init(self) -> None:
        """Restart: the vehicle and sensor re-initialised, the estimate back to x0, P0."""
        self.robot.init()
        if self.sensor is not None:
            self.sensor.init()
        self.history: list[EKFLog] = []
        self.landmarks: dict[int, list[int]] = {}
        if self.est_vehicle:
            self.x_est = self.x0.copy()
            self.P_est = np.zeros((3, 3)) if self.P0 is None else self.P0.copy()
        else:
            self.x_est = np.zeros(0)
            self.P_est = np.zeros((0, 0))

    # ------------------------------------------------------------------ filter
    def predict(self, odo: ArrayLike) -> None:
        """Propagate the estimate by odometry ``(d, dtheta)`` (the vehicle's motion model)."""
        odo = np.asarray(odo, dtype=float)
        if not self.est_vehicle:
            return
        nv = 3
        xv, Pvv = self.x_est[:nv], self.P_est[:nv, :nv]
        Fx, Fv = self.robot.Fx(xv, odo), self.robot.Fv(xv, odo)
        self.x_est = np.concatenate((self.robot.f(xv, odo), self.x_est[nv:]))
        P = self.P_est.copy()
        P[:nv, :nv] = Fx @ Pvv @ Fx.T + Fv @ self.V_est @ Fv.T
        P[:nv, nv:] = Fx @ self.P_est[:nv, nv:]
        P[nv:, :nv] = P[:nv, nv:].T
        self.P_est = P

    def _vehicle(self) -> Array:
        return self.x_est[:3] if self.est_vehicle else np.asarray(self.robot.x, dtype=float)

    def update(self, z: ArrayLike | None, lm_id: int | None) -> Array | None:
        """Correct the estimate with the observation ``z = (range, bearing)`` of landmark
        ``lm_id``; a SLAM landmark seen for the first time is added to the state. Returns
        the innovation (None when there was no update)."""
        if z is None or lm_id is None:
            return None
        z = np.asarray(z, dtype=float)
        xv = self._vehicle()
        nv = 3 if self.est_vehicle else 0
        if self.est_map:
            if lm_id not in self.landmarks:
                self._extend(xv, z, lm_id)
                return None
            j = nv + 2 * self.landmarks[lm_id][0]
            xf = self.x_est[j:j + 2]
            zp = self.sensor.h(xv, xf)
            Hx = np.zeros((2, len(self.x_est)))
            Hx[:, j:j + 2] = self.sensor.Hp(xv, xf)
            if self.est_vehicle:
                Hx[:, :3] = self.sensor.Hx(xv, xf)
            Hw = self.sensor.Hw(xv, xf)
            self.landmarks[lm_id][1] += 1
        else:
            zp = self.sensor.h(xv, lm_id)
            Hx = self.sensor.Hx(xv, lm_id)
            Hw = self.sensor.Hw(xv, lm_id)
        innov = np.array([z[0] - zp[0], wrap(z[1] - zp[1])])
        P = self.P_est
        S = Hx @ P @ Hx.T + Hw @ self.W_est @ Hw.T
        K = P @ Hx.T @ np.linalg.inv(S)
        x = self.x_est + K @ innov
        if self.est_vehicle:
            x[2] = wrap(x[2])
        if self.joseph:
            IKH = np.eye(len(x)) - K @ Hx
            P = IKH @ P @ IKH.T + K @ self.W_est @ K.T
        else:
            P = P - K @ S @ K.T
            P = 0.5 * (P + P.T)
        self.x_est, self.P_est = x, P
        return innov

    def _extend(self, xv: Array, z: Array, lm_id: int) -> None:
        """Add a landmark first seen at z to the state (the Toolbox's ``_extend_map``)."""
        xf = self.sensor.g(xv, z)
        n = len(self.x_est)
        Gz = self.sensor.Gz(xv, z)
        Yz = np.zeros((n + 2, n + 2))
        Yz[:n, :n] = np.eye(n)
        if self.est_vehicle:
            Yz[n:, :3] = self.sensor.Gx(xv, z)
        Yz[n:, n:] = Gz
        self.P_est = Yz @ block_diag(self.P_est, self.W_est) @ Yz.T
        self.x_est = np.concatenate((self.x_est, xf))
        self.landmarks[lm_id] = [len(self.landmarks), 1]

    def step(self) -> None:
        """Move the vehicle one sample (its control), then predict and update."""
        odo = self.robot.step()
        self.predict(odo)
        z, lm_id = (None, None) if self.sensor is None else self.sensor.reading()
        innov = self.update(z, lm_id)
        if self.keep_history:
            self.history.append(EKFLog(self.robot.t, self.x_est.copy(), np.asarray(odo), self.P_est.copy(),
                                       None if innov is None else innov.copy(), -1 if lm_id is None else lm_id))

    def run(self, T: float) -> None:
        """Restart and step for ``T`` s."""
        self.init()
        for _ in range(int(round(T / self.robot.dt))):
            self.step()

    # ------------------------------------------------------------------ results
    def get_xyt(self) -> Array:
        """The estimated poses (k, 3) over the history."""
        return np.array([h.x_est[:3] for h in self.history])

    def get_map(self) -> Array:
        """SLAM: the estimated landmark positions (N, 2), in the order of their ids seen."""
        nv = 3 if self.est_vehicle else 0
        out = np.full((len(self.landmarks), 2), np.nan)
        for i, (lm, (k, _)) in enumerate(sorted(self.landmarks.items())):
            out[i] = self.x_est[nv + 2 * k:nv + 2 * k + 2]
        return out

    def landmark_P(self, lm_id: int) -> Array:
        """SLAM: the covariance (2, 2) of landmark ``lm_id``'s estimate."""
        j = (3 if self.est_vehicle else 0) + 2 * self.landmarks[lm_id][0]
        return self.P_est[j:j + 2, j:j + 2]
