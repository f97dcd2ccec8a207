"""The mobile-robot kinds of the 2D drawing panel (issue #27): ``vehicle``, ``laser``,
``occupancy``, ``path``, ``ellipse`` and ``particles``, as pydantic models, and how their
own properties are compiled (:func:`compile_prop`).

They draw what :mod:`ejsrl.mobile` computes, in world units (m, rad): a vehicle at a pose
``[x, y, theta]`` with its footprint, a laser scan's rays and returns, an occupancy grid,
a planned path, a covariance ellipse and a particle filter's particles. The 3D scene has
kinds of the same names (:mod:`ejsrl.world.kinds`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Callable, Union

from pydantic import Field

from ejsgen._shapes import infer_shape
from ejsgen.errors import SpecError
from ejsgen.spec import ColorValue, Expr, NumOrExpr, VecOrExpr

if TYPE_CHECKING:
    from ejsgen._view_compile import ViewCompiler
    from ejsgen.yamlload import Path_

from ejsgen._spec2d import _Shape

__all__ = ["MOBILE_MODELS", "compile_prop", "MOBILE_PROPS"]

Points = Union[str, list[list[Union[float, int, str]]]]


class VehicleEl(_Shape):
    """A mobile robot at a pose [x, y, theta]: a triangle pointing along its heading (or the footprint you give), turned and placed by the pose; dragging it moves [x, y]."""

    pose: VecOrExpr
    """[x, y, theta] (m, m, rad), or an expression giving them (e.g. a vehicle's state x)."""
    length: NumOrExpr = 1.0
    """Length from tail to nose in metres (of the triangle drawn without a footprint)."""
    breadth: NumOrExpr | None = None
    """Width of the triangle in metres (default: half the length)."""
    footprint: Points | None = None
    """The outline in the vehicle's own frame (x forward, y to its left), N x 2 in metres: a list of [x, y] or an expression; instead of the triangle."""
    fill: ColorValue | None = None
    """Fill colour (default: a light tint of its colour)."""
    width: NumOrExpr = 1.5
    """Line width in pixels."""


class LaserEl(_Shape):
    """A laser (range) scan seen from a sensor pose: a ray to each return and a dot where a beam hit something (beams at max_range hit nothing: ray only)."""

    pose: VecOrExpr
    """The sensor's pose [x, y, theta] (m, m, rad)."""
    ranges: Union[str, list[Union[float, int, str]]]
    """The ranges (n,) in metres, one per beam: an expression (e.g. scanner.scan(x)) or a list."""
    angles: Union[str, list[Union[float, int, str]], None] = None
    """Each beam's angle from the heading (n,) in radians (default: n beams evenly over fov, as LaserScanner's)."""
    fov: NumOrExpr = math.pi
    """Field of view in radians, centred on the heading (without angles)."""
    max_range: NumOrExpr | None = None
    """A range at or beyond it is no return: its ray is drawn without a dot (default: every beam hit)."""
    size: NumOrExpr = 4
    """Diameter of the dots in pixels."""
    width: NumOrExpr = 1.0
    """Width of the rays in pixels."""


class OccupancyEl(_Shape):
    """An occupancy grid: obstacle cells filled with its colour, free cells white (a grid of probabilities or costs in greys, 0 white to 1 its colour)."""

    grid: Expr
    """An ejsrl.mobile BinaryOccupancyGrid or OccupancyGrid (its cell size and origin used), or an H x W array (row 0 at the lowest y)."""
    cellsize: NumOrExpr = 1.0
    """Cell side in metres (for an array)."""
    origin: VecOrExpr = Field(default_factory=lambda: [0.0, 0.0])
    """The centre [x, y] of cell [0, 0] in metres (for an array)."""


class PathEl(_Shape):
    """A path: a line through N x 2 points or N x 3 poses (a planner's answer), with a dot at its start and a cross at its goal."""

    points: Points
    """The way points, N x 2 (or N x 3 poses, their x and y drawn): a list or an expression."""
    width: NumOrExpr = 2.0
    """Line width in pixels."""


class EllipseEl(_Shape):
    """A covariance ellipse: where a 2-D Gaussian about position holds confidence of its probability (EKF uncertainty)."""

    position: VecOrExpr
    """Its centre [x, y] (the estimate)."""
    covariance: Union[str, list[list[Union[float, int, str]]]]
    """The covariance, 2 x 2 (m²), or larger (a pose's or an EKF's: its top-left 2 x 2)."""
    confidence: NumOrExpr = 0.95
    """The probability it holds, between 0 and 1 (chi-squared with 2 degrees of freedom)."""
    scale: NumOrExpr = 1.0
    """Drawn this many times larger (a small uncertainty made visible)."""
    fill: ColorValue | None = None
    """Fill colour (default: none)."""
    width: NumOrExpr = 1.5
    """Line width in pixels."""


class ParticlesEl(_Shape):
    """A particle filter's particles: a dot at each row of an N x 2 (positions) or N x 3 (poses) array."""

    points: Points
    """The particles, N x 2 or N x 3 (x, y, theta: x and y drawn)."""
    size: NumOrExpr = 3
    """Dot diameter in pixels."""


#: the mobile kinds (added to ``ejsgen._spec2d.CHILD_MODELS``)
MOBILE_MODELS: dict[str, type[_Shape]] = {
    "vehicle": VehicleEl,
    "laser": LaserEl,
    "occupancy": OccupancyEl,
    "path": PathEl,
    "ellipse": EllipseEl,
    "particles": ParticlesEl,
}

#: the properties compiled here (the others, width, size, fill, as every 2D kind's)
MOBILE_PROPS = {"pose", "length", "breadth", "footprint", "ranges", "angles", "fov", "max_range", "grid",
                "cellsize", "origin", "points", "covariance", "confidence", "scale"}


def _expression(vc: "ViewCompiler", value: str, path: "Path_", what: str, fits: Callable[[tuple[int, ...]], bool],
                need: str, hint: Callable[[tuple[int, ...]], str]) -> Any:
    """An expression property (``E.Dynamic``) whose shape, when known, ``fits``; else the
    error '{what} must be {need}, but ... has shape ...' with ``hint(shape)``; None after an error."""
    res = vc.c.expr_source(path, what)
    if res is None:
        return None
    shape = infer_shape(res[1], vc.c.var_shapes)
    if shape is not None and not fits(shape):
        vc.c.errors.append(SpecError(vc.c.loc(path), f"{what} must be {need}, but '{value}' has shape {shape}",
                                         hint(shape) or vc.c.text_hint(value)))
        return None
    return vc.dynamic(path, "", what, value)


def compile_prop(vc: "ViewCompiler", kind: str, prop: str, value: Any, path: "Path_", what: str) -> tuple[bool, Any]:
    """``(handled, compiled value)`` of a mobile kind's own property (``handled`` False:
    the 2D compiler's generic rules apply); a value None after an error was recorded."""
    c = vc.c
    if prop not in MOBILE_PROPS or kind not in MOBILE_MODELS:
        return False, None
    if prop == "pose":
        return True, vc.vector(value, path, "", what, 3)
    if prop in ("length", "breadth", "fov", "max_range", "cellsize", "scale"):
        if not isinstance(value, str) and not value > 0:
            c.errors.append(SpecError(c.loc(path), f"{what} must be above 0, got {value}"))
            return True, None
        return True, vc.number(value, path, "", what)
    if prop == "confidence":
        if not isinstance(value, str) and not 0 < value < 1:
            c.errors.append(SpecError(c.loc(path), f"{what} is a probability between 0 and 1 (not included), got {value}",
                                      "0.95 draws the 95 % ellipse"))
            return True, None
        return True, vc.number(value, path, "", what)
    if prop == "origin":
        return True, vc.vector(value, path, "", what, 2)
    if prop in ("ranges", "angles"):
        if isinstance(value, str):
            return True, _expression(vc, value, path, what, lambda sh: len(sh) == 1, "a vector (n,), one per beam",
                                     lambda sh: "a scan's ranges: scanner.scan(x), shape (n,)")
        return True, vc.vector(value, path, "", what, None)
    if prop == "grid":
        return True, _expression(vc, value, path, what, lambda sh: len(sh) == 2, "an occupancy grid or an H x W array",
                                 lambda sh: "BinaryOccupancyGrid(array, cellsize=..., origin=...) from ejsrl.mobile, or a 2-D array")
    if prop == "covariance":
        if isinstance(value, str):
            return True, _expression(vc, value, path, what, lambda sh: len(sh) == 2 and sh[0] == sh[1] >= 2,
                                     "a square covariance matrix, 2 x 2 or larger", lambda sh: "an EKF's: ekf.P_est (its top-left 2 x 2 is drawn)")
        if not (isinstance(value, list) and len(value) >= 2 and all(isinstance(r, list) and len(r) == len(value) for r in value)):
            c.errors.append(SpecError(c.loc(path), f"{what} must be a square matrix [[sxx, sxy], [sxy, syy]] or an expression"))
            return True, None
        return True, vc.matrix(value, path, "", what, (len(value), len(value)))
    # footprint (N x 2), path and particle points (N x 2 or N x 3)
    cols = (2,) if prop == "footprint" else (2, 3)
    need = "an N x 2 array of [x, y] rows" if cols == (2,) else "an N x 2 (positions) or N x 3 (poses) array"
    if isinstance(value, str):
        return True, _expression(vc, value, path, what, lambda sh: len(sh) == 2 and sh[1] in cols, need,
                                 lambda sh: "a 2 x N array: transpose it with .T" if len(sh) == 2 and sh[0] in cols else "")
    widths = {len(r) for r in value}
    if len(widths) != 1 or not widths <= set(cols):
        c.errors.append(SpecError(c.loc(path), f"{what} must be {need}: every row [x, y]" + ("" if cols == (2,) else " or [x, y, theta]")))
        return True, None
    return True, vc.matrix(value, path, "", what, None)
