"""The mobile-robot kinds of the 2D panel (issue #27): frame items of a ``vehicle``,
``laser``, ``occupancy``, ``path``, ``ellipse`` and ``particles`` (see
``ejsgen._spec2d_mobile`` for their properties).

Each becomes items of the kinds the panel already draws (polylines, segments, markers, an
image), so the browser side is unchanged. World units: metres and radians; sizes and
widths in pixels.
"""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from ejsrl.view._panel2d import encode_xy

__all__ = ["MOBILE_SHAPE_KINDS", "mobile_items", "vehicle_points", "laser_points", "grid_image"]

#: kind -> the properties it takes (besides name, visible, color, drag)
MOBILE_SHAPE_KINDS: dict[str, tuple[str, ...]] = {
    "vehicle": ("pose", "length", "breadth", "footprint", "fill", "width"),
    "laser": ("pose", "ranges", "angles", "fov", "max_range", "size", "width"),
    "occupancy": ("grid", "cellsize", "origin"),
    "path": ("points", "width"),
    "ellipse": ("position", "covariance", "confidence", "scale", "fill", "width"),
    "particles": ("points", "size"),
}


def _pose(value: Any, what: str) -> np.ndarray:
    p = np.asarray(value, dtype=float).reshape(-1)
    if p.shape[0] < 3:
        raise ValueError(f"{what} must be [x, y, theta], got {p.shape[0]} numbers")
    return p[:3]


def _rows(value: Any, what: str, cols: tuple[int, ...]) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.ndim == 1 and a.shape[0] in cols:
        a = a.reshape(1, -1)
    if a.ndim != 2 or a.shape[1] not in cols:
        need = " or ".join(f"N x {c}" for c in cols)
        hint = " (a 2 x N array: transpose it, .T)" if a.ndim == 2 and a.shape[0] in cols else ""
        raise ValueError(f"{what} must be an {need} array, but has shape {a.shape}{hint}")
    return a


def vehicle_points(pose: Any, length: float = 1.0, breadth: float | None = None, footprint: Any = None) -> np.ndarray:
    """The outline (k, 2) of a vehicle at ``pose`` (x, y, theta) in the world: ``footprint``
    (N, 2) in its own frame (x forward), or a triangle of ``length`` x ``breadth`` (m) with
    its nose along the heading, 0.6 of the length ahead of the pose."""
    x, y, th = _pose(pose, "a vehicle's pose")
    if footprint is None:
        b = 0.5 * length if breadth is None else float(breadth)
        body = np.array([[0.6 * length, 0.0], [-0.4 * length, 0.5 * b], [-0.4 * length, -0.5 * b]])
    else:
        body = _rows(footprint, "a vehicle's footprint", (2,))
    c, s = math.cos(th), math.sin(th)
    return body @ np.array([[c, s], [-s, c]]) + (x, y)


def laser_points(pose: Any, ranges: Any, angles: Any = None, fov: float = math.pi) -> np.ndarray:
    """The points (n, 2) a scan's beams end at in the world: beam i from the sensor at
    ``pose`` along ``theta + angles[i]`` (default: n angles evenly over ``fov``, as
    :class:`ejsrl.mobile.LaserScanner`'s), ``ranges[i]`` metres away."""
    x, y, th = _pose(pose, "a laser's pose")
    r = np.asarray(ranges, dtype=float).reshape(-1)
    if angles is None:
        a = np.linspace(-fov / 2, fov / 2, r.size) if r.size > 1 else np.zeros(r.size)
    else:
        a = np.asarray(angles, dtype=float).reshape(-1)
        if a.size != r.size:
            raise ValueError(f"a laser has {r.size} ranges but {a.size} angles")
    a = a + th
    return np.column_stack((x + r * np.cos(a), y + r * np.sin(a)))


def grid_image(grid: Any, cellsize: float = 1.0, origin: Any = (0.0, 0.0), rgb: tuple[float, float, float] = (0.29, 0.31, 0.34)) -> tuple[np.ndarray, tuple[float, float, float, float]]:
    """An occupancy grid as a picture (H, W, 3) uint8, its top row the largest y, and
    where it lies ``(x0, x1, y0, y1)`` (the cells' outer edges, m). ``grid``: an
    ``ejsrl.mobile`` grid (its ``cellsize`` and ``origin``) or an (H, W) array, row 0 at
    the lowest y; booleans (True: obstacle) or values 0-1 (free to occupied) shaded from
    white to ``rgb``."""
    if hasattr(grid, "grid") and hasattr(grid, "cellsize"):
        cellsize, origin, grid = grid.cellsize, grid.origin, grid.grid
    g = np.asarray(grid)
    if g.ndim != 2 or g.size == 0:
        raise ValueError(f"an occupancy grid must be an H x W array, got shape {g.shape}")
    v = np.clip(np.nan_to_num(g.astype(float), nan=0.5), 0.0, 1.0)[::-1]
    white = np.ones(3)
    img = np.round(255 * (white + v[..., None] * (np.asarray(rgb, dtype=float) - white))).astype(np.uint8)
    ox, oy = (float(t) for t in np.asarray(origin, dtype=float).reshape(2))
    s = float(cellsize)
    rows, cols = g.shape
    return img, (ox - s / 2, ox + s / 2 + (cols - 1) * s, oy - s / 2, oy + s / 2 + (rows - 1) * s)


def mobile_items(kind: str, name: str, p: dict[str, Any], color: str | None, css: Callable[[Any, str | None], str | None],
                 png: Callable[[Any], str]) -> list[dict[str, Any]]:
    """The frame items of a mobile kind: ``p`` its properties' values now, ``color`` its
    CSS colour (None: the kind's), ``css`` turns a colour value into CSS, ``png`` an image
    into a data URL (cached by the caller). The first item carries the drag handle."""
    if kind == "vehicle":
        pose = _pose(p["pose"], f"the pose of {name}")
        pts = vehicle_points(pose, float(p.get("length", 1.0)), p.get("breadth"), p.get("footprint"))
        # the pose's position first, then a break: a drag takes the first point
        xy = np.vstack([pose[:2], [np.nan, np.nan], pts])
        fill = css(p.get("fill"), None) or ("rgba(73,80,87,0.25)" if color is None else None)
        return [{"t": "polyline", "xy": encode_xy(xy), "stroke": color or "#343a40", "width": float(p.get("width", 1.5)),
                 "dash": None, "closed": True, "fill": fill}]
    if kind == "laser":
        pose = _pose(p["pose"], f"the pose of {name}")
        ranges = np.asarray(p["ranges"], dtype=float).reshape(-1)
        ends = laser_points(pose, ranges, p.get("angles"), float(p.get("fov", math.pi)))
        start = np.broadcast_to(pose[:2], ends.shape)
        stroke = color or "#f03e3e"
        items = [{"t": "segments", "xy": encode_xy(np.hstack([start, ends])), "stroke": stroke, "width": float(p.get("width", 1.0))}]
        mr = p.get("max_range")
        hit = np.isfinite(ranges) if mr is None else np.isfinite(ranges) & (ranges < float(mr))
        items.append({"t": "markers", "xy": encode_xy(ends[hit].reshape(-1, 2)), "shape": "circle", "size": float(p.get("size", 4)),
                      "fill": stroke, "stroke": None})
        return items
    if kind == "occupancy":
        rgb = (0.29, 0.31, 0.34)
        if color is not None:
            from ejsrl.world.colors import to_rgb

            try:
                rgb = tuple(to_rgb(color))  # type: ignore[assignment]
            except Exception:  # noqa: BLE001 - an rgb() string from a triple: the default
                pass
        img, (x0, x1, y0, y1) = grid_image(p["grid"], float(p.get("cellsize", 1.0)), p.get("origin", (0.0, 0.0)), rgb)
        return [{"t": "image", "x0": x0, "y0": y0, "x1": x1, "y1": y1, "src": png(img), "smooth": False}]
    if kind == "path":
        pts = _rows(p["points"], f"the points of {name}", (2, 3))[:, :2]
        stroke = color or "#2f9e44"
        items = [{"t": "polyline", "xy": encode_xy(pts), "stroke": stroke, "width": float(p.get("width", 2.0)),
                  "dash": None, "closed": False, "fill": None}]
        if len(pts):
            items.append({"t": "markers", "xy": encode_xy(pts[:1]), "shape": "circle", "size": 8.0, "fill": stroke, "stroke": None})
            items.append({"t": "markers", "xy": encode_xy(pts[-1:]), "shape": "cross", "size": 12.0, "fill": None,
                          "stroke": stroke, "width": 2.5})
        return items
    if kind == "ellipse":
        from ejsrl.mobile.drawing import ellipse_points

        P = np.asarray(p["covariance"], dtype=float)
        if P.ndim != 2 or P.shape[0] != P.shape[1] or P.shape[0] < 2:
            raise ValueError(f"the covariance of {name} must be a square matrix, 2 x 2 or larger, but has shape {P.shape}")
        centre = np.asarray(p["position"], dtype=float).reshape(-1)[:2]
        scale = float(p.get("scale", 1.0))
        pts = ellipse_points(scale * scale * P[:2, :2], centre, confidence=float(p.get("confidence", 0.95)))
        return [{"t": "polyline", "xy": encode_xy(pts), "stroke": color or "#1c7ed6", "width": float(p.get("width", 1.5)),
                 "dash": None, "closed": True, "fill": css(p.get("fill"), None)}]
    if kind == "particles":
        pts = _rows(p["points"], f"the points of {name}", (2, 3))[:, :2]
        return [{"t": "markers", "xy": encode_xy(pts), "shape": "circle", "size": float(p.get("size", 3)),
                 "fill": color or "#e8590c", "stroke": None}]
    raise ValueError(f"unknown mobile kind {kind!r}")  # pragma: no cover - Shape2D refuses it
