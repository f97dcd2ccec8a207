"""The browser's camera of a 3D view: where the spec's ``view`` and ``set_view()`` put it.

:class:`ViewCamera` turns the requests the world holds (``ejsrl.world.view3d``) into a camera
pose (:class:`CameraPose`) and sets it on viser client cameras:

- when a tab connects (a reload too): the whole pose, so every tab of a simulation sees what
  the spec and its code asked for;
- when the request changes (``set_view()``, a ``view`` property bound to an expression): the
  whole pose, for every tab;
- every frame while following an object: the target (the object's position) and, with
  ``follow_offset``, the position (the object's position plus the offset the camera had);
- on Restore view: the spec's pose again.

Between those the user orbits and zooms freely. A world without a ``view`` node keeps the
framed oblique first view (:func:`ejsrl.view._framing.frame_camera`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ejsrl.view._framing import VIEW_ASPECT, VIEW_FOV, frame_camera, framed_points, framing_view
from ejsrl.world.view3d import VIEW_KIND, check_up, preset_direction, view_node

__all__ = ["CameraPose", "ViewCamera", "resolve", "apply_pose"]

log = logging.getLogger("ejsrl.view")

_Z_UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class CameraPose:
    """A camera of the 3D view: ``position`` and ``look_at`` (3,) in metres (world), ``up`` (3,)
    the direction shown upwards, ``fov`` the vertical field of view in radians; ``offset`` (3,)
    ``position - look_at`` kept while following with an offset (else None)."""

    position: np.ndarray
    look_at: np.ndarray
    up: np.ndarray
    fov: float
    follow: str | None = None
    offset: np.ndarray | None = None


def _element_places_camera(view: Any) -> bool:
    """Whether the spec's ``view`` element gives the camera's ``position`` (or a transform)."""
    from ejsrl.world.binding import scene_elements

    stack = list(scene_elements(list(view or [])))
    while stack:
        e = stack.pop()
        if e.kind == VIEW_KIND:
            return e.position is not None or e.transform is not None
        stack.extend(e.children)
    return False


def _vec(value: Any) -> np.ndarray | None:
    if value is None:
        return None
    v = np.asarray(value, dtype=float).reshape(-1)
    return v if v.shape == (3,) and np.all(np.isfinite(v)) else None


def resolve(world: Any, node: Any, *, spec_position: bool, lock: Any = None) -> CameraPose:
    """The camera that ``node`` (the world's ``view`` node) asks for now: its spec properties,
    overridden by what code asked (its ``commanded`` property). ``spec_position``: the spec
    gives the camera's position (the node's pose); else it is framed along the preset."""
    props = dict(node.props)
    asked = dict(props.get("commanded") or {})
    position = node.T_world()[:3, 3].copy() if spec_position else None
    preset = props.get("preset")
    if "position" in asked:
        position, preset = np.asarray(asked["position"], dtype=float), None
    if "preset" in asked:
        position, preset = None, asked["preset"]
    get = lambda key: asked[key] if key in asked else props.get(key)  # noqa: E731
    follow = get("follow") or None
    target = _vec(get("target"))
    if follow and follow in world.nodes:
        target = world[follow].T_world()[:3, 3].copy()
    fov_deg = get("fov")
    fov = math.radians(float(fov_deg)) if fov_deg is not None and 1.0 <= float(fov_deg) <= 170.0 else float(VIEW_FOV)
    up = _vec(get("up"))
    if position is not None:
        position = np.asarray(position, dtype=float)
        if target is None:
            points = framed_points(world, lock)
            target = (points.min(axis=0) + points.max(axis=0)) / 2.0 if points is not None else np.zeros(3)
        if up is None:
            up = _Z_UP
    else:
        try:
            view_from, preset_up = preset_direction(str(preset or "iso"))
        except KeyError:
            view_from, preset_up = preset_direction("iso")
        if up is None:
            up = preset_up
        if check_up(up, -view_from) is not None:
            up = preset_up
        points = framed_points(world, lock)
        if points is None:
            points = np.zeros((1, 3)) if target is None else target.reshape(1, 3)
        if target is not None:
            points = np.vstack([points, target])
        position, target = framing_view(points, fov=fov, aspect=VIEW_ASPECT, view_from=view_from, up=up, center=target)
    if check_up(up, target - position) is not None:  # an expression or a call made it degenerate: the nearest sensible up
        if np.linalg.norm(target - position) < 1e-12:
            position = target + np.array([0.0, -1.0, 0.0])
        up = _Z_UP if check_up(_Z_UP, target - position) is None else np.array([0.0, 1.0, 0.0])
    offset = (position - target) if follow and get("follow_offset") else None
    return CameraPose(position, target, np.asarray(up, dtype=float), fov, follow, offset)


def apply_pose(camera: Any, pose: CameraPose, *, whole: bool = True) -> None:
    """Set ``pose`` on ``camera`` (a viser client's camera): up and fov too if ``whole``.

    viser checks each setting against the pose it holds (zeros until the tab reports its
    camera) and refuses one that would make its position equal its look-at point, so the
    position and the look-at point go first, in the order that avoids that, then up."""
    position = tuple(float(v) for v in pose.position)
    look_at = tuple(float(v) for v in pose.look_at)
    held = np.asarray(camera._state.look_at if hasattr(camera, "_state") else camera.look_at, dtype=float)
    if np.allclose(held, position):
        camera.look_at = look_at
        camera.position = position
    else:
        camera.position = position
        camera.look_at = look_at
    if whole:
        camera.up_direction = tuple(float(v) for v in pose.up)
        camera.fov = float(pose.fov)


class ViewCamera:
    """The camera of one view of ``app`` (its world, its lock, its ``view`` elements)."""

    def __init__(self, app: Any) -> None:
        self.app = app
        self._spec_position = _element_places_camera(getattr(app, "view", None))
        #: the rev of the view node last shown, and the pose resolved then
        self._rev: int | None = None
        self.pose: CameraPose | None = None
        #: the world's view node (or None) and the number of nodes the world had when it was looked for
        self._found: tuple[Any, int] | None = None

    def _world(self) -> Any:
        try:
            return getattr(self.app, "world", None)
        except RuntimeError:
            return None

    def _node(self, world: Any) -> Any:
        """The world's ``view`` node, looked for again only when the world's nodes change in number
        (``set_view`` adds one to a scene without it): a frame costs no walk through the world."""
        count = len(world.nodes)
        if self._found is None or self._found[1] != count or (self._found[0] is not None and self._found[0].world is not world):
            self._found = (view_node(world), count)
        return self._found[0]

    def _resolve(self) -> CameraPose | None:
        world = self._world()
        if world is None:
            return None
        node = self._node(world)
        if node is None:
            return None
        self._rev = node.rev
        self.pose = resolve(world, node, spec_position=self._spec_position)
        return self.pose

    def show(self, cameras: list[Any]) -> None:
        """Set the whole camera on ``cameras`` (a tab that connects, Restore view); the caller holds the model lock.

        Without a ``view`` node: the framed first view."""
        pose = self._resolve()
        for camera in cameras:
            try:
                if pose is None:
                    frame_camera(camera, self._world())
                else:
                    apply_pose(camera, pose)
            except Exception:
                log.debug("setting a client's camera failed", exc_info=True)

    def on_frame(self, cameras: list[Any]) -> None:
        """A frame: the whole camera if what the world asks for changed, else the followed
        object's moves (the caller holds the model lock)."""
        world = self._world()
        node = self._node(world) if world is not None else None
        if node is None:
            return
        if node.rev != self._rev:
            self.show(cameras)
            return
        pose = self.pose
        if pose is None or not pose.follow or pose.follow not in world.nodes:
            return
        at = world[pose.follow].T_world()[:3, 3]
        moved = CameraPose(at + pose.offset if pose.offset is not None else pose.position, at.copy(), pose.up, pose.fov,
                           pose.follow, pose.offset)
        for camera in cameras:
            try:
                if pose.offset is not None:
                    apply_pose(camera, moved, whole=False)
                else:
                    camera.look_at = tuple(float(v) for v in at)
            except Exception:
                log.debug("following with a client's camera failed", exc_info=True)
        self.pose = moved
