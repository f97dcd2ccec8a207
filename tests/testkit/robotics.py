"""Shared helpers for the robotics tests (imported as a plain module)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ejsrl.robotics import Robot, models
from ejsrl.robotics.link import PrismaticMDH, RevoluteMDH
from ejsrl.robotics.transforms import rpy2tr, transl

FIXTURES = Path(__file__).resolve().parents[1] / "robotics" / "fixtures"


def mdh_arm() -> Robot:
    """A 5-joint modified-DH arm with a prismatic joint, non-trivial inertias (test only)."""
    I1 = np.array([[0.05, 0.01, 0.0], [0.01, 0.04, 0.002], [0.0, 0.002, 0.03]])
    return Robot(
        [
            RevoluteMDH(d=0.3, a=0.0, alpha=0.0, m=2.0, r=[0.0, 0.02, -0.1], I=I1, Jm=1e-4, G=50, B=1e-4, Tc=0.01),
            RevoluteMDH(d=0.05, a=0.1, alpha=np.pi / 2, m=1.5, r=[0.2, 0.0, 0.03], I=[0.01, 0.03, 0.03, 0.001, 0, 0]),
            PrismaticMDH(theta=0.3, a=0.4, alpha=-np.pi / 2, m=1.0, r=[0.0, 0.01, -0.1], I=[0.02, 0.02, 0.002],
                         qlim=[0.1, 0.5], offset=0.05),
            RevoluteMDH(d=0.1, a=0.02, alpha=np.pi / 3, m=0.5, r=[0.01, 0.0, 0.05], I=[0.003, 0.002, 0.001]),
            RevoluteMDH(d=0.0, a=0.0, alpha=-np.pi / 2, m=0.3, r=[0.0, 0.0, 0.04], I=[0.001, 0.001, 0.0005]),
        ],
        name="mdh5",
    )


ALL_MODELS = {
    "puma560": models.puma560,
    "stanford": models.stanford,
    "pa10": models.pa10,
    "ur5": models.ur5,
    "planar3": lambda: models.planar(3, vertical=True),
    "rrr": models.rrr,
    "scara": models.scara,
    "mdh5": mdh_arm,
}


def with_base_tool(robot: Robot) -> Robot:
    """The same arm on a tilted, shifted base and with an offset tool."""
    robot.base = transl(0.3, -0.2, 0.5) @ rpy2tr(0.2, -0.3, 0.7)
    robot.tool = transl(0.01, 0.02, 0.1) @ rpy2tr(0.1, 0.4, -0.2)
    return robot


def random_q(robot: Robot, rng: np.random.Generator, m: int | None = None) -> np.ndarray:
    lim = robot.qlim
    lo = np.where(np.isfinite(lim[0]), lim[0], -np.pi)
    hi = np.where(np.isfinite(lim[1]), lim[1], np.pi)
    return rng.uniform(lo, hi, size=None if m is None else (m, robot.n))
