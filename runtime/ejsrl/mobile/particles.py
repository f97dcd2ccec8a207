"""Monte Carlo localisation: a particle filter over the vehicle's pose, as the Toolbox's
``ParticleFilter`` (Corke, *Robotics, Vision and Control*, 6.7).

Each step moves every particle by the odometry plus noise of covariance ``R`` (3, 3),
weights it by the likelihood of the sensor's reading, ``exp(-e^T L^-1 e / 2) + w0`` for
the innovation e and covariance ``L`` (2, 2), and draws the next generation in
proportion to the weights (inverse CDF of ``uniform`` draws). Random numbers come from
``np.random.default_rng(seed)``. The estimate is the particles' mean position and
circular mean heading; ``std`` their spread.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ._util import Array, angdiff

__all__ = ["ParticleFilter", "PFLog"]


class PFLog(NamedTuple):
    t: float
    odo: Array
    x_est: Array
    std: Array


class ParticleFilter:
    """Args:
        robot: the vehicle (stepped by :meth:`step`).
        sensor: a :class:`~ejsrl.mobile.RangeBearingSensor` on it, with its map.
        R: (3, 3) covariance of the noise added to each particle's motion.
        L: (2, 2) covariance of the observation likelihood.
        nparticles: number of particles; seed: of the filter's random numbers.
        x0: initial pose (3,) of every particle, or (n, 3) particles; None: uniform over
            ``workspace`` (default: the sensor map's) with uniform headings.
        w0: weight floor, so a particle far off is not discarded at once.
    """

    def __init__(self, robot: Any, sensor: Any, R: ArrayLike, L: ArrayLike, *, nparticles: int = 500,
                 seed: int | None = 0, x0: ArrayLike | None = None, workspace: ArrayLike | None = None,
                 w0: float = 0.05) -> None:
        if nparticles < 1:
            raise ValueError(f"a particle filter needs particles, got nparticles = {nparticles}")
        self.robot, self.sensor = robot, sensor
        self.R = np.asarray(R, dtype=float).reshape(3, 3)
        self.L = np.asarray(L, dtype=float).reshape(2, 2)
        self.nparticles = int(nparticles)
        self.seed = seed
        self.x0 = None if x0 is None else np.asarray(x0, dtype=float)
        ws = sensor.map.workspace if workspace is None else np.asarray(workspace, dtype=float)
        self.workspace = np.asarray(ws, dtype=float).reshape(4)
        self.w0 = float(w0)
        self.init()

    def init(self) -> None:
        """Restart: the vehicle and sensor re-initialised, the particles drawn again."""
        self.robot.init()
        self.sensor.init()
        self.random = np.random.default_rng(self.seed)
        self.history: list[PFLog] = []
        n = self.nparticles
        if self.x0 is None:
            ws = self.workspace
            self.x = np.column_stack((self.random.uniform(ws[0], ws[1], n), self.random.uniform(ws[2], ws[3], n),
                                      self.random.uniform(-np.pi, np.pi, n)))
        elif self.x0.shape == (3,):
            self.x = np.tile(self.x0, (n, 1))
        elif self.x0.shape == (n, 3):
            self.x = self.x0.copy()
        else:
            raise ValueError(f"x0 must have shape (3,) or ({n}, 3), got {self.x0.shape}")
        self.weight = np.ones(n)

    def predict(self, odo: ArrayLike) -> None:
        """Move every particle by the odometry, plus noise of covariance R."""
        self.x = self.robot.f(self.x, odo) + self.random.multivariate_normal((0.0, 0.0, 0.0), self.R,
                                                                           size=self.nparticles)
        self.x[:, 2] = angdiff(self.x[:, 2])

    def observe(self, z: ArrayLike, lm_id: int) -> None:
        """Weight each particle by how well it explains the reading z of landmark lm_id."""
        z = np.asarray(z, dtype=float)
        zp = self.sensor.h(self.x, lm_id)
        e = np.column_stack((z[0] - zp[:, 0], angdiff(z[1], zp[:, 1])))
        self.weight = np.exp(-0.5 * np.einsum("ni,ij,nj->n", e, np.linalg.inv(self.L), e)) + self.w0

    def resample(self) -> None:
        """The next generation: n draws in proportion to the weights (inverse CDF)."""
        cdf = np.cumsum(self.weight)
        cdf /= cdf[-1]
        u = self.random.uniform(0.0, 1.0, self.nparticles)
        self.x = self.x[np.minimum(np.searchsorted(cdf, u, side="right"), self.nparticles - 1)]

    @property
    def x_est(self) -> Array:
        """Mean position and circular mean heading of the particles (3,)."""
        th = np.arctan2(np.sin(self.x[:, 2]).sum(), np.cos(self.x[:, 2]).sum())
        return np.array([self.x[:, 0].mean(), self.x[:, 1].mean(), th])

    @property
    def std(self) -> Array:
        """Standard deviations of x, y (m) and the circular one of the heading (rad)."""
        c, s = np.cos(self.x[:, 2]).mean(), np.sin(self.x[:, 2]).mean()
        R = min(1.0, float(np.hypot(c, s)))
        return np.array([self.x[:, 0].std(), self.x[:, 1].std(), np.sqrt(-2.0 * np.log(max(R, 1e-300)))])

    def step(self) -> None:
        """Move the vehicle one sample, predict, and (with a reading) weight and resample."""
        odo = self.robot.step()
        self.predict(odo)
        z, lm_id = self.sensor.reading()
        if z is not None:
            self.observe(z, lm_id)
            self.resample()
        self.history.append(PFLog(self.robot.t, np.asarray(odo), self.x_est, self.std))

    def run(self, T: float) -> None:
        self.init()
        for _ in range(int(round(T / self.robot.dt))):
            self.step()

    def get_xyt(self) -> Array:
        return np.array([h.x_est for h in self.history])

    @property
    def points(self) -> Array:
        """The particles' positions (n, 2), to draw as a point set."""
        return self.x[:, :2].copy()
