"""One link of a serial arm: its Denavit-Hartenberg parameters and its dynamics.

Conventions follow Corke's Robotics Toolbox (``RevoluteDH`` / ``PrismaticDH``):

- Standard DH (``mdh=False``): ``A_i = Rz(theta) Tz(d) Tx(a) Rx(alpha)``; joint i moves
  about/along ``z_{i-1}``, and the link's frame i sits at its far end.
- Modified DH (``mdh=True``, Craig): ``A_i = Rx(alpha) Tx(a) Rz(theta) Tz(d)``; joint i
  moves about/along ``z_i``, and frame i sits at the joint.
- Revolute joint: ``theta = q + offset``, ``d`` fixed. Prismatic: ``d = q + offset``,
  ``theta`` fixed.
- Dynamics are expressed in the link's own frame i: mass ``m`` (kg), centre of mass ``r``
  (m), inertia ``I`` (kg m^2, about the centre of mass). Motor quantities are referred to
  the motor side: rotor inertia ``Jm``, gear ratio ``G`` (joint torque = G * motor torque),
  viscous friction ``B`` and Coulomb friction ``Tc = (Tc+, Tc-)``; they reach the joint
  scaled by ``G**2`` (``Jm``, ``B``) and ``|G|`` (``Tc``), as in the Toolbox.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["Link", "ETSLink", "RevoluteDH", "PrismaticDH", "RevoluteMDH", "PrismaticMDH"]

Array = NDArray[np.float64]

_DYNAMIC = ("m", "r", "I", "Jm", "G", "B", "Tc")


def _inertia_matrix(I: ArrayLike | None) -> Array:
    """(3, 3) inertia from a 3-vector (diagonal), a 6-vector ``[Ixx Iyy Izz Ixy Iyz Ixz]``
    (the Toolbox order) or a (3, 3) matrix."""
    if I is None:
        return np.zeros((3, 3))
    a = np.asarray(I, dtype=float)
    if a.shape == (3, 3):
        if not np.allclose(a, a.T):
            raise ValueError("inertia matrix I must be symmetric")
        return a.copy()
    a = a.reshape(-1)
    if a.size == 3:
        return np.diag(a)
    if a.size == 6:
        xx, yy, zz, xy, yz, xz = a
        return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    raise ValueError(f"inertia I must have 3, 6 or 3x3 elements, got shape {np.shape(I)}")


class Link:
    """One joint and the rigid body it moves.

    Args:
        a: link length (m).
        alpha: link twist (rad).
        d: link offset (m); for a prismatic joint the value used at ``q = 0`` is ``offset``.
        theta: joint angle (rad) of a prismatic joint (ignored for revolute ones).
        sigma: ``0`` or ``"R"`` for revolute, ``1`` or ``"P"`` for prismatic.
        offset: added to ``q`` before use (rad or m).
        qlim: ``(qmin, qmax)`` joint limits, or ``None`` for unlimited.
        mdh: ``True`` for modified (Craig) DH parameters.
        m, r, I: mass (kg), centre of mass in frame i (m), inertia about the centre of mass
            in frame i (3, 6 ``[Ixx Iyy Izz Ixy Iyz Ixz]`` or (3, 3)).
        Jm, G, B, Tc: motor inertia, gear ratio, motor viscous friction, motor Coulomb
            friction ``(Tc+, Tc-)`` (a scalar ``c`` means ``(c, -c)``).
        name: optional label.
    """

    def __init__(
        self,
        a: float = 0.0,
        alpha: float = 0.0,
        d: float = 0.0,
        theta: float = 0.0,
        *,
        sigma: int | str = 0,
        offset: float = 0.0,
        qlim: ArrayLike | None = None,
        mdh: bool = False,
        m: float = 0.0,
        r: ArrayLike | None = None,
        I: ArrayLike | None = None,  # noqa: E741
        Jm: float = 0.0,
        G: float = 1.0,
        B: float = 0.0,
        Tc: float | ArrayLike = 0.0,
        name: str = "",
    ) -> None:
        object.__setattr__(self, "version", 0)
        if isinstance(sigma, str):
            if sigma.upper() not in ("R", "P"):
                raise ValueError(f"sigma must be 'R' or 'P', got {sigma!r}")
            sigma = 0 if sigma.upper() == "R" else 1
        self.a = float(a)
        self.alpha = float(alpha)
        self.d = float(d)
        self.theta = float(theta)
        self.sigma = int(sigma)
        self.offset = float(offset)
        self.qlim = None if qlim is None else np.asarray(qlim, dtype=float).reshape(2)
        self.mdh = bool(mdh)
        self.m = float(m)
        self.r = np.zeros(3) if r is None else np.asarray(r, dtype=float).reshape(3)
        self.I = _inertia_matrix(I)
        self.Jm = float(Jm)
        self.G = float(G)
        self.B = float(B)
        tc = np.asarray(Tc, dtype=float).reshape(-1)
        self.Tc = np.array([tc[0], -tc[0]]) if tc.size == 1 else tc.reshape(2).copy()
        self.name = name

    def __setattr__(self, key: str, value: Any) -> None:
        # A version counter lets a Robot notice edits and refresh its cached arrays.
        if key == "I":
            value = _inertia_matrix(value)
        object.__setattr__(self, key, value)
        object.__setattr__(self, "version", self.version + 1)

    @property
    def isrevolute(self) -> bool:
        """True for a revolute joint."""
        return self.sigma == 0

    @property
    def isprismatic(self) -> bool:
        """True for a prismatic joint."""
        return self.sigma == 1

    def A(self, q: float) -> Array:
        """Link transform ``T_{i-1}_i`` (4, 4) for joint value ``q``."""
        from ._kinematics import dh_transforms

        return dh_transforms(
            np.array([q], dtype=float),
            np.array([self.a]),
            np.array([self.alpha]),
            np.array([self.d]),
            np.array([self.theta]),
            np.array([self.offset]),
            np.array([self.sigma == 1]),
            self.mdh,
        )[0]

    def friction(self, qd: float | ArrayLike, coulomb: bool = True) -> Array | float:
        """Friction torque (or force) acting on the joint at joint velocity ``qd``.

        Opposes the motion (negative for positive ``qd``), as in the Toolbox:
        ``-|G| (B |G| qd + Tc±)``; no stiction (zero at ``qd == 0``).
        """
        qd = np.asarray(qd, dtype=float)
        tau = self.B * abs(self.G) * qd
        if coulomb:
            tau = tau + np.where(qd > 0, self.Tc[0], np.where(qd < 0, self.Tc[1], 0.0))
        out = -abs(self.G) * tau
        return float(out) if out.ndim == 0 else out

    def copy(self) -> "Link":
        """An independent copy."""
        return Link(
            self.a, self.alpha, self.d, self.theta, sigma=self.sigma, offset=self.offset,
            qlim=self.qlim, mdh=self.mdh, m=self.m, r=self.r.copy(), I=self.I.copy(),
            Jm=self.Jm, G=self.G, B=self.B, Tc=self.Tc.copy(), name=self.name,
        )

    def __repr__(self) -> str:
        kind = "Prismatic" if self.isprismatic else "Revolute"
        conv = "MDH" if self.mdh else "DH"
        var = f"theta={self.theta:.4g}" if self.isprismatic else f"d={self.d:.4g}"
        return f"{kind}{conv}({var}, a={self.a:.4g}, alpha={self.alpha:.4g}, offset={self.offset:.4g}, m={self.m:.4g})"


def RevoluteDH(d: float = 0.0, a: float = 0.0, alpha: float = 0.0, **kw: Any) -> Link:
    """Revolute joint, standard DH (the Toolbox's argument order ``d, a, alpha``)."""
    return Link(a, alpha, d, 0.0, sigma=0, **kw)


def PrismaticDH(theta: float = 0.0, a: float = 0.0, alpha: float = 0.0, **kw: Any) -> Link:
    """Prismatic joint, standard DH (``d = q + offset``)."""
    return Link(a, alpha, 0.0, theta, sigma=1, **kw)


def RevoluteMDH(d: float = 0.0, a: float = 0.0, alpha: float = 0.0, **kw: Any) -> Link:
    """Revolute joint, modified DH (``a``, ``alpha`` are those of the previous link)."""
    return Link(a, alpha, d, 0.0, sigma=0, mdh=True, **kw)


def PrismaticMDH(theta: float = 0.0, a: float = 0.0, alpha: float = 0.0, **kw: Any) -> Link:
    """Prismatic joint, modified DH."""
    return Link(a, alpha, 0.0, theta, sigma=1, mdh=True, **kw)


class ETSLink(Link):
    """A link given by elementary transforms: a constant transform, then the joint motion.

    ``A_i(q) = origin @ Rz(theta) @ Tz(d)`` with ``theta = q + offset`` (revolute) or
    ``d = q + offset`` (prismatic): the joint turns about, or slides along, the z axis of
    its own frame i, which sits at the joint (as in modified DH, of which this is the
    generalisation: MDH is ``origin = Rx(alpha) Tx(a)``). URDF joints, whose axis may
    point anywhere, are brought to this form by :mod:`.urdf` (each link frame is turned so
    that the joint axis is its z axis).

    Args:
        origin: ``T_{i-1}_joint`` (4, 4): the joint's frame in the previous link frame at
            ``q = 0`` (before the joint moves).
        sigma, offset, qlim, m, r, I, Jm, G, B, Tc, name: as for :class:`Link`; ``r`` and
            ``I`` are in frame i.
        d: fixed slide along z after the rotation (revolute joints only).
    """

    def __init__(self, origin: ArrayLike | None = None, *, sigma: int | str = 0, d: float = 0.0,
                 theta: float = 0.0, **kw: Any) -> None:
        kw.pop("mdh", None)
        super().__init__(0.0, 0.0, d, theta, sigma=sigma, mdh=True, **kw)
        T = np.eye(4) if origin is None else np.array(origin, dtype=float).reshape(4, 4)
        T.flags.writeable = False
        self.origin = T

    def A(self, q: float) -> Array:
        """Link transform ``T_{i-1}_i`` (4, 4) for joint value ``q``."""
        return self.origin @ super().A(q)

    def copy(self) -> "ETSLink":
        """An independent copy."""
        return ETSLink(self.origin, sigma=self.sigma, d=self.d, theta=self.theta, offset=self.offset,
                       qlim=self.qlim, m=self.m, r=self.r.copy(), I=self.I.copy(), Jm=self.Jm, G=self.G,
                       B=self.B, Tc=self.Tc.copy(), name=self.name)

    def __repr__(self) -> str:
        kind = "Prismatic" if self.isprismatic else "Revolute"
        t = np.round(self.origin[:3, 3], 5).tolist()
        return f"ETSLink({kind}, origin t={t}, offset={self.offset:.4g}, m={self.m:.4g}, name={self.name!r})"
