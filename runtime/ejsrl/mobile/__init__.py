"""ejsrl.mobile: mobile robots, as the Robotics Toolbox names them (issue #27).

- vehicles (:mod:`.vehicles`): :class:`Bicycle` (car-like, steering limits), :class:`Unicycle`,
  :class:`DiffSteer` (differential drive), :class:`Omni`; their kinematics ``deriv(x, u)``
  for a spec's ODEs, ``step`` with noisy odometry, the motion model ``f``, ``Fx``, ``Fv``;
- controllers (:mod:`.control`): :func:`move_to_point`, :func:`move_to_pose`,
  :func:`follow_line`, :func:`pure_pursuit`;
- maps and planners: :class:`BinaryOccupancyGrid` (also from an image file),
  :class:`DistanceTransformPlanner`, :class:`AStarPlanner`, :class:`DstarPlanner` (replans
  when cells change), :class:`PRMPlanner`, :class:`RRTPlanner` (car-like),
  :class:`LatticePlanner` (straight and quarter-turn moves on a lattice of poses);
- sensors: :class:`LandmarkMap`, :class:`RangeBearingSensor`, :class:`LaserScanner`;
- estimation: :class:`EKF` (dead reckoning, localisation, EKF-SLAM), :class:`ParticleFilter`
  (Monte Carlo localisation), :class:`PoseGraph` (graph SLAM, g2o and TORO files);
- :class:`SE2` poses; drawing helpers for the 2D panel: :func:`ellipse_points`,
  :func:`vehicle_outline`.

Units: metres, radians, seconds; a pose is ``(x, y, theta)``.
"""

from __future__ import annotations

from ._util import angdiff, wrap
from .control import follow_line, lookahead_point, move_to_point, move_to_pose, pose_direction, pure_pursuit
from .drawing import chi2_2dof, ellipse_points, vehicle_outline
from .ekf import EKF
from .grid import BinaryOccupancyGrid, OccupancyGrid
from .lattice import LatticePlanner, LatticeStatus
from .particles import ParticleFilter
from .planners import AStarPlanner, DistanceTransformPlanner, DstarPlanner, NoPathError, path_length
from .posegraph import PoseGraph
from .poses import SE2
from .sampling import PRMPlanner, RRTPlanner
from .sensors import LandmarkMap, LaserScanner, RangeBearingSensor
from .vehicles import Bicycle, DiffSteer, Omni, Unicycle, VehicleBase

__all__ = [
    "AStarPlanner", "Bicycle", "BinaryOccupancyGrid", "DiffSteer", "DistanceTransformPlanner", "DstarPlanner",
    "EKF", "LandmarkMap", "LatticePlanner", "LatticeStatus", "PoseGraph", "PRMPlanner", "RRTPlanner", "LaserScanner", "NoPathError", "OccupancyGrid", "Omni", "ParticleFilter", "RangeBearingSensor", "SE2",
    "Unicycle", "VehicleBase", "angdiff", "chi2_2dof", "ellipse_points", "follow_line", "lookahead_point",
    "move_to_point", "move_to_pose", "path_length", "pose_direction", "pure_pursuit", "vehicle_outline", "wrap",
]
