"""Generated kinematics and dynamics of arms made of elementary-transform links (private).

An :class:`~ejsrl.robotics.link.ETSLink` is ``A_i = origin_i @ Rz(theta) @ Tz(d)``: any
constant transform, then the joint's motion about or along its own z axis (URDF joints
are brought to that form by :mod:`.urdf`). Modified DH is the special case
``origin = Rx(alpha) Tx(a)``, so every algorithm of :mod:`._kernels` that works in link
frames with the joint on z_i (the Jacobian, the composite-rigid-body inertia, the LDL
solve, friction) applies as it is; only the frames and the link rotations of the RNE
differ. :class:`Params` carries ``ets = True`` and these two functions, and
``_kernels.frames``/``_kernels.rne`` hand over to them, so every kernel (fkine, jacob0,
rne, inertia, accel and the IK steps) is generated for these arms too, with the constant
transforms folded in.
"""

from __future__ import annotations

from typing import Any, Sequence

from . import _kernels
from ._codegen import Scalar
from ._kernels import Frame, Vec, _add, _combo, _cross, _dot, _joint, _mv, compose, craig_outward, link_wrench

__all__ = ["Params"]


class Params(_kernels.Params):
    """The parameters of :class:`._kernels.Params` plus each link's constant ``origin``."""

    ets = True

    def __init__(self, robot: Any) -> None:
        super().__init__(robot)
        self.origins = [_kernels._pose(link.origin) for link in robot.links]
        # rows of each origin's rotation (for the RNE)
        self.orows = [[[o[0][k], o[1][k], o[2][k]] for k in range(3)] for o in self.origins]

    def frames(self, q: Sequence[Scalar], base: Frame) -> list[Frame]:
        """Frames 0..n in the world (frame 0 is ``base``), each ``(x, y, z, p)``."""
        F = base
        out = [base]
        for i in range(self.n):
            x, y, z, p = compose(F, self.origins[i])
            ct, st, d = _joint(self, i, q[i])
            x, y = _combo([(ct, x), (st, y)]), _combo([(-st, x), (ct, y)])
            p = _combo([(1.0, p), (d, z)])
            F = (x, y, z, p)
            out.append(F)
        return out

    def rne(self, q: Sequence[Scalar], qd: Sequence[Scalar], qdd: Sequence[Scalar], a0: Vec) -> list[Scalar]:
        """Rigid-body joint forces by recursive Newton-Euler (Craig's link-frame form, as
        for modified DH), ``a0``: base acceleration (``-gravity``) in the base frame."""
        n = self.n
        w: Vec = [0.0, 0.0, 0.0]
        wd: Vec = [0.0, 0.0, 0.0]
        acc: Vec = list(a0)
        z = [0.0, 0.0, 1.0]
        Rs, ps, Fs, Ns = [], [], [], []
        for i in range(n):
            ct, st, d = _joint(self, i, q[i])
            Ro = self.orows[i]
            R = [[Ro[k][0] * ct + Ro[k][1] * st, Ro[k][1] * ct - Ro[k][0] * st, Ro[k][2]] for k in range(3)]
            po = self.origins[i][3]
            p = [po[k] + Ro[k][2] * d for k in range(3)]  # origin i-1 -> i in frame i-1
            w, wd, acc = craig_outward(R, p, self.prism[i], qd[i], qdd[i], w, wd, acc)
            Rs.append(R)
            ps.append(p)
            F, N = link_wrench(self.m[i], self.r[i], self.I[i], w, wd, acc)
            Fs.append(F)
            Ns.append(N)
        tau: list[Scalar] = [0.0] * n
        f: Vec = [0.0, 0.0, 0.0]
        nn: Vec = [0.0, 0.0, 0.0]
        for i in range(n - 1, -1, -1):
            r = self.r[i]
            if i < n - 1:
                fR, nR = _mv(Rs[i + 1], f), _mv(Rs[i + 1], nn)
                nn = _add(nR, _cross(ps[i + 1], fR), _cross(r, Fs[i]), Ns[i])
                f = _add(fR, Fs[i])
            else:
                nn = _add(_cross(r, Fs[i]), Ns[i])
                f = Fs[i]
            tau[i] = _dot(f if self.prism[i] else nn, z)
        return tau
