"""Virtual-camera rendering of the world: RGB and depth images from a camera pose.

``render(world, "cam")`` is what ``capture("cam")`` returns in apps, with or without a
browser. The back end is the NumPy z-buffer rasterizer of ``_raster.py`` (deterministic,
flat shading). ``backend`` is kept as a parameter ("auto" and "numpy" both pick it) for an
OpenGL back end (moderngl on a headless EGL context) that is not built yet.

Shading: each face gets its colour times ``ambient + (1 - ambient) * |cos a|`` where ``a``
is the angle between its normal and ``LIGHT_DIR``, a light attached to the camera (so
faces seen edge-on are darker); no textures, no shadows.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision.camera import CameraModel
from ejsrl.world._raster import rasterize

__all__ = ["render", "render_triangles", "shade_faces", "BACKGROUND", "AMBIENT"]

#: default background colour, RGB in [0, 1] (a light grey-blue)
BACKGROUND: tuple[float, float, float] = (0.82, 0.86, 0.92)
#: share of a face's colour it keeps when seen edge-on
AMBIENT: float = 0.3
#: unit vector towards the light in the camera frame (x right, y down, z forward)
LIGHT_DIR: NDArray[np.float64] = np.array([-0.25, -0.35, -1.0]) / np.linalg.norm([-0.25, -0.35, -1.0])


def shade_faces(
    tris_cam: NDArray[np.float64], rgb: NDArray[np.float64], ambient: float = AMBIENT
) -> NDArray[np.uint8]:
    """Flat shading: camera-frame triangles (F, 3, 3) and colours (F, 3) in [0, 1] -> (F, 3) uint8.

    The light comes from the camera, slightly from its upper left (``LIGHT_DIR``, camera
    frame), so coplanar faces get the same shade and the sides of a box differ.
    """
    n = np.cross(tris_cam[:, 1] - tris_cam[:, 0], tris_cam[:, 2] - tris_cam[:, 0])
    nn = np.linalg.norm(n, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = np.abs(n @ LIGHT_DIR) / nn
    cos = np.nan_to_num(cos, nan=1.0)
    k = ambient + (1.0 - ambient) * cos
    return np.clip(np.rint(255.0 * np.clip(rgb, 0.0, 1.0) * k[:, None]), 0, 255).astype(np.uint8)


def _bg_uint8(background: Sequence[float]) -> NDArray[np.uint8]:
    bg = np.asarray(background, dtype=np.float64).reshape(3)
    if bg.max() > 1.0:  # allow 0-255 too
        bg = bg / 255.0
    return np.clip(np.rint(bg * 255.0), 0, 255).astype(np.uint8)


def render_triangles(
    tris_world: ArrayLike,
    rgb: ArrayLike,
    camera: CameraModel,
    T_world_camera: ArrayLike,
    *,
    background: Sequence[float] = BACKGROUND,
    cull_backfaces: bool = True,
    backend: str = "numpy",
) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
    """Render world triangles (F, 3, 3) with colours (F, 3) in [0, 1] seen by ``camera``.

    Returns ``rgb`` (H, W, 3) uint8 and ``depth`` (H, W) float32 (metres along the optical
    axis, inf where nothing is seen).
    """
    tris = np.asarray(tris_world, dtype=np.float64).reshape(-1, 3, 3)
    cols = np.asarray(rgb, dtype=np.float64).reshape(-1, 3)
    T = np.asarray(T_world_camera, dtype=np.float64)
    R, t = T[:3, :3], T[:3, 3]
    tris_cam = (tris - t) @ R  # world -> camera: R^T (p - t)
    shaded = shade_faces(tris_cam, cols)
    bg = _bg_uint8(background)
    if backend not in ("numpy", "auto"):
        raise ValueError(f"unknown render backend {backend!r}; only 'numpy' (or 'auto') is available")
    face, depth = rasterize(
        tris_cam, camera.K, camera.width, camera.height, near=camera.near, far=camera.far, cull_backfaces=cull_backfaces
    )
    table = np.concatenate([shaded, bg[None, :]])
    image = table[face]  # face == -1 picks the background row
    return image, depth


def _pick_backend(backend: str) -> str:
    """The back end that ``backend`` ("auto", "numpy") resolves to: the NumPy rasterizer."""
    return "numpy" if backend == "auto" else backend


def render(
    world: Any,
    camera: CameraModel | str,
    T_world_camera: ArrayLike | None = None,
    *,
    exclude: Sequence[str] = (),
    background: Sequence[float] = BACKGROUND,
    cull_backfaces: bool = True,
    backend: str = "auto",
) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
    """Render what a camera sees in ``world``: ``(rgb (H, W, 3) uint8, depth (H, W) float32)``.

    ``camera``: a ``CameraModel`` (then ``T_world_camera`` (4, 4), the camera pose in the
    world, is required) or the name of a ``CameraNode`` of the world (then its pose,
    intrinsics, resolution, near and far come from the node; a given ``T_world_camera``
    overrides the pose). ``exclude``: names of nodes not to draw (for example the robot
    link that carries the camera). ``background``: RGB in [0, 1] (default ``BACKGROUND``,
    light grey-blue). ``cull_backfaces``: skip faces seen from behind, as the browser view
    (three.js, front side) does; set False for open meshes seen from both sides.
    ``backend``: "auto" or "numpy" (see the module docstring).

    Depth is Z in the camera frame (metres along the optical axis), inf where nothing is
    seen. The output is deterministic.
    """
    if isinstance(camera, str):
        node = world[camera]
        if getattr(node, "kind", None) != "camera":
            raise ValueError(f"{camera!r} is a {node.kind}, not a camera")
        cam = CameraModel.from_node(node)
        T = node.T_world() if T_world_camera is None else np.asarray(T_world_camera, dtype=float)
        exclude = tuple(exclude) + (camera,)
    elif isinstance(camera, CameraModel):
        if T_world_camera is None:
            raise ValueError("render(world, CameraModel, T_world_camera): the camera pose T_world_camera is required")
        cam = camera
        T = np.asarray(T_world_camera, dtype=float)
    else:
        raise TypeError(f"camera must be a CameraModel or a camera name, not {type(camera).__name__}")
    tris, rgb = world.triangles(exclude=tuple(exclude))
    return render_triangles(
        tris, rgb, cam, T, background=background, cull_backfaces=cull_backfaces, backend=_pick_backend(backend)
    )
