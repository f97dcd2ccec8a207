"""The 3D scene's mobile-robot kinds (declared in :mod:`ejsrl.world.kinds`): their world
nodes, which turn a pose ``[x, y, theta]``, a scan, a grid, a path, a covariance or
particles into what the scene draws (a solid, a polyline, a point cloud) on the plane
``z = 0`` of the element's frame (its ``position``/``rotation``, if given, place that plane;
an ellipse's ``position`` is its centre [x, y] on the plane, as in the drawing panel).

Importing this module registers the classes in ``ejsrl.world.scene.NODE_KINDS``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ejsrl.world.scene import NODE_KINDS, Node, Part

__all__ = ["VehicleNode", "LaserNode", "OccupancyNode", "PathNode", "EllipseNode", "ParticlesNode"]


def _pose(value: Any) -> np.ndarray:
    p = np.asarray(value, dtype=float).reshape(-1)
    if p.shape[0] < 3:
        raise ValueError(f"a pose is [x, y, theta], got {p.shape[0]} numbers")
    return p[:3]


def _xy(value: Any, what: str) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.ndim == 1 and a.shape[0] in (2, 3):
        a = a.reshape(1, -1)
    if a.ndim != 2 or a.shape[1] not in (2, 3):
        raise ValueError(f"{what} must be an N x 2 or N x 3 array, but has shape {a.shape}")
    return a[:, :2]


def _lift(xy: np.ndarray, z: float) -> np.ndarray:
    return np.column_stack((xy, np.full(len(xy), float(z))))


def _prism(outline: np.ndarray, z0: float, z1: float) -> Part:
    """A prism over a convex outline (k, 2) from z0 to z1 (fan-triangulated caps)."""
    k = len(outline)
    v = np.vstack((_lift(outline, z0), _lift(outline, z1)))
    (ax, ay), (bx, by) = outline[1] - outline[0], outline[2] - outline[0]
    if ax * by - ay * bx < 0:  # make it counter-clockwise
        v = np.vstack((_lift(outline[::-1], z0), _lift(outline[::-1], z1)))
    faces = [[0, j + 1, j] for j in range(1, k - 1)] + [[k, k + j, k + j + 1] for j in range(1, k - 1)]
    for j in range(k):
        a, b = j, (j + 1) % k
        faces += [[a, b, k + b], [a, k + b, k + a]]
    return Part(v, np.array(faces), None)


class _Derived(Node):
    """A node whose drawn ``points`` (or pose) follow from its own properties."""

    SOURCES: tuple[str, ...] = ()

    def __init__(self, name: str, **kw: Any) -> None:
        super().__init__(name, **kw)
        self.props["points"] = self._points()

    def set(self, **values: Any) -> bool:
        changed = super().set(**values)
        if changed and any(k in values for k in self.SOURCES):
            self.props["points"] = self._points()
        return changed

    def _points(self) -> np.ndarray:  # pragma: no cover - every subclass has its own
        return np.zeros((0, 3))


class VehicleNode(Node):
    """A vehicle at ``pose`` [x, y, theta]: a prism ``height`` high over its footprint (a
    triangle ``length`` x ``breadth`` pointing along x, or ``footprint`` N x 2 in its own
    frame), turned and placed by the pose on the element's plane."""

    kind = "vehicle"
    GEOMETRY_PROPS = ("length", "breadth", "height", "footprint")

    def __init__(self, name: str, **kw: Any) -> None:
        super().__init__(name, **kw)
        self._base = self.T_parent_local.copy()
        self._place()

    def set(self, **values: Any) -> bool:
        base = values.pop("T_parent_local", None)
        changed = super().set(**values)
        if base is not None:
            base = np.asarray(base, dtype=float)
            if not np.array_equal(base, self._base):
                self._base = base.copy()
                changed = True
        if changed and (base is not None or "pose" in values):
            self._place()
        return changed

    def _place(self) -> None:
        x, y, th = _pose(self.props["pose"])
        T = np.eye(4)
        T[:2, :2] = [[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]]
        T[:2, 3] = (x, y)
        super().set(T_parent_local=self._base @ T)

    def _make_parts(self) -> list[Part]:
        p = self.props
        if p.get("footprint") is not None:
            outline = _xy(p["footprint"], "a vehicle's footprint")
        else:
            L = float(p["length"])
            b = 0.5 * L if p.get("breadth") is None else float(p["breadth"])
            outline = np.array([[0.6 * L, 0.0], [-0.4 * L, 0.5 * b], [-0.4 * L, -0.5 * b]])
        return [_prism(outline, 0.0, float(p["height"]))]


class LaserNode(_Derived):
    """A laser scan from ``pose``: a ray from the sensor to the end of each beam (``ranges``
    at ``angles`` from the heading, default evenly over ``fov``), ``z`` above the plane."""

    kind = "laser"
    SOURCES = ("pose", "ranges", "angles", "fov", "z")

    def _points(self) -> np.ndarray:
        from ejsrl.view._drawing_mobile import laser_points

        p = self.props
        if p.get("ranges") is None:
            return np.zeros((0, 3))
        pose = _pose(p["pose"])
        ends = laser_points(pose, p["ranges"], p.get("angles"), float(p["fov"]))
        star = np.empty((2 * len(ends), 2))  # sensor, end, sensor, end...: every ray in one line
        star[0::2] = pose[:2]
        star[1::2] = ends
        return _lift(star, float(p["z"]))


class PathNode(Node):
    """A path through ``points`` (N x 2 points or N x 3 poses), ``z`` above the plane: the
    node holds them as given lifted to N x 3 at ``z`` (what the scene draws), so an
    unchanged path is not sent again."""

    kind = "path"

    def __init__(self, name: str, **kw: Any) -> None:
        kw["points"] = self._lifted(kw.get("points", self.DEFAULTS["points"]), kw.get("z", self.DEFAULTS["z"]))
        super().__init__(name, **kw)

    def set(self, **values: Any) -> bool:
        if "points" in values or "z" in values:
            values["points"] = self._lifted(values.get("points", self.props["points"]), values.get("z", self.props["z"]))
        return super().set(**values)

    def _lifted(self, rows: Any, z: Any) -> np.ndarray:
        """The rows' x and y (N, 2) with ``z`` as a third column: (N, 3)."""
        if rows is None:
            return np.zeros((0, 3))
        return _lift(_xy(rows, f"a {self.kind}'s points"), float(z))


class EllipseNode(_Derived):
    """The ``confidence`` ellipse of the 2 x 2 (top-left) ``covariance`` about ``position`` [x, y],
    drawn ``scale`` times larger, ``z`` above the plane."""

    kind = "ellipse"
    SOURCES = ("position", "covariance", "confidence", "scale", "z")

    def _points(self) -> np.ndarray:
        from .drawing import ellipse_points

        p = self.props
        if p.get("covariance") is None:
            return np.zeros((0, 3))
        P = np.asarray(p["covariance"], dtype=float)
        if P.ndim != 2 or P.shape[0] != P.shape[1] or P.shape[0] < 2:
            raise ValueError(f"a covariance must be a square matrix, 2 x 2 or larger, but has shape {P.shape}")
        s = float(p["scale"])
        c = np.asarray(p["position"], dtype=float).reshape(-1)[:2]
        return _lift(ellipse_points(s * s * P[:2, :2], c, confidence=float(p["confidence"])), float(p["z"]))


class ParticlesNode(PathNode):
    """A point at each row of ``points`` (N x 2 or N x 3 poses), ``z`` above the plane."""

    kind = "particles"


class OccupancyNode(Node):
    """The occupied cells of ``grid`` (an ``ejsrl.mobile`` grid, or an H x W array with
    ``cellsize`` and ``origin``) as blocks ``height`` high."""

    kind = "occupancy"
    GEOMETRY_PROPS = ("grid", "cellsize", "origin", "height")

    def set(self, **values: Any) -> bool:
        g = values.get("grid")
        if g is not None and hasattr(g, "grid") and hasattr(g, "cellsize"):  # a grid object: its cells, copied
            values.update(grid=np.array(g.grid, dtype=float), cellsize=float(g.cellsize),
                          origin=tuple(float(v) for v in np.asarray(g.origin).reshape(2)))
        elif g is not None:
            values["grid"] = np.array(g, dtype=float)
        return super().set(**values)

    def _make_parts(self) -> list[Part]:
        p = self.props
        if p.get("grid") is None:
            return []
        g = np.asarray(p["grid"], dtype=float)
        if g.ndim != 2:
            raise ValueError(f"an occupancy grid must be an H x W array, got shape {g.shape}")
        rows, cols = np.nonzero(g >= 0.5)
        if not len(rows):
            return []
        s = float(p["cellsize"])
        ox, oy = (float(v) for v in np.asarray(p["origin"], dtype=float).reshape(2))
        h = float(p["height"])
        corners = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (0.0, 1.0)])
        faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
        centres = np.column_stack((ox + s * cols, oy + s * rows, np.zeros(len(rows))))
        v = (corners * (s, s, h))[None, :, :] + centres[:, None, :]
        f = faces[None, :, :] + 8 * np.arange(len(rows))[:, None, None]
        return [Part(v.reshape(-1, 3), f.reshape(-1, 3), None)]


NODE_KINDS.update({cls.kind: cls for cls in (VehicleNode, LaserNode, OccupancyNode, PathNode, EllipseNode, ParticlesNode)})
