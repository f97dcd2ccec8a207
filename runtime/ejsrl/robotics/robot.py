"""``Robot``: a serial-link arm described by DH links, its kinematics and dynamics.

Names and conventions follow Corke's Robotics Toolbox (``fkine``, ``jacob0``, ``rne``...).
All inputs and outputs are NumPy arrays in SI units and radians. Methods that take joint
values accept one configuration ``(n,)`` or a batch ``(m, n)`` and answer for all of them
at once (vectorised over configurations). The work is done by code generated for the
arm on first use (``_kernels``): plain float arithmetic for one configuration, one NumPy
operation per scalar operation for a batch.

Frames: ``base`` is ``T_world_base`` (4, 4); ``tool`` is ``T_linkn_tool`` (4, 4).
``gravity`` is the gravitational acceleration in the world frame (default
``[0, 0, -9.81]`` m/s^2).
"""

from __future__ import annotations

import math
from typing import Any, Iterable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _dynamics, _extras, _kernels, _kinematics
from .link import ETSLink, Link

__all__ = ["Robot"]

Array = NDArray[np.float64]


def _floats(x: ArrayLike, n: int) -> list[float]:
    """x broadcast to (n,), as a list of Python floats (fast when already a float array)."""
    if type(x) is np.ndarray and x.shape == (n,) and x.dtype.char == "d":
        return x.tolist()
    return np.broadcast_to(np.asarray(x, dtype=float), (n,)).tolist()


def _parallel_axis(d: Array) -> Array:
    """Inertia shift ``(d.d) E - d d^T`` (3, 3) for a unit mass at offset d."""
    return float(d @ d) * np.eye(3) - np.outer(d, d)



def _qlim_text(link: Any) -> str:
    """A joint's limits as the robot's table prints them (degrees, or metres if prismatic)."""
    if link.qlim is None:
        return "-"
    if link.isprismatic:
        return f"[{link.qlim[0]:.3g}, {link.qlim[1]:.3g}]"
    return f"[{np.degrees(link.qlim[0]):.0f}, {np.degrees(link.qlim[1]):.0f}]"

class Robot:
    """A serial-link arm.

    The kinematics and dynamics run through functions generated for this arm's
    parameters (see ``_kernels``): on plain floats for one configuration, vectorised for a
    batch. ``base`` and ``tool`` are folded into them, so assign new matrices rather
    than editing them in place (they are read-only).

    Args:
        links: the links from base to end-effector (all standard or all modified DH).
        name: label shown in the UI and in ``repr``.
        base: ``T_world_base`` (4, 4); identity by default.
        tool: ``T_linkn_tool`` (4, 4); identity by default.
        gravity: gravitational acceleration in the world frame (3,), m/s^2.
        poses: named joint configurations, e.g. ``{"qz": ..., "qr": ...}``; each is also
            available as an attribute (``robot.qz``).
        manufacturer: optional text.

    Geometry for drawing: ``link_lengths()`` gives each link's ``a`` and ``d`` and
    ``reach`` a characteristic size of the arm (m), so a viewer can size link bodies and
    the scene without knowing the model.
    """

    _fast = True  # False: the NumPy reference implementations (the tests compare both)

    def __init__(
        self,
        links: Iterable[Link],
        *,
        name: str = "robot",
        base: ArrayLike | None = None,
        tool: ArrayLike | None = None,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        poses: dict[str, ArrayLike] | None = None,
        manufacturer: str = "",
    ) -> None:
        self.links: list[Link] = list(links)
        if not self.links:
            raise ValueError("a Robot needs at least one link")
        mdh = {link.mdh for link in self.links}
        if len(mdh) != 1:
            raise ValueError("all links must use the same DH convention (standard or modified)")
        ets = {isinstance(link, ETSLink) for link in self.links}
        if len(ets) != 1:
            raise ValueError("links must be all ETSLink (elementary transforms) or all DH links; "
                             "write a DH link as ETSLink(origin=Rx(alpha) @ Tx(a), d=d)")
        #: True for an arm of :class:`ETSLink` (e.g. loaded from a URDF file)
        self.ets = ets.pop()
        #: per link frame 0..n, the geometry to draw (set by ``load_urdf``; None: automatic)
        self.visuals: list[list[Any]] | None = None
        #: the joints' names (URDF), else ``["q1", ...]``
        self.joint_names: list[str] = [link.name or f"q{j + 1}" for j, link in enumerate(self.links)]
        self.name = name
        self.manufacturer = manufacturer
        self.base = np.eye(4) if base is None else base  # type: ignore[assignment]
        self.tool = np.eye(4) if tool is None else tool  # type: ignore[assignment]
        self.gravity = np.asarray(gravity, dtype=float).reshape(3)
        self.poses: dict[str, Array] = {}
        self._payload: tuple[float, Array, Array] | None = None
        self._cache_key: tuple[int, ...] | None = None
        self._lists_key = -1
        self._gen = 0
        for key, value in (poses or {}).items():
            self.addconfiguration(key, value)

    # ----------------------------------------------------------------- structure
    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.links)

    @property
    def mdh(self) -> bool:
        """True when the links use modified (Craig) DH parameters."""
        return self.links[0].mdh

    @property
    def base(self) -> Array:
        """``T_world_base`` (4, 4)."""
        return self._base

    @base.setter
    def base(self, T: ArrayLike) -> None:
        T = np.array(T, dtype=float).reshape(4, 4)
        T.flags.writeable = False
        self._base = T
        self._base_is_eye = bool(np.array_equal(T, np.eye(4)))
        self._cache_key = None  # the generated kernels include the base

    @property
    def tool(self) -> Array:
        """``T_linkn_tool`` (4, 4)."""
        return self._tool

    @tool.setter
    def tool(self, T: ArrayLike) -> None:
        T = np.array(T, dtype=float).reshape(4, 4)
        T.flags.writeable = False
        self._tool = T
        self._tool_is_eye = bool(np.array_equal(T, np.eye(4)))
        self._cache_key = None  # the payload is placed relative to the tool; kernels include it

    @property
    def qlim(self) -> Array:
        """Joint limits (2, n): row 0 minimum, row 1 maximum (``±inf`` when unlimited)."""
        out = np.empty((2, self.n))
        for j, link in enumerate(self.links):
            out[:, j] = (-np.inf, np.inf) if link.qlim is None else link.qlim
        return out

    @property
    def reach(self) -> float:
        """Characteristic size (m): the sum of ``|a| + |d|`` over the links (prismatic
        links count their upper limit), plus the tool offset. An upper bound on reach."""
        total = 0.0
        for link in self.links:
            d = link.d
            if link.isprismatic:
                d = link.qlim[1] + link.offset if link.qlim is not None else link.offset
            total += abs(link.a) + abs(d)
            if self.ets:
                total += float(np.linalg.norm(link.origin[:3, 3]))
        return float(total + np.linalg.norm(self.tool[:3, 3]))

    def link_lengths(self) -> Array:
        """Geometry hints (n, 2): ``[a, d]`` of each link in m (prismatic: ``d`` = upper
        limit). Link i's body runs from frame i-1 to frame i: ``d`` along ``z_{i-1}`` then
        ``a`` along ``x_i`` (standard DH)."""
        out = np.empty((self.n, 2))
        for j, link in enumerate(self.links):
            d = link.d
            if link.isprismatic:
                d = link.qlim[1] + link.offset if link.qlim is not None else link.offset
            out[j] = (link.a, d)
        return out

    def addconfiguration(self, name: str, q: ArrayLike) -> None:
        """Register a named pose, reachable as ``robot.poses[name]`` and ``robot.<name>``."""
        q = np.asarray(q, dtype=float).reshape(self.n)
        self.poses[name] = q
        setattr(self, name, q)

    # ----------------------------------------------------------------- cached arrays
    def _params(self) -> None:
        key = tuple([link.version for link in self.links])
        if key == self._cache_key:
            return
        L = self.links
        self._a = np.array([k.a for k in L])
        self._alpha = np.array([k.alpha for k in L])
        self._ca = np.cos(self._alpha)
        self._sa = np.sin(self._alpha)
        self._d = np.array([k.d for k in L])
        self._theta = np.array([k.theta for k in L])
        self._offset = np.array([k.offset for k in L])
        self._prism = np.array([k.isprismatic for k in L])
        if self.ets:
            self._origins = np.array([k.origin for k in L])  # (n, 4, 4)
        self._m = np.array([k.m for k in L])
        self._r = np.array([k.r for k in L])
        self._I = np.array([k.I for k in L])
        self._Jm = np.array([k.Jm for k in L])
        self._G = np.array([k.G for k in L])
        self._B = np.array([k.B for k in L])
        self._Tc = np.array([k.Tc for k in L])  # (n, 2)
        self._armature = self._Jm * self._G**2
        if self._payload is not None:
            self._apply_payload()
        Gabs = np.abs(self._G)
        self._coulomb = (Gabs * self._Tc[:, 0]).tolist(), (Gabs * self._Tc[:, 1]).tolist()
        self._kernels: dict[tuple, _kernels.Kernel] = {}
        self._kparams: _kernels.Params | None = None
        self._cache_key = key
        self._gen += 1  # generation of the cached arrays

    def _apply_payload(self) -> None:
        mp, rp, Ip = self._payload  # type: ignore[misc]
        R = self.tool[:3, :3]
        r_n = R @ rp + self.tool[:3, 3]  # payload centre of mass in frame n
        I_n = R @ Ip @ R.T
        m0, r0, I0 = self._m[-1], self._r[-1], self._I[-1]
        mt = m0 + mp
        if mt <= 0:
            return
        c = (m0 * r0 + mp * r_n) / mt
        self._m = self._m.copy()
        self._r = self._r.copy()
        self._I = self._I.copy()
        self._m[-1] = mt
        self._r[-1] = c
        self._I[-1] = I0 + m0 * _parallel_axis(r0 - c) + I_n + mp * _parallel_axis(r_n - c)

    def _rne_rigid(self, A: Array, Qd: Array, Qdd: Array, a0: Array) -> Array:
        """Rigid-body RNE (m, n): plain floats for one configuration, NumPy for batches."""
        if len(Qd) == 1:
            if self._lists_key != self._gen:
                self._lists = (self._m.tolist(), self._r.tolist(), self._I.tolist(), self._prism.tolist())
                self._lists_key = self._gen
            m, r, I, pr = self._lists
            return _dynamics.rne_rigid_single(A[0], Qd[0], Qdd[0], a0, m, r, I, pr, self.mdh)[None]
        return _dynamics.rne_rigid(A, Qd, Qdd, a0, self._m, self._r, self._I, self._prism, self.mdh)

    def __getstate__(self) -> dict[str, Any]:
        # Generated functions do not pickle: drop them, they are rebuilt on first use.
        state = self.__dict__.copy()
        state.update(_kernels={}, _kparams=None, _cache_key=None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self.base, self.tool = self._base, self._tool  # read-only again

    def _kernel(self, key: tuple) -> _kernels.Kernel:
        """The generated function ``key`` for the current parameters (built on first use)."""
        self._params()
        k = self._kernels.get(key)
        if k is None:
            if self._kparams is None:
                if self.ets:
                    from . import _ets

                    self._kparams = _ets.Params(self)
                else:
                    self._kparams = _kernels.Params(self)
            k = self._kernels[key] = _kernels.build(self._kparams, key)
        return k

    def _a0(self, gravity: ArrayLike | None) -> list[float]:
        """Base acceleration ``-g`` in the base frame (3 floats)."""
        g = self._gravity_base(gravity).tolist()
        return [-g[0], -g[1], -g[2]]

    def _run(self, key: tuple, args: list[Array], shape: tuple[int, ...]) -> Array:
        """Run kernel ``key`` on one configuration ((n,) args) or a batch ((m, k) args)."""
        k = self._kernel(key)
        if args[0].ndim == 1:
            flat = [v for a in args for v in a.tolist()]
            try:
                vals = k.single(*flat)
            except (ValueError, ZeroDivisionError, OverflowError):
                vals = k.fallback(flat)
            return np.array(vals, dtype=float).reshape(shape)
        lead = args[0].shape[:-1]
        m = int(np.prod(lead))
        flat = [np.broadcast_to(a, lead + a.shape[-1:]).reshape(m, a.shape[-1]) for a in args]
        return k.batch(flat, int(np.prod(shape))).reshape(lead + shape)

    def _A(self, q: Array) -> Array:
        self._params()
        A = _kinematics.dh_transforms(
            q, self._a, self._alpha, self._d, self._theta, self._offset, self._prism, self.mdh,
            ca=self._ca, sa=self._sa,
        )
        return self._origins @ A if self.ets else A

    def _q(self, q: ArrayLike) -> Array:
        q = np.asarray(q, dtype=float)
        if q.shape[-1] != self.n:
            raise ValueError(f"{self.name}: expected {self.n} joint values, got shape {q.shape}")
        return q

    # ----------------------------------------------------------------- kinematics
    def fkine(self, q: ArrayLike) -> Array:
        """End-effector pose ``T_world_tool`` (4, 4), or (m, 4, 4) for q of shape (m, n).

        Includes ``base`` and ``tool``."""
        q = self._q(q)
        if self._fast:
            return self._run(("fkine",), [q], (4, 4))
        A = self._A(q)
        return _kinematics.chain(
            A, None if self._base_is_eye else self._base, None if self._tool_is_eye else self._tool
        )

    def fkine_all(self, q: ArrayLike) -> Array:
        """World frames (n+1, 4, 4) (or (m, n+1, 4, 4)): index 0 is the base frame
        (``base``), index i the frame of link i; the tool is not applied. Draw link i's
        body in frame i."""
        q = self._q(q)
        if self._fast:
            return self._run(("fkine_all",), [q], (self.n + 1, 4, 4))
        return _kinematics.chain_all(self._A(q), self._base)

    def _frames_and_end(self, q: Array) -> tuple[Array, Array]:
        F = _kinematics.chain_all(self._A(q), self._base)
        Te = F[..., -1, :, :] if self._tool_is_eye else F[..., -1, :, :] @ self._tool
        return F, Te

    def jacob0(self, q: ArrayLike) -> Array:
        """Geometric Jacobian in the world frame (6, n) or (m, 6, n).

        Rows ``vx vy vz wx wy wz``: linear velocity of the tool origin and angular
        velocity, both in world coordinates."""
        q = self._q(q)
        if self._fast:
            return self._run(("jacob0",), [q], (6, self.n))
        F, Te = self._frames_and_end(q)
        return _kinematics.jacobian_from_frames(F, Te, self._prism, self.mdh)

    def jacobe(self, q: ArrayLike) -> Array:
        """Geometric Jacobian in the tool frame (6, n) or (m, 6, n), rows ``vx vy vz wx wy wz``."""
        q = self._q(q)
        if self._fast:
            return self._run(("jacobe",), [q], (6, self.n))
        F, Te = self._frames_and_end(q)
        J = _kinematics.jacobian_from_frames(F, Te, self._prism, self.mdh)
        Rt = np.swapaxes(Te[..., :3, :3], -1, -2)
        return np.concatenate((Rt @ J[..., :3, :], Rt @ J[..., 3:, :]), axis=-2)

    def manipulability(self, q: ArrayLike, *, axes: str = "all") -> Array | float:
        """Yoshikawa manipulability ``sqrt(det(J J^T))`` of ``jacob0`` (scalar or (m,)).

        ``axes``: ``"all"`` (6 rows), ``"trans"`` (linear rows), ``"rot"`` (angular rows).
        """
        J = self.jacob0(q)
        rows = {"all": slice(0, 6), "trans": slice(0, 3), "rot": slice(3, 6)}[axes]
        J = J[..., rows, :]
        out = np.sqrt(np.maximum(np.linalg.det(J @ np.swapaxes(J, -1, -2)), 0.0))
        return float(out) if np.ndim(out) == 0 else out

    # ----------------------------------------------------------------- inverse kinematics
    def ikine(self, T: ArrayLike, q0: ArrayLike | None = None, **kw: Any) -> Any:
        """Inverse kinematics: closed-form seeds where the arm has them, polished and otherwise
        searched by Levenberg-Marquardt; see :func:`ejsrl.robotics.ik.ikine`."""
        from .ik import ikine

        return ikine(self, T, q0, **kw)

    def ikine_a(self, T: ArrayLike, config: str = "lun", **kw: Any) -> Any:
        """Closed-form inverse kinematics of a Puma-type arm; see :func:`ejsrl.robotics.ik.ikine_a`."""
        from .ik import ikine_a

        return ikine_a(self, T, config, **kw)

    # ----------------------------------------------------------------- dynamics
    def payload(self, mass: float, r: ArrayLike = (0.0, 0.0, 0.0), I: ArrayLike | None = None) -> None:  # noqa: E741
        """Attach a payload rigidly to the tool (the EjsRL paper's external inertia).

        Args:
            mass: kg (0 removes the payload).
            r: its centre of mass in the tool frame (m).
            I: its inertia about its centre of mass in tool-frame axes (3, 6 or (3, 3)).
        """
        from .link import _inertia_matrix

        self._payload = None if mass == 0 else (float(mass), np.asarray(r, float).reshape(3), _inertia_matrix(I))
        self._cache_key = None

    def _gravity_base(self, gravity: ArrayLike | None) -> Array:
        g = self.gravity if gravity is None else np.asarray(gravity, dtype=float)
        return g if self._base_is_eye else g @ self._base[:3, :3]  # R^T g

    def friction(self, qd: ArrayLike) -> Array:
        """Joint friction (n,) or (m, n) at joint velocities ``qd``: viscous ``B G^2 qd`` and
        Coulomb ``|G| Tc±``, acting *against* the motion (Toolbox sign). ``rne`` adds its
        negative, i.e. the torque the motors spend overcoming it."""
        self._params()
        qd = np.asarray(qd, dtype=float)
        G = np.abs(self._G)
        coul = np.where(qd > 0, self._Tc[:, 0], np.where(qd < 0, self._Tc[:, 1], 0.0))
        return -G * (self._B * G * qd + coul)

    def nofriction(self, *, coulomb: bool = True, viscous: bool = False) -> "Robot":
        """A copy with friction removed, as Robotics Toolbox's ``nofriction``: ``coulomb``
        zeroes the Coulomb friction ``Tc``, ``viscous`` the viscous friction ``B`` (by
        default only Coulomb friction goes)."""
        links = [k.copy() for k in self.links]
        for k in links:
            if coulomb:
                k.Tc = np.zeros(2)
            if viscous:
                k.B = 0.0
        r = Robot(links, name=self.name + " (no friction)", base=self.base, tool=self.tool,
                  gravity=self.gravity, poses=self.poses, manufacturer=self.manufacturer)
        r._payload = self._payload
        for key in ("visuals", "joint_names", "urdf_frames", "urdf_path", "link_names", "tip"):  # a URDF arm's
            if key in self.__dict__:
                setattr(r, key, self.__dict__[key])
        return r

    def rne(
        self,
        q: ArrayLike,
        qd: ArrayLike | None = None,
        qdd: ArrayLike | None = None,
        *,
        gravity: ArrayLike | None = None,
        fext: ArrayLike | None = None,
        friction: bool = True,
        armature: bool = True,
    ) -> Array:
        """Inverse dynamics by recursive Newton-Euler: joint forces (n,) or (m, n).

        ``tau = M(q) qdd + C(q, qd) qd + g(q) - friction(qd) - J0(q)^T fext``, where M
        includes the motor armature ``Jm G^2`` and any ``payload``.

        Args:
            q, qd, qdd: (n,) or (m, n); ``qd``/``qdd`` default to zero.
            gravity: override ``self.gravity`` (world frame, m/s^2).
            fext: (6,) or (m, 6) wrench ``[fx fy fz mx my mz]`` applied *by the environment
                on the tool*, expressed in the world frame, moment about the tool origin.
            friction, armature: include friction / motor armature (default True).
        """
        q = self._q(q)
        if self._fast and fext is None:
            return self._rne_fast(q, qd, qdd, gravity, friction, armature)
        q = self._q(q)
        single = q.ndim == 1
        Q = np.atleast_2d(q)
        Qd = np.zeros_like(Q) if qd is None else np.broadcast_to(np.asarray(qd, float), Q.shape)
        Qdd = np.zeros_like(Q) if qdd is None else np.broadcast_to(np.asarray(qdd, float), Q.shape)
        A = self._A(Q)
        tau = self._rne_rigid(A, Qd, Qdd, -self._gravity_base(gravity))
        if armature:
            tau += self._armature * Qdd
        if friction:
            tau -= self.friction(Qd)
        if fext is not None:
            J = self.jacob0(Q)
            tau -= (np.swapaxes(J, -1, -2) @ np.broadcast_to(np.asarray(fext, float), (len(Q), 6))[..., None])[..., 0]
        return tau[0] if single else tau

    def _rne_fast(self, q: Array, qd: ArrayLike | None, qdd: ArrayLike | None, gravity: ArrayLike | None,
                  friction: bool, armature: bool) -> Array:
        n = self.n
        kernel = self._kernel(("rne", qd is not None, qdd is not None, armature, friction and qd is not None))
        if q.ndim == 1:
            qdl = [0.0] * n if qd is None else _floats(qd, n)
            qddl = [0.0] * n if qdd is None else _floats(qdd, n)
            args = [*q.tolist(), *qdl, *qddl, *self._a0(gravity)]
            try:
                return np.array(kernel.single(*args), dtype=float)
            except (ValueError, ZeroDivisionError, OverflowError):
                return np.array(kernel.fallback(args))
        Q = q.reshape(-1, n)
        zero = np.zeros((1, n))
        Qd = zero if qd is None else np.asarray(qd, float)
        Qdd = zero if qdd is None else np.asarray(qdd, float)
        Qd, Qdd = (np.broadcast_to(x, q.shape).reshape(-1, n) for x in (Qd, Qdd))
        a0 = np.broadcast_to(np.array(self._a0(gravity)), (len(Q), 3))
        return kernel.batch([Q, Qd, Qdd, a0], n).reshape(q.shape)

    def inertia(self, q: ArrayLike) -> Array:
        """Joint-space inertia matrix (n, n) or (m, n, n), motor armature included
        (composite rigid body: centre-of-mass Jacobians of all links, batched)."""
        q = self._q(q)
        if self._fast:
            return self._run(("inertia",), [q], (self.n, self.n))
        single = q.ndim == 1
        Q = np.atleast_2d(q)
        M = self._inertia(Q)
        return M[0] if single else M

    def _inertia(self, Q: Array, A: Array | None = None) -> Array:
        if A is None:
            A = self._A(Q)
        F = _kinematics.chain_all(A, np.eye(4))  # M does not depend on the base pose
        M = _dynamics.inertia_composite(F, self._m, self._r, self._I, self._prism, self.mdh)
        n = self.n
        M[:, np.arange(n), np.arange(n)] += self._armature
        return 0.5 * (M + np.swapaxes(M, -1, -2))

    def coriolis(self, q: ArrayLike, qd: ArrayLike) -> Array:
        """Coriolis/centripetal matrix C (n, n) or (m, n, n): velocity torques are ``C @ qd``."""
        q = self._q(q)
        single = q.ndim == 1
        Q = np.atleast_2d(q)
        Qd = np.broadcast_to(np.asarray(qd, float), Q.shape)
        m, n = Q.shape
        # Unit speeds e_j give the squared terms; pairs e_j + e_k the products.
        pairs = [(j, k) for j in range(n) for k in range(j + 1, n)]
        basis = np.zeros((n + len(pairs), n))
        basis[np.arange(n), np.arange(n)] = 1.0
        for row, (j, k) in enumerate(pairs, start=n):
            basis[row, [j, k]] = 1.0
        nb = len(basis)
        tau = self.rne(np.repeat(Q, nb, axis=0), np.tile(basis, (m, 1)), None,
                       gravity=np.zeros(3), friction=False, armature=False).reshape(m, nb, n)
        Csq = tau[:, :n, :].swapaxes(-1, -2)  # (m, n, n): column j from qd_j^2
        C = Csq * Qd[:, None, :]
        for row, (j, k) in enumerate(pairs, start=n):
            cross_jk = tau[:, row, :] - Csq[:, :, j] - Csq[:, :, k]  # coefficient of qd_j qd_k
            C[:, :, j] += 0.5 * cross_jk * Qd[:, k, None]
            C[:, :, k] += 0.5 * cross_jk * Qd[:, j, None]
        return C[0] if single else C

    def gravload(self, q: ArrayLike, *, gravity: ArrayLike | None = None) -> Array:
        """Gravity torques g(q) (n,) or (m, n)."""
        q = self._q(q)
        return self.rne(q, None, None, gravity=gravity, friction=False, armature=False)

    def accel(self, q: ArrayLike, qd: ArrayLike, tau: ArrayLike, *, gravity: ArrayLike | None = None) -> Array:
        """Forward dynamics: joint accelerations (n,) or (m, n) for applied forces ``tau``.

        Walker-Orin style: RNE with ``qdd = 0`` gives the bias ``C qd + g - friction``, the
        composite-rigid-body inertia M, then ``qdd = M^-1 (tau - bias)`` (batched solve).
        """
        q = self._q(q)
        if self._fast:
            return self._accel_fast(q, qd, tau, gravity)
        single = q.ndim == 1
        Q = np.atleast_2d(q)
        Qd = np.broadcast_to(np.asarray(qd, float), Q.shape)
        T = np.broadcast_to(np.asarray(tau, float), Q.shape)
        A = self._A(Q)
        M = self._inertia(Q, A)
        _dynamics.check_inertia(self.name, Q, _dynamics.ldl_pivots(M))
        bias = self._rne_rigid(A, Qd, np.zeros_like(Qd), -self._gravity_base(gravity)) - self.friction(Qd)
        qdd = np.linalg.solve(M, (T - bias)[..., None])[..., 0]
        return qdd[0] if single else qdd

    def _accel_fast(self, q: Array, qd: ArrayLike, tau: ArrayLike, gravity: ArrayLike | None) -> Array:
        n = self.n
        kernel = self._kernel(("accel",))
        if q.ndim == 1:
            args = [*q.tolist(), *_floats(qd, n), *_floats(tau, n), *self._a0(gravity)]
            try:
                vals = kernel.single(*args)
            except (ValueError, ZeroDivisionError, OverflowError):
                vals = kernel.fallback(args)
            piv = vals[n:]
            if min(piv) > max(piv) / _dynamics.MAX_PIVOT_RATIO:
                return np.array(vals[:n], dtype=float)
            _dynamics.check_inertia(self.name, q, np.array(piv, dtype=float))
            return np.array(vals[:n], dtype=float)  # not reached: check_inertia raised
        Q = q.reshape(-1, n)
        Qd, T = (np.broadcast_to(np.asarray(x, float), q.shape).reshape(-1, n) for x in (qd, tau))
        a0 = np.broadcast_to(np.array(self._a0(gravity)), (len(Q), 3))
        with np.errstate(divide="ignore", invalid="ignore"):
            out = kernel.batch([Q, Qd, T, a0], 2 * n)
        _dynamics.check_inertia(self.name, Q, out[:, n:])
        return out[:, :n].reshape(q.shape)

    # ----------------------------------------------------------------- more of the Toolbox
    def hessian0(self, q: ArrayLike, J0: ArrayLike | None = None) -> Array:
        """Manipulator Hessian in the world frame (n, 6, n) (or (m, n, 6, n)):
        ``H[j, :, i]`` is the derivative of ``jacob0``'s column i with respect to ``q_j``."""
        return _extras.hessian0(self, self._q(q), None if J0 is None else np.asarray(J0, dtype=float))

    def jacob0_dot(self, q: ArrayLike, qd: ArrayLike, H: ArrayLike | None = None) -> Array:
        """Rate of change of ``jacob0`` (6, n) at joint velocities ``qd``, so the tool's
        spatial acceleration is ``J qdd + Jdot qd``."""
        return _extras.jacob0_dot(self, self._q(q), qd, None if H is None else np.asarray(H, dtype=float))

    def jacobm(self, q: ArrayLike, *, axes: str = "all") -> Array:
        """Manipulability Jacobian (n, 1): the gradient of ``manipulability(q, axes=axes)``."""
        return _extras.jacobm(self, self._q(q), axes)

    def fdyn(self, T: float, q0: ArrayLike, Q: Any = None, Q_args: dict | None = None, qd0: ArrayLike | None = None,
             solver: str = "RK45", solver_args: dict | None = None, dt: float | None = None) -> Any:
        """Forward dynamics over ``T`` s from ``q0`` (and ``qd0``) under joint torques
        ``Q(robot, t, q, qd)`` (zero if None): a ``(t, q, qd)`` named tuple, integrated by
        scipy's ``solver`` (as the Toolbox's ``fdyn``; ``dt`` resamples on a uniform grid)."""
        return _extras.fdyn(self, T, q0, Q, Q_args, qd0, solver, solver_args, dt)

    def cinertia(self, q: ArrayLike) -> Array:
        """Cartesian inertia (6, 6) ``J^-T M J^-1`` (world-frame geometric Jacobian)."""
        return _extras.cinertia(self, self._q(q))

    def itorque(self, q: ArrayLike, qdd: ArrayLike) -> Array:
        """Inertia torques ``M(q) qdd`` (n,) or (m, n): RNE with zero velocity and gravity."""
        return self.rne(q, None, qdd, gravity=np.zeros(3))

    def gravjac(self, q: ArrayLike, *, gravity: ArrayLike | None = None) -> tuple[Array, Array]:
        """Gravity torques from the centre-of-mass Jacobians and ``jacob0``: ``(tau, J)``."""
        return _extras.gravjac(self, self._q(q), gravity)

    def paycap(self, q: ArrayLike, w: ArrayLike, tlim: ArrayLike, *, frame: str = "base") -> tuple[Any, Any]:
        """Static payload capacity ``(wmax, joint)`` along the wrench direction ``w``
        within the joint torque limits ``tlim`` (see :func:`._extras.paycap`)."""
        return _extras.paycap(self, self._q(q), w, tlim, frame)

    def payload_capacity(self, q: ArrayLike, tau_m: ArrayLike, w: ArrayLike, frame: str = "base") -> Array:
        """Per joint (m, n), the multiple of ``w`` that takes it to its torque limit (as the
        Toolbox's ``payload_capacity``)."""
        return _extras.payload_capacity(self, self._q(q), tau_m, w, frame)

    def vellipse(self, q: ArrayLike, opt: str = "trans", *, centre: ArrayLike | str | None = None) -> Any:
        """Velocity ellipsoid (``Ellipsoid``) of the tool for unit joint speed, ``J J^T``."""
        return _extras.ellipse(self, self._q(q), opt, "velocity", centre)

    def fellipse(self, q: ArrayLike, opt: str = "trans", *, centre: ArrayLike | str | None = None) -> Any:
        """Force ellipsoid (``Ellipsoid``) of the tool for unit joint torque, ``(J J^T)^-1``."""
        return _extras.ellipse(self, self._q(q), opt, "force", centre)

    def collided(self, q: ArrayLike, shape: Any, T: ArrayLike | None = None, *, margin: float = 0.0,
                 skip_base: bool = False) -> list[int]:
        """Link frames (0 = base) that touch the ``ejsrl.world.collision.CollisionShape``
        ``shape`` at world pose ``T`` (identity if None), or come within ``margin`` m. Links
        are checked with the convex hulls of a URDF arm's meshes, else with the capsules and
        cylinders of the automatic link geometry."""
        return _extras.collided_links(self, self._q(q), shape, T, margin, skip_base)

    def iscollided(self, q: ArrayLike, shape: Any, T: ArrayLike | None = None, *, margin: float = 0.0,
                   skip_base: bool = False) -> bool:
        """True if any link touches ``shape`` (see :meth:`collided`)."""
        return bool(self.collided(q, shape, T, margin=margin, skip_base=skip_base))

    # ----------------------------------------------------------------- display
    def __repr__(self) -> str:
        if self.ets:
            return self._repr_ets()
        conv = "modified DH" if self.mdh else "standard DH"
        head = f"{self.name}: {self.n} joints ({''.join('P' if k.isprismatic else 'R' for k in self.links)}), {conv}"
        rows = [f"{'j':>2} | {'theta':>12} | {'d':>12} | {'a':>9} | {'alpha':>9} | {'qlim (deg or m)':>19}"]
        rows.append("-" * len(rows[0]))
        for j, k in enumerate(self.links, start=1):
            off = f"{k.offset:+.4g}" if k.offset else ""
            theta = f"{k.theta:.4g}" if k.isprismatic else f"q{j}{off}"
            d = f"q{j}{off}" if k.isprismatic else f"{k.d:.5g}"
            lim = _qlim_text(k)
            rows.append(f"{j:>2} | {theta:>12} | {d:>12} | {k.a:>9.5g} | {np.degrees(k.alpha):>8.4g}° | {lim:>19}")
        return "\n".join([head, *rows, *self._repr_extra()])

    def _repr_ets(self) -> str:
        from .transforms import tr2rpy

        head = f"{self.name}: {self.n} joints ({''.join('P' if k.isprismatic else 'R' for k in self.links)}), " \
               "elementary transforms: A_i = origin_i Rz(q) (R) or origin_i Tz(q) (P)"
        rows = [f"{'j':>2} | {'joint':<22} | {'origin xyz (m)':>28} | {'origin rpy (deg)':>22} | {'qlim (deg or m)':>17}"]
        rows.append("-" * len(rows[0]))
        for j, k in enumerate(self.links, start=1):
            xyz = ", ".join(f"{v:.4g}" for v in k.origin[:3, 3])
            rpy = ", ".join(f"{v:.4g}" for v in np.degrees(tr2rpy(k.origin)))
            lim = _qlim_text(k)
            rows.append(f"{j:>2} | {self.joint_names[j - 1][:22]:<22} | {xyz:>28} | {rpy:>22} | {lim:>17}")
        return "\n".join([head, *rows, *self._repr_extra()])

    def _repr_extra(self) -> list[str]:
        """The lines after a table: base and tool offsets, named poses."""
        extra = []
        if not self._base_is_eye:
            extra.append(f"base t = {np.round(self.base[:3, 3], 4).tolist()}")
        if not self._tool_is_eye:
            extra.append(f"tool t = {np.round(self.tool[:3, 3], 4).tolist()}")
        if self.poses:
            extra.append("poses: " + ", ".join(self.poses))
        return extra
