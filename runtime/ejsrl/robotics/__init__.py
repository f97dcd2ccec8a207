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

from ejsrl._lazy import lazy_exports

# Each name is imported when first read (ejsrl._lazy; the submodules models, ik, trajectory and
# transforms too): a lab that only needs ``transforms`` (every 3D scene) loads nothing else.
__getattr__, __dir__ = lazy_exports(__name__, {
    ".link": ("ETSLink", "Link", "PrismaticDH", "PrismaticMDH", "RevoluteDH", "RevoluteMDH"),
    ".robot": ("Robot",),
    ".urdf": ("load_urdf",),
    ".pose": ("SE3", "SO3"),
    ".quaternion": ("UnitQuaternion",),
    ".trajectory": ("mstraj",),
})

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
