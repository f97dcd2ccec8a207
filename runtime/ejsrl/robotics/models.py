"""A library of arms, each a short declaration of its DH links (and one from its URDF file).

Every model has named poses ``qz`` (all zeros) and ``qr`` (a ready pose), in
``robot.poses`` and as attributes, and ``link_lengths()`` / ``reach`` for drawing.
Sources are stated per model; dynamics not published for an arm are marked approximate.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .link import Link, PrismaticDH, RevoluteDH, RevoluteMDH
from .robot import Robot
from .transforms import transl, trotx, trotz

__all__ = ["puma560", "stanford", "pa10", "ur5", "ur5_urdf", "UR5_URDF", "planar", "rrr", "scara",
           "panda", "kr5", "irb140", "lbr_iiwa", "ur10", "random_arm"]

#: the UR5 URDF file shipped with ejsrl (with its STL meshes; see NOTICE.md beside it)
UR5_URDF = Path(__file__).resolve().parent / "data" / "ur5" / "ur5.urdf"

pi = np.pi
deg = pi / 180.0
inch = 0.0254


def _rod(m: float, length: float, axis: int, radius: float = 0.03) -> np.ndarray:
    """Inertia (3, 3) of a solid cylinder of mass m about its centre, long axis ``axis``."""
    Il = 0.5 * m * radius**2
    It = m * (3 * radius**2 + length**2) / 12.0
    diag = [It, It, It]
    diag[axis] = Il
    return np.diag(diag)


def puma560() -> Robot:
    """Unimation Puma 560, standard DH, exactly as Robotics Toolbox for Python 1.x
    ``models.DH.Puma560`` (kinematics after Paul & Zhang, dynamics from Armstrong, Khatib
    and Burdick 1986 and Corke & Armstrong-Helouvry 1994, motor data at the motor side).

    The 0.67183 m (26.45 in) pedestal is in d1. Poses: ``qz`` zero, ``qr`` ready
    (vertical), ``qs`` stretched, ``qn`` nominal (a dexterous, non-singular pose).
    """
    L = [
        RevoluteDH(d=26.45 * inch, a=0.0, alpha=pi / 2, I=[0, 0.35, 0, 0, 0, 0], r=[0, 0, 0], m=0.0,
                   Jm=200e-6, G=-62.6111, B=1.48e-3, Tc=[0.395, -0.435], qlim=[-160 * deg, 160 * deg]),
        RevoluteDH(d=0.0, a=0.4318, alpha=0.0, I=[0.13, 0.524, 0.539, 0, 0, 0], r=[-0.3638, 0.006, 0.2275],
                   m=17.4, Jm=200e-6, G=107.815, B=0.817e-3, Tc=[0.126, -0.071], qlim=[-45 * deg, 225 * deg]),
        RevoluteDH(d=0.15005, a=0.0203, alpha=-pi / 2, I=[0.066, 0.086, 0.0125, 0, 0, 0],
                   r=[-0.0203, -0.0141, 0.070], m=4.8, Jm=200e-6, G=-53.7063, B=1.38e-3, Tc=[0.132, -0.105],
                   qlim=[-225 * deg, 45 * deg]),
        RevoluteDH(d=0.4318, a=0.0, alpha=pi / 2, I=[1.8e-3, 1.3e-3, 1.8e-3, 0, 0, 0], r=[0, 0.019, 0],
                   m=0.82, Jm=33e-6, G=76.0364, B=71.2e-6, Tc=[11.2e-3, -16.9e-3], qlim=[-110 * deg, 170 * deg]),
        RevoluteDH(d=0.0, a=0.0, alpha=-pi / 2, I=[0.3e-3, 0.4e-3, 0.3e-3, 0, 0, 0], r=[0, 0, 0], m=0.34,
                   Jm=33e-6, G=71.923, B=82.6e-6, Tc=[9.26e-3, -14.5e-3], qlim=[-100 * deg, 100 * deg]),
        RevoluteDH(d=0.0, a=0.0, alpha=0.0, I=[0.15e-3, 0.15e-3, 0.04e-3, 0, 0, 0], r=[0, 0, 0.032], m=0.09,
                   Jm=33e-6, G=76.686, B=36.7e-6, Tc=[3.96e-3, -10.5e-3], qlim=[-266 * deg, 266 * deg]),
    ]
    return Robot(
        L,
        name="Puma 560",
        manufacturer="Unimation",
        poses={
            "qz": np.zeros(6),
            "qr": [0, pi / 2, -pi / 2, 0, 0, 0],
            "qs": [0, 0, -pi / 2, 0, 0, 0],
            "qn": [0, pi / 4, -pi, 0, pi / 4, 0],
        },
    )


def stanford() -> Robot:
    """Stanford arm (RRPRRR), standard DH and inertial data as Robotics Toolbox for Python
    ``models.DH.Stanford`` (Paul 1981; the centres of mass are the Toolbox's values
    verbatim). The prismatic joint 3 travels 12 to 50 inch."""
    L = [
        RevoluteDH(d=0.412, a=0.0, alpha=-pi / 2, I=[0.276, 0.255, 0.071, 0, 0, 0], r=[0, 0.0175, -0.1105],
                   m=9.29, Jm=0.953, qlim=[-170 * deg, 170 * deg]),
        RevoluteDH(d=0.154, a=0.0, alpha=pi / 2, I=[0.108, 0.018, 0.100, 0, 0, 0], r=[0, -1.054, 0], m=5.01,
                   Jm=2.193, qlim=[-170 * deg, 170 * deg]),
        PrismaticDH(theta=-pi / 2, a=0.0203, alpha=0.0, I=[2.51, 2.51, 0.006, 0, 0, 0], r=[0, 0, -6.447], m=4.25,
                    Jm=0.782, qlim=[12 * inch, 50 * inch]),
        RevoluteDH(d=0.0, a=0.0, alpha=-pi / 2, I=[0.002, 0.001, 0.001, 0, 0, 0], r=[0, 0.092, -0.054], m=1.08,
                   Jm=0.106, qlim=[-170 * deg, 170 * deg]),
        RevoluteDH(d=0.0, a=0.0, alpha=pi / 2, I=[0.003, 0.0004, 0, 0, 0, 0], r=[0, 0.566, 0.003], m=0.63,
                   Jm=0.097, qlim=[-90 * deg, 90 * deg]),
        RevoluteDH(d=0.0, a=0.0, alpha=0.0, I=[0.013, 0.013, 0.0003, 0, 0, 0], r=[0, 0, 1.554], m=0.51,
                   Jm=0.020, qlim=[-170 * deg, 170 * deg]),
    ]
    return Robot(L, name="Stanford arm", manufacturer="Victor Scheinman",
                 poses={"qz": [0, 0, 0.5, 0, 0, 0], "qr": [0, pi / 4, 0.8, 0, pi / 4, 0]})


def pa10() -> Robot:
    """Mitsubishi PA-10 (7R, redundant), standard DH: shoulder height 0.317 m, upper arm
    0.45 m, forearm 0.48 m, wrist to flange 0.07 m; joint limits from the PA-10 manual.
    Masses are approximate (total about 25 kg); inertias are those of uniform cylinders."""
    d = [0.317, 0.0, 0.45, 0.0, 0.48, 0.0, 0.07]
    alpha = [-pi / 2, pi / 2, -pi / 2, pi / 2, -pi / 2, pi / 2, 0.0]
    lim = np.array([177, 94, 174, 137, 255, 165, 255]) * deg
    mass = [9.78, 8.41, 3.51, 4.31, 3.45, 1.46, 0.24]
    com = [[0, 0.1, 0], [0, 0, 0.12], [0, 0.1, 0], [0, 0, 0.12], [0, 0.1, 0], [0, 0, 0.02], [0, 0, -0.02]]
    L = [
        RevoluteDH(d=d[j], a=0.0, alpha=alpha[j], m=mass[j], r=com[j],
                   I=_rod(mass[j], 0.25 if j < 5 else 0.08, axis=1 if j % 2 == 0 else 2, radius=0.07),
                   qlim=[-lim[j], lim[j]])
        for j in range(7)
    ]
    return Robot(L, name="PA-10", manufacturer="Mitsubishi Heavy Industries",
                 poses={"qz": np.zeros(7), "qr": [0, pi / 6, 0, pi / 3, 0, pi / 3, 0]})


def ur5() -> Robot:
    """Universal Robots UR5, standard DH from Universal Robots (as Robotics Toolbox for
    Python ``models.DH.UR5``), with its masses and centres of mass. UR publish no link
    inertias; here each link is a uniform cylinder of radius 0.06 m (as in ur_description)."""
    a = [0.0, -0.42500, -0.39225, 0.0, 0.0, 0.0]
    d = [0.089459, 0.0, 0.0, 0.10915, 0.09465, 0.0823]
    alpha = [pi / 2, 0.0, 0.0, pi / 2, -pi / 2, 0.0]
    mass = [3.7000, 8.3930, 2.33, 1.2190, 1.2190, 0.1897]
    com = [[0, -0.02561, 0.00193], [0.2125, 0, 0.11336], [0.15, 0, 0.0265],
           [0, -0.0018, 0.01634], [0, -0.0018, 0.01634], [0, 0, -0.001159]]
    lengths = [0.15, 0.425, 0.39225, 0.12, 0.12, 0.0823]
    axes = [2, 0, 0, 2, 2, 2]
    L = [
        RevoluteDH(d=d[j], a=a[j], alpha=alpha[j], m=mass[j], r=com[j],
                   I=_rod(mass[j], lengths[j], axes[j], radius=0.06), qlim=[-2 * pi, 2 * pi])
        for j in range(6)
    ]
    return Robot(L, name="UR5", manufacturer="Universal Robots",
                 poses={"qz": np.zeros(6), "qr": np.array([180, 0, 0, 0, 90, 0]) * deg})


def ur5_urdf() -> Robot:
    """Universal Robots UR5 from its URDF description (ros-industrial ``ur_description``, BSD;
    see ``data/ur5/NOTICE.md``): link meshes, limits and inertias as the file gives them,
    ``fkine`` to the ``tool0`` flange frame. Needs ``pip install yourdfpy``.

    The ROS ``base_link`` is the arm's base turned half a turn about z from the DH model
    :func:`ur5`, and the joint zero positions follow the URDF."""
    from .urdf import load_urdf

    robot = load_urdf(UR5_URDF, tip="tool0", name="UR5")
    robot.manufacturer = "Universal Robots"
    robot.addconfiguration("qz", np.zeros(6))
    robot.addconfiguration("qr", np.array([0.0, -90.0, 90.0, -90.0, -90.0, 0.0]) * deg)
    return robot


def planar(n: int = 2, a: float = 1.0, m: float = 1.0, *, vertical: bool = False) -> Robot:
    """Planar arm of ``n`` revolute joints, links of length ``a`` (m) and mass ``m`` (kg),
    each a uniform thin rod. The arm moves in the base x-y plane; with ``vertical=True``
    the base is rotated so it moves in the world x-z plane, under gravity."""
    L = [
        RevoluteDH(a=a, m=m, r=[-a / 2, 0, 0], I=[0.0, m * a * a / 12, m * a * a / 12])
        for _ in range(n)
    ]
    qr = np.zeros(n)
    qr[0] = pi / 4
    if n > 1:
        qr[1:] = -pi / (2 * (n - 1))
    return Robot(L, name=f"planar{n}", base=trotx(pi / 2) if vertical else None,
                 poses={"qz": np.zeros(n), "qr": qr})


def rrr() -> Robot:
    """Anthropomorphic 3R arm (waist, shoulder, elbow): shoulder height 0.4 m, upper arm
    0.4 m, forearm 0.3 m, links as uniform rods."""
    L = [
        RevoluteDH(d=0.4, a=0.0, alpha=pi / 2, m=3.0, r=[0, -0.2, 0], I=_rod(3.0, 0.4, 1, 0.05),
                   qlim=[-pi, pi]),
        RevoluteDH(a=0.4, m=2.0, r=[-0.2, 0, 0], I=_rod(2.0, 0.4, 0), qlim=[-pi, pi]),
        RevoluteDH(a=0.3, m=1.0, r=[-0.15, 0, 0], I=_rod(1.0, 0.3, 0), qlim=[-pi, pi]),
    ]
    return Robot(L, name="RRR", poses={"qz": np.zeros(3), "qr": [0, pi / 4, -pi / 2]})


def scara() -> Robot:
    """SCARA (RRPR), standard DH: column 0.4 m, arms 0.325 m and 0.225 m, a 0.2 m quill
    (prismatic joint 3, pointing down) and a wrist roll. Links as uniform rods."""
    L = [
        RevoluteDH(d=0.4, a=0.325, alpha=0.0, m=4.0, r=[-0.16, 0, 0], I=_rod(4.0, 0.325, 0), qlim=[-2.6, 2.6]),
        RevoluteDH(d=0.0, a=0.225, alpha=pi, m=2.0, r=[-0.11, 0, 0], I=_rod(2.0, 0.225, 0), qlim=[-2.5, 2.5]),
        PrismaticDH(theta=0.0, a=0.0, alpha=0.0, m=1.0, r=[0, 0, -0.1], I=_rod(1.0, 0.2, 2, 0.01),
                    qlim=[0.0, 0.2]),
        RevoluteDH(d=0.0, a=0.0, alpha=0.0, m=0.3, r=[0, 0, 0.02], I=_rod(0.3, 0.04, 2, 0.03),
                   qlim=[-2 * pi, 2 * pi]),
    ]
    return Robot(L, name="SCARA", poses={"qz": np.zeros(4), "qr": [pi / 6, -pi / 3, 0.1, 0]})


def _arm(name: str, maker: str, a: list[float], d: list[float], alpha: list[float], lim_deg: np.ndarray,
         mass: list[float], *, mdh: bool = False, tool: np.ndarray | None = None,
         qr: list[float] | None = None) -> Robot:
    """An arm from its DH table, joint limits (degrees, symmetric when one row), and
    approximate masses: each link a uniform cylinder of radius 0.06 m along its longer
    DH offset, centre of mass halfway along it."""
    n = len(a)
    lim = np.asarray(lim_deg, dtype=float) * deg
    lim = np.vstack((-lim, lim)) if lim.ndim == 1 else lim
    links = []
    for j in range(n):
        along_x = abs(a[j]) >= abs(d[j])
        length = max(abs(a[j]), abs(d[j]), 0.05)
        r = [-a[j] / 2, 0.0, 0.0] if along_x else [0.0, 0.0, -d[j] / 2] if not mdh else [0.0, 0.0, d[j] / 2]
        cls = RevoluteMDH if mdh else RevoluteDH
        links.append(cls(d=d[j], a=a[j], alpha=alpha[j], m=mass[j], r=r,
                         I=_rod(mass[j], length, 0 if along_x else 2, radius=0.06), qlim=lim[:, j]))
    return Robot(links, name=name, manufacturer=maker, tool=tool,
                 poses={"qz": np.zeros(n), "qr": np.zeros(n) if qr is None else np.asarray(qr, dtype=float)})


def panda() -> Robot:
    """Franka Emika Panda (7R), modified DH from Franka's documentation (as the Toolbox's
    ``models.DH.Panda``), with the hand as the tool (0.103 m along the flange z, turned
    -45 deg); masses from Franka's published dynamics, link inertias approximate."""
    return _arm("Panda", "Franka Emika", a=[0, 0, 0, 0.0825, -0.0825, 0, 0.088],
                d=[0.333, 0, 0.316, 0, 0.384, 0, 0.107], alpha=[0, -pi / 2, pi / 2, pi / 2, -pi / 2, pi / 2, pi / 2],
                lim_deg=np.array([[-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973],
                                  [2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973]]) / deg,
                mass=[4.970684, 0.646926, 3.228604, 3.587895, 1.225946, 1.666555, 0.735522], mdh=True,
                tool=transl(0, 0, 0.103) @ trotz(-pi / 4), qr=[0, -0.3, 0, -2.2, 0, 2.0, pi / 4])


def kr5() -> Robot:
    """KUKA KR5 (6R, shoulder offset 0.18 m), standard DH from KUKA's data sheet (as the
    Toolbox's ``models.DH.KR5``); masses approximate (total about 28 kg)."""
    return _arm("KR5", "KUKA", a=[0.18, 0.6, 0.12, 0, 0, 0], d=[0.4, 0, 0, -0.62, 0, -0.115],
                alpha=[-pi / 2, 0, pi / 2, -pi / 2, pi / 2, pi],
                lim_deg=np.array([[-155, -180, -15, -350, -130, -350], [155, 65, 158, 350, 130, 350]]),
                mass=[10.0, 8.0, 5.0, 2.5, 1.5, 0.5], qr=[0, -pi / 2, pi / 2, 0, pi / 2, 0])


def irb140() -> Robot:
    """ABB IRB 140 (6R, shoulder offset 0.07 m), standard DH from ABB's product manual (as
    the Toolbox's ``models.DH.IRB140``); masses of the first three links from the Toolbox,
    of the wrist approximate."""
    return _arm("IRB140", "ABB", a=[0.07, 0.36, 0, 0, 0, 0], d=[0.352, 0, 0, 0.38, 0, 0.065],
                alpha=[-pi / 2, 0, -pi / 2, pi / 2, -pi / 2, 0],
                lim_deg=np.array([[-180, -100, -220, -200, -120, -400], [180, 100, 60, 200, 120, 400]]),
                mass=[34.65536, 15.99459, 20.86205, 3.0, 1.5, 0.3], qr=[0, 0, 0, 0, -pi / 2, 0])


def lbr_iiwa() -> Robot:
    """KUKA LBR iiwa 14 R820 (7R), standard DH from KUKA's specification (shoulder 0.36 m,
    upper arm 0.42 m, forearm 0.4 m, flange 0.126 m) and its joint limits; masses approximate
    (total about 30 kg)."""
    return _arm("LBR iiwa 14", "KUKA", a=[0.0] * 7, d=[0.36, 0, 0.42, 0, 0.4, 0, 0.126],
                alpha=[-pi / 2, pi / 2, pi / 2, -pi / 2, -pi / 2, pi / 2, 0],
                lim_deg=np.array([170, 120, 170, 120, 170, 120, 175]),
                mass=[6.4, 7.0, 3.4, 3.5, 3.5, 2.1, 0.8], qr=[0, pi / 6, 0, -pi / 3, 0, pi / 3, 0])


def ur10() -> Robot:
    """Universal Robots UR10 (CB3), standard DH and masses from Universal Robots (as the
    Toolbox's ``models.DH.UR10``); link inertias approximate (cylinders)."""
    return _arm("UR10", "Universal Robots", a=[0, -0.612, -0.5723, 0, 0, 0],
                d=[0.1273, 0, 0, 0.163941, 0.1157, 0.0922], alpha=[pi / 2, 0, 0, pi / 2, -pi / 2, 0],
                lim_deg=np.full(6, 360.0), mass=[7.1, 12.7, 4.27, 2.0, 2.0, 0.365],
                qr=[pi, 0, 0, 0, pi / 2, 0])


def random_arm(n: int = 6, seed: int = 0) -> Robot:
    """A random n-joint revolute arm (a test of the general IK): standard DH with ``a``, ``d``
    uniform in [0, 0.4] m, twists uniform in [-pi, pi], limits +-170 deg; point-like unit masses."""
    rng = np.random.default_rng(seed)
    a, d = rng.uniform(0, 0.4, n), rng.uniform(0, 0.4, n)
    alpha = rng.uniform(-pi, pi, n)
    return _arm(f"random {n}R (seed {seed})", "", a=a.tolist(), d=d.tolist(), alpha=alpha.tolist(),
                lim_deg=np.full(n, 170.0), mass=[1.0] * n)


_ = Link  # re-exported for model authors: ``models.Link``
