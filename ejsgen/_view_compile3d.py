"""Build-time checks of a scene's ``view`` element (the 3D view's camera).

What the runtime cannot show is refused at FILE:LINE:COL: a second ``view`` in a scene, an
unknown ``preset`` (with "did you mean"), a ``preset`` together with a ``position``, a
rotation or transform (a camera's orientation is its target and up), a field of view outside
1-170 degrees, an ``up`` of zero or along the direction the camera looks (when both are
constants), a camera standing on its target, and a ``follow`` that names no object of the
scene nor a robot's link (``arm.link3``; checked once the whole scene is known, with the
closest name as a hint).
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Any

import numpy as np

from ejsgen._suggest import closest, did_you_mean
from ejsgen.errors import SpecError
from ejsrl.world.view3d import ALIASES, PRESETS, check_up, preset_direction

if TYPE_CHECKING:
    from ejsgen._view_compile import ViewCompiler
    from ejsgen.validate import ViewItem

__all__ = ["check_view", "check_follows"]


def _const3(value: Any) -> np.ndarray | None:
    """A constant [x, y, z] (every item a number), else None (an expression)."""
    if isinstance(value, (list, tuple)) and len(value) == 3 and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        return np.asarray(value, dtype=float)
    return None


def check_view(vc: ViewCompiler, item: ViewItem, name: str) -> None:
    """Check one ``view`` element (its errors go to the compiler's list)."""
    c, p, path = vc.c, item.props, item.path
    views: list[tuple[Any, Any, str]] = vc.__dict__.setdefault("_views3d", [])
    if views:
        c.errors.append(SpecError(c.loc(path), "a scene has one camera: this is its second 'view'",
                                  "merge the two into one view element"))
    views.append((path, p, name))
    for key in ("rotation", "transform"):
        if getattr(p, key) is not None:
            c.errors.append(SpecError(c.loc(path + (key,)), f"a view has no {key}: the camera turns to its target",
                                      "give position, target and up"))
    preset = p.preset
    direction: np.ndarray | None = None
    if preset is not None:
        if preset not in PRESETS and preset not in ALIASES:
            names = [*PRESETS, *ALIASES]
            c.errors.append(SpecError(c.loc(path + ("preset",)), f"unknown preset '{preset}' (presets: {', '.join(names)})",
                                      did_you_mean(preset, names)))
        else:
            view_from, _up = preset_direction(preset)
            direction = -view_from
        if p.position is not None:
            c.errors.append(SpecError(c.loc(path + ("preset",)), "give a view either a position or a preset, not both",
                                      "a preset places the camera along its direction, framing the scene"))
    if isinstance(p.fov, (int, float)) and not isinstance(p.fov, bool) and not 1.0 <= float(p.fov) <= 170.0:
        c.errors.append(SpecError(c.loc(path + ("fov",)), f"fov is the vertical field of view in degrees, 1 to 170; got {p.fov}"))
    position, target, up = _const3(p.position), _const3(p.target), _const3(p.up)
    if position is not None and target is not None and p.follow is None:
        direction = target - position
        if np.linalg.norm(direction) < 1e-12:
            c.errors.append(SpecError(c.loc(path + ("target",)), "the camera's target is its position: it looks nowhere",
                                      "move the target or the position"))
            direction = None
    where = path + ("up",)
    if up is None and p.up is None and preset is None and direction is not None:
        up, where = np.array([0.0, 0.0, 1.0]), path  # the default up, which the spec did not write
    if up is not None:
        if np.linalg.norm(up) < 1e-12:
            why: str | None = "up must not be [0, 0, 0]"
        else:
            why = check_up(up, direction) if direction is not None else None
        if why is not None:
            looks = "" if direction is None else f" (it looks along [{', '.join(f'{v + 0.0:g}' for v in direction)}])"
            c.errors.append(SpecError(c.loc(where), f"{why}{looks}", _up_hint(direction)))
    if p.follow_offset and p.follow is None:
        c.errors.append(SpecError(c.loc(path + ("follow_offset",)), "follow_offset needs follow: the object whose offset the camera keeps"))
    if p.follow is not None and p.follow == name:
        c.errors.append(SpecError(c.loc(path + ("follow",)), "a view cannot follow itself", "name a scene object"))


def _up_hint(direction: np.ndarray | None) -> str:
    if direction is None:
        return "e.g. up: [0, 0, 1]"
    d = direction / np.linalg.norm(direction)
    for cand in ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]):
        if check_up(np.asarray(cand), d) is None and abs(float(np.dot(cand, d))) < 0.9:
            return f"e.g. up: [{', '.join(f'{v + 0.0:g}' for v in cand)}]"
    return "choose an up across the view direction"


def check_follows(vc: ViewCompiler) -> None:
    """Once the scene is compiled: every ``follow`` names one of its objects."""
    c = vc.c
    for path, p, name in vc.__dict__.get("_views3d", []):
        link = re.fullmatch(r"(.+)\.link\d+", p.follow or "")
        if link is not None and link.group(1) in vc.scene_names:
            continue  # a robot's link: "<robot>.link<i>" (0 the base), as collisions() names them
        if p.follow is not None and p.follow != name and p.follow not in vc.scene_names:
            others = sorted(n for n in vc.scene_names if n != name)
            hint = did_you_mean(p.follow, others)
            robot = closest(link.group(1), others) if link is not None and not hint else None
            if robot is not None:  # a link of a misspelt robot
                hint = f"did you mean '{robot}{p.follow[len(link.group(1)):]}'?"
            c.errors.append(SpecError(c.loc(path + ("follow",)), f"the view follows '{p.follow}', but the scene has no object of that name",
                                      hint or (f"objects: {', '.join(others)}" if others else "give the object a name")))
