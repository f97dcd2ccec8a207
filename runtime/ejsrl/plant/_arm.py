"""The reference plant's arm: a 5-axis educational arm (the paper's RobUALab arm) with motor dynamics.

Each joint is an independent motor-and-gear drive, the model an educational arm's servo boards
run: a current-limited PD servo tracks a reference that moves toward the set point at the joint's
speed limit; the joint obeys ``J qdd = u - b qd - Fc tanh(qd / 0.01)`` (viscous and Coulomb
friction). Angles in rad, speeds in rad/s, torques in N m, lengths in m.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["ArmParams", "Arm"]

N_JOINTS = 5


@dataclass(frozen=True)
class ArmParams:
    """Joint limits and drive constants of the arm; every array is shape (5,)."""

    q_min: np.ndarray = field(default_factory=lambda: np.radians([-170.0, -30.0, -120.0, -110.0, -180.0]))
    q_max: np.ndarray = field(default_factory=lambda: np.radians([170.0, 130.0, 120.0, 110.0, 180.0]))
    qd_max: np.ndarray = field(default_factory=lambda: np.radians([90.0, 90.0, 120.0, 150.0, 180.0]))
    inertia: np.ndarray = field(default_factory=lambda: np.array([0.08, 0.12, 0.06, 0.02, 0.01]))
    viscous: np.ndarray = field(default_factory=lambda: np.array([0.05, 0.08, 0.04, 0.01, 0.005]))
    coulomb: np.ndarray = field(default_factory=lambda: np.array([0.20, 0.30, 0.15, 0.05, 0.02]))
    u_max: np.ndarray = field(default_factory=lambda: np.array([12.0, 18.0, 9.0, 3.0, 1.5]))
    kp: np.ndarray = field(default_factory=lambda: np.array([160.0, 240.0, 120.0, 40.0, 20.0]))
    kd: np.ndarray = field(default_factory=lambda: np.array([7.0, 10.0, 5.0, 1.6, 0.8]))
    #: link lengths of the arm, m: base height, upper arm, forearm, wrist to tool tip
    lengths: tuple[float, float, float, float] = (0.35, 0.22, 0.22, 0.15)
    #: the lowest height the tool tip may reach (the table top), m
    z_min: float = 0.0


class Arm:
    """The arm's state and one integration step; not thread-safe (the plant holds its lock)."""

    def __init__(self, params: ArmParams | None = None, *, noise: float = 2e-4, seed: int | None = None) -> None:
        self.p = params or ArmParams()
        self.q = np.zeros(N_JOINTS)
        self.qd = np.zeros(N_JOINTS)
        self.q_ref = np.zeros(N_JOINTS)
        self.q_set = np.zeros(N_JOINTS)
        self.gripper = 0.0
        self.braking = False
        self.noise = float(noise)
        self._rng = np.random.default_rng(seed)

    def tool_position(self, q: np.ndarray) -> np.ndarray:
        """Tool tip position (3,) in the base frame, m, for joint angles ``q`` (5,), rad."""
        h, a2, a3, a4 = self.p.lengths
        r = a2 * np.cos(q[1]) + a3 * np.cos(q[1] + q[2]) + a4 * np.cos(q[1] + q[2] + q[3])
        z = h + a2 * np.sin(q[1]) + a3 * np.sin(q[1] + q[2]) + a4 * np.sin(q[1] + q[2] + q[3])
        return np.array([r * np.cos(q[0]), r * np.sin(q[0]), z])

    def check(self, q: np.ndarray) -> str | None:
        """Why the set point ``q`` (5,) rad is refused, or None when it is inside every limit."""
        if q.shape != (N_JOINTS,) or not np.all(np.isfinite(q)):
            return f"a set point is {N_JOINTS} finite joint angles"
        for i in range(N_JOINTS):
            if not self.p.q_min[i] - 1e-9 <= q[i] <= self.p.q_max[i] + 1e-9:
                return (f"joint {i + 1} set point {np.degrees(q[i]):.1f} deg is outside its limits "
                        f"[{np.degrees(self.p.q_min[i]):.0f}, {np.degrees(self.p.q_max[i]):.0f}] deg")
        z = self.tool_position(q)[2]
        if z < self.p.z_min:
            return f"the tool would be {z * 1000:.0f} mm below the table (workspace limit)"
        return None

    def step(self, dt: float) -> None:
        """Advance the arm by ``dt`` seconds (semi-implicit Euler, called with dt <= 1 ms)."""
        p = self.p
        if self.braking:
            # e-stop / watchdog: the drives brake at full torque (helped by friction) to
            # standstill, never past it, then hold where they stopped
            dec = (p.u_max + p.coulomb + p.viscous * np.abs(self.qd)) / p.inertia * dt
            self.qd = np.sign(self.qd) * np.maximum(np.abs(self.qd) - dec, 0.0)
            self.q_ref = self.q.copy()
            self.q_set = self.q.copy()
        else:
            step = p.qd_max * dt
            self.q_ref = self.q_ref + np.clip(self.q_set - self.q_ref, -step, step)
            u = np.clip(p.kp * (self.q_ref - self.q) - p.kd * self.qd, -p.u_max, p.u_max)
            qdd = (u - p.viscous * self.qd - p.coulomb * np.tanh(self.qd / 0.01)) / p.inertia
            self.qd = self.qd + qdd * dt
        self.q = self.q + self.qd * dt

    def measure(self) -> tuple[np.ndarray, np.ndarray]:
        """Encoder readings: joint angles (5,) rad with sensor noise, and joint speeds (5,) rad/s."""
        return self.q + self._rng.normal(0.0, self.noise, N_JOINTS), self.qd.copy()

    def moving(self) -> bool:
        return bool(np.max(np.abs(self.qd)) > 1e-3)
