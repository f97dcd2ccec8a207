"""The first view of a scene: a camera that frames what the world shows.

:func:`scene_bounds` measures the world's content (and its floors, the grids);
:func:`framing_view` places the nearest camera, looking from :data:`VIEW_FROM` (or a
direction of the spec's ``view``: ``ejsrl.view._camera``), that sees a set of points; :func:`frame_camera` points a viser camera (a client's, when it connects)
at the content, grown by :data:`VIEW_MARGIN` for what moves about.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["scene_bounds", "framing_view", "framed_points", "frame_camera", "VIEW_FROM", "VIEW_FOV", "VIEW_ASPECT", "VIEW_MARGIN"]

#: the direction the initial camera looks from (towards -x, +y, down), and its vertical field of view
VIEW_FROM = np.array([1.0, -1.0, 0.75])
VIEW_FOV = np.radians(75.0)  # viser's default
#: the 3D view's width / height assumed (the canvas between the docked About and control panels)
VIEW_ASPECT = 0.7
#: how much larger than the content's box the view is, for what moves about (a pendulum
#: swings to the other side); grids (floors) are framed as they are
VIEW_MARGIN = 1.5

Box = tuple[np.ndarray, np.ndarray]


def scene_bounds(world: Any) -> tuple[Box | None, Box | None]:
    """``(content, floor)``: boxes ``(lo, hi)`` (corners (3,), metres) around what the world shows.

    ``content``: solids (boxes, meshes, robots ...), the points of lines, trails and point
    clouds, frames' axes, labels and cameras; ``floor``: the squares of grids. Invisible
    nodes do not count; a box is None when nothing is in it.
    """
    content: list[np.ndarray] = []
    floor: list[np.ndarray] = []
    tris, _rgb = world.triangles()
    if len(tris):
        content.append(tris.reshape(-1, 3))
    for node in world.walk():
        if not world.is_visible(node) or node.opacity <= 0.0:
            continue
        T = node.T_world()
        local: np.ndarray | None = None
        into = content
        if node.kind in ("line", "trail", "points"):
            local = np.asarray(node.props.get("points", np.zeros((0, 3))), dtype=float).reshape(-1, 3)
        elif node.kind == "frame":
            local = np.vstack([np.zeros(3), np.eye(3) * float(node.props.get("size", 0.2))])
        elif node.kind == "grid":
            h = float(node.props.get("size", 2.0)) / 2.0
            local = np.array([[-h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0], [h, -h, 0.0]])
            into = floor
        elif node.kind in ("text3d", "camera"):
            local = np.zeros((1, 3))
        if local is not None and len(local):
            into.append(local @ T[:3, :3].T + T[:3, 3])
    return _box(content), _box(floor)


def _box(points: list[np.ndarray]) -> Box | None:
    if not points:
        return None
    p = np.concatenate(points)
    p = p[np.all(np.isfinite(p), axis=1)]
    return (p.min(axis=0), p.max(axis=0)) if len(p) else None


def _corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def framing_view(
    points: np.ndarray,
    *,
    fov: float = VIEW_FOV,
    aspect: float = VIEW_ASPECT,
    view_from: np.ndarray = VIEW_FROM,
    up: np.ndarray = np.array([0.0, 0.0, 1.0]),
    center: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """``(position, look_at)`` of the nearest camera that sees all of ``points`` (N, 3), world, metres.

    The camera looks from the direction ``view_from`` (3,) (default :data:`VIEW_FROM`), with
    ``up`` (3,) up on screen, at ``center`` (3,) (default: the centre of the points' box); its
    distance is the least that keeps every point inside the vertical field of view ``fov``
    (radians) and the horizontal one given ``aspect`` (width / height), plus 5 %.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    if center is None:
        center = (pts.min(axis=0) + pts.max(axis=0)) / 2.0
    center = np.asarray(center, dtype=float)
    f = -np.asarray(view_from, dtype=float) / np.linalg.norm(view_from)  # the viewing direction
    r = np.cross(f, np.asarray(up, dtype=float))
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    tan_v = np.tan(fov / 2.0)
    tan_h = tan_v * aspect
    rel = pts - center
    # a point at rel is inside when |rel.r| <= tan_h (d + rel.f) and |rel.u| <= tan_v (d + rel.f)
    need = np.maximum(np.abs(rel @ r) / tan_h, np.abs(rel @ u) / tan_v) - rel @ f
    distance = max(float(need.max()) * 1.05, 0.2)
    return center - distance * f, center


def framed_points(world: Any, lock: Any = None) -> np.ndarray | None:
    """The corners (N, 3) a first view frames: the content's box grown by :data:`VIEW_MARGIN`
    about its centre, and the floors' boxes; None for a world with nothing to show.
    ``lock``: the model lock, held while the world is read."""
    if world is None:
        return None
    if lock is not None:
        with lock:
            content, floor = scene_bounds(world)
    else:
        content, floor = scene_bounds(world)
    corners = []
    if content is not None:
        lo, hi = content
        mid, half = (lo + hi) / 2.0, np.maximum((hi - lo) / 2.0, 0.05)
        corners.append(_corners(mid - VIEW_MARGIN * half, mid + VIEW_MARGIN * half))
    if floor is not None:
        corners.append(_corners(*floor))
    return np.concatenate(corners) if corners else None


def frame_camera(camera: Any, world: Any, lock: Any = None) -> None:
    """Point ``camera`` (a viser client's camera, or ``server.initial_camera``) at the world's content.

    The points of :func:`framed_points` are framed (:func:`framing_view`). A world with
    nothing to show leaves the camera where it is.
    """
    points = framed_points(world, lock)
    if points is None:
        return
    position, look_at = framing_view(points)
    camera.position = tuple(float(v) for v in position)
    camera.look_at = tuple(float(v) for v in look_at)
