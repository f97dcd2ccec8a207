"""What the model's code needs from the world: the small interface between ``sim`` and ``world``.

The prelude's ``capture()``, ``object_pose()``, ``move_object()``, ``attach()``,
``release()``, ``collisions()`` and the robot programs' ``close_gripper()`` reach the
scene only through :class:`WorldAccess`, which the app (``ejsrl.app.App``) implements over
its ``ejsrl.world`` binding. ``sim`` imports neither the view nor the app nor the world.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["WorldAccess", "WorldFunctionsAccess"]


@runtime_checkable
class WorldFunctionsAccess(Protocol):
    """The prelude's world functions (``ejsrl.world.functions.WorldFunctions`` implements them)."""

    def object_pose(self, name: str) -> np.ndarray: ...

    def move_object(self, name: str, pose: ArrayLike) -> None: ...

    def attach(self, name: str, robot: str, link: int | None = None) -> None: ...

    def release(self, name: str) -> None: ...

    def collisions(self) -> list[tuple[str, str]]: ...

    def set_view(self, position: Any = None, target: Any = None, up: Any = None, fov: float | None = None, **kw: Any) -> None:
        """Ask for a camera of the 3D view (``ejsrl.world.view3d.set_view``)."""
        ...

    def graspable_near(self, robot: Any, point: ArrayLike, reach: float) -> tuple[str, str] | None:
        """The nearest visible graspable object within ``reach`` of ``point`` and the name of
        the scene element that draws ``robot`` (a ``Robot``): ``(object, element)``; None if
        there is none or the robot is not drawn. Poses are brought up to date first."""
        ...


@runtime_checkable
class WorldAccess(Protocol):
    """The world as model code sees it: a virtual camera and the world functions."""

    def capture(self, name: str) -> np.ndarray:
        """The RGB image (H, W, 3) that camera ``name`` sees now."""
        ...

    def capture_depth(self, name: str) -> np.ndarray:
        """The depth image (H, W) float32 of camera ``name`` now (Z in metres, inf where empty)."""
        ...

    def world_functions(self) -> WorldFunctionsAccess:
        """The world functions over the app's scene."""
        ...
