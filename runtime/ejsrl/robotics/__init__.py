"""ejsrl.robotics: serial-link arms from DH parameters or URDF files (what EjsRL's Robotics module gave EJS).

Names follow Corke's Robotics Toolbox: ``Robot.fkine``, ``jacob0``, ``ikine``, ``rne``...
Everything takes and returns NumPy arrays, SI units and radians.

- :class:`Link`, :class:`Robot`: models and their kinematics and dynamics.
- :class:`SE3`, :class:`SO3`, :class:`UnitQuaternion`: pose and rotation values (composition ``*``, ``inv``, ``interp``...).
- :func:`load_urdf`: a ``Robot`` from a URDF file (:class:`ETSLink` links, meshes to draw).
- :mod:`models`: ``puma560``, ``stanford``, ``pa10``, ``ur5``, ``ur5_urdf``, ``planar``, ``rrr``, ``scara``,
  ``panda``, ``kr5``, ``irb140``, ``lbr_iiwa``, ``ur10``, ``random_arm``.
- :mod:`trajectory`: cubic, quintic, LSPB, synchronous/asynchronous, splines, 4-3-4, Cartesian,
  :func:`mstraj` (multi-segment with blends, as the Toolbox's).
- :mod:`transforms`: rotations, transforms, RPY/Euler, angle-axis, quaternions (wxyz).
- :mod:`ik`: ``ikine`` (closed-form seeds where the arm has them, Levenberg-Marquardt) and
  ``ikine_a`` (closed form, Puma type).
"""

from __future__ import annotations

from . import transforms
from .link import ETSLink, Link, PrismaticDH, PrismaticMDH, RevoluteDH, RevoluteMDH
from .robot import Robot
from .urdf import load_urdf
from .pose import SE3, SO3
from .quaternion import UnitQuaternion

from . import models  # noqa: E402  (models need Robot)
from . import ik, trajectory  # noqa: E402
from .trajectory import mstraj  # noqa: E402

__all__ = [
    "Link",
    "ETSLink",
    "load_urdf",
    "SE3",
    "SO3",
    "UnitQuaternion",
    "RevoluteDH",
    "PrismaticDH",
    "RevoluteMDH",
    "PrismaticMDH",
    "Robot",
    "models",
    "trajectory",
    "mstraj",
    "transforms",
    "ik",
]
