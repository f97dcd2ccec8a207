"""The 3D view's camera as the world holds it: the spec's ``view`` element and ``set_view()``.

A scene's ``view`` element (``ejsrl.world.kinds``: kind ``view``) is a world node that is not
drawn. Its properties are what the spec asks for (``target``, ``up``, ``fov``, ``preset``,
``follow``, ``follow_offset``; its pose's translation is the camera's ``position``), written
by the scene binding like any element's. What code asked for with ``set_view()`` is kept
beside them, in the node's ``commanded`` property (None: nothing), so the panel's Restore view
button can drop it and go back to the spec's camera. Everything here belongs to the world,
and so to one simulation (one session): each tab of a class has its own camera; every tab
of one simulation, and a tab reloaded later, is shown the same one.

The browser side (``ejsrl.view._camera``) turns these requests into a camera: it frames the
scene for a preset and moves the camera each frame for ``follow``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["PRESETS", "ALIASES", "VIEW_KIND", "preset_direction", "view_node", "set_view", "drop_commanded", "check_up"]

#: the kind of the camera's world node
VIEW_KIND = "view"

#: preset -> (direction from the target to the camera, up on screen): square-on views of the
#: coordinate planes (front: the x-z plane with x to the right and z up) and the oblique one
#: the view had before cameras could be set (iso)
PRESETS: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "front": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
    "back": ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
    "right": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    "left": ((-1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    "top": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    "bottom": ((0.0, 0.0, -1.0), (0.0, 1.0, 0.0)),
    "iso": ((1.0, -1.0, 0.75), (0.0, 0.0, 1.0)),
}
#: other names of presets: the plane seen square-on
ALIASES: dict[str, str] = {"xz": "front", "yz": "right", "xy": "top"}


def preset_direction(name: str) -> tuple[np.ndarray, np.ndarray]:
    """``(from, up)`` of a preset (or alias): unit direction (3,) from the target to the camera, and up (3,)."""
    d, up = PRESETS[ALIASES.get(name, name)]
    v = np.asarray(d, dtype=float)
    return v / np.linalg.norm(v), np.asarray(up, dtype=float)


def check_up(up: np.ndarray, direction: np.ndarray) -> str | None:
    """Why ``up`` (3,) cannot be the screen's up when looking along ``direction`` (3,), or None."""
    nu, nd = float(np.linalg.norm(up)), float(np.linalg.norm(direction))
    if nu < 1e-12:
        return "up must not be [0, 0, 0]"
    if nd < 1e-12:
        return "the camera's position and target are the same point: it looks nowhere"
    if np.linalg.norm(np.cross(up / nu, direction / nd)) < 1e-6:
        return "up is parallel to the direction the camera looks in, so no direction on screen is up"
    return None


def view_node(world: Any) -> Any:
    """The world's ``view`` node (the first), or None."""
    for node in world.walk():
        if node.kind == VIEW_KIND:
            return node
    return None


def _vec3(value: Any, what: str) -> tuple[float, float, float]:
    v = np.asarray(value, dtype=float).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"set_view: {what} needs three finite numbers [x, y, z], got {value!r}")
    return (float(v[0]), float(v[1]), float(v[2]))


def set_view(
    world: Any,
    position: Any = None,
    target: Any = None,
    up: Any = None,
    fov: float | None = None,
    *,
    preset: str | None = None,
    follow: str | None = None,
    follow_offset: bool | None = None,
) -> None:
    """Ask the 3D view of ``world`` for a camera: what is given replaces what the spec (or an
    earlier call) asked for; what is left out (None) stays. ``position``, ``target``, ``up``:
    [x, y, z] (metres; up a direction); ``fov``: vertical, degrees; ``preset``: see
    :data:`PRESETS` (replaces ``position``, as ``position`` replaces a preset); ``follow``: a
    scene object's name, ``""`` to stop following. Bad values raise ``ValueError``.
    """
    from ejsrl.world.scene import NODE_KINDS

    asked: dict[str, Any] = {}
    if position is not None:
        asked["position"] = _vec3(position, "position")
    if target is not None:
        asked["target"] = _vec3(target, "target")
    if up is not None:
        asked["up"] = _vec3(up, "up")
        if np.linalg.norm(asked["up"]) < 1e-12:
            raise ValueError("set_view: up must not be [0, 0, 0]")
    if fov is not None:
        f = float(fov)
        if not (math.isfinite(f) and 1.0 <= f <= 170.0):
            raise ValueError(f"set_view: fov is the vertical field of view in degrees, 1 to 170; got {fov!r}")
        asked["fov"] = f
    if preset is not None:
        if str(preset) not in PRESETS and str(preset) not in ALIASES:
            import difflib

            close = difflib.get_close_matches(str(preset), [*PRESETS, *ALIASES], n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ValueError(f"set_view: unknown preset {preset!r} (presets: {', '.join([*PRESETS, *ALIASES])}){hint}")
        asked["preset"] = str(preset)
    if follow is not None:
        if follow != "":
            world[str(follow)]  # KeyError with a 'did you mean'
        asked["follow"] = str(follow) or None
    if follow_offset is not None:
        asked["follow_offset"] = bool(follow_offset)
    if "position" in asked and "preset" in asked:
        raise ValueError("set_view: give either a position or a preset, not both")
    node = view_node(world)
    if node is None:  # a scene without a view element: the camera is the framed default until code asks
        node = world.add(NODE_KINDS[VIEW_KIND](world.unique_name(VIEW_KIND)))
    commanded = dict(node.props.get("commanded") or {})
    if "position" in asked:
        commanded.pop("preset", None)
    if "preset" in asked:
        commanded.pop("position", None)
    commanded.update(asked)
    node.set(commanded=commanded)


def drop_commanded(world: Any) -> None:
    """Forget what code asked of the camera (the Restore view button): the spec's camera again."""
    node = view_node(world)
    if node is not None and node.props.get("commanded"):
        node.set(commanded=None)
