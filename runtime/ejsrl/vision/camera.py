"""The pinhole camera model shared by the renderer, the image functions and visual servoing.

Frames and conventions: the camera frame has z forward (the optical axis), x right and
y down, as in OpenCV. Pixel coordinates are ``(x, y)`` = (column, row) with the centre of
pixel ``img[r, c]`` at ``(c, r)``; the image covers ``[-0.5, w - 0.5] x [-0.5, h - 0.5]``.
``T_world_camera`` is the (4, 4) pose of the camera frame in the world.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["CameraModel", "intrinsics_from_fov", "look_at"]

Array = NDArray[np.float64]


def look_at(eye: ArrayLike, target: ArrayLike, up: ArrayLike = (0.0, 0.0, 1.0)) -> Array:
    """``T_world_camera`` (4, 4): a camera at ``eye`` looking at ``target`` (z forward, y down).

    ``up`` is the world direction that appears up in the image (not parallel to the view).
    """
    eye = np.asarray(eye, dtype=float)
    z = np.asarray(target, dtype=float) - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, np.asarray(up, dtype=float))
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, np.cross(z, x), z, eye
    return T


def intrinsics_from_fov(width: int, height: int, fov_deg: float) -> Array:
    """The (3, 3) matrix K of a camera with square pixels and a vertical field of view.

    ``fov_deg``: vertical field of view in degrees (the UI edge); the principal point is the
    image centre ``((w - 1) / 2, (h - 1) / 2)`` and ``fx = fy = (h / 2) / tan(fov / 2)``.
    """
    if not 0.0 < fov_deg < 180.0:
        raise ValueError(f"fov_deg must be in (0, 180) degrees, got {fov_deg}")
    f = 0.5 * height / math.tan(math.radians(fov_deg) / 2.0)
    return np.array([[f, 0.0, (width - 1) / 2.0], [0.0, f, (height - 1) / 2.0], [0.0, 0.0, 1.0]])


def _points(P: ArrayLike) -> Array:
    arr = np.asarray(P, dtype=np.float64)
    if arr.shape[-1] != 3:
        raise ValueError(f"expected points of shape (N, 3), got {arr.shape}")
    return arr.reshape(-1, 3)


class CameraModel:
    """A pinhole camera: ``width`` x ``height`` pixels and intrinsics ``K`` (3, 3).

    Give either ``fov_deg`` (vertical field of view in degrees, square pixels, centred
    principal point) or ``K``; with neither, a 60 degree field of view is used. ``near`` and
    ``far`` (metres) bound what the renderer draws.
    """

    def __init__(
        self,
        width: int,
        height: int,
        fov_deg: float | None = None,
        K: ArrayLike | None = None,
        *,
        near: float = 0.01,
        far: float = 100.0,
    ) -> None:
        self.width = int(width)
        self.height = int(height)
        if self.width <= 0 or self.height <= 0:
            raise ValueError(f"the resolution must be positive, got {width} x {height}")
        if K is not None and fov_deg is not None:
            raise ValueError("give either fov_deg or K, not both")
        if K is None:
            self.K = intrinsics_from_fov(self.width, self.height, 60.0 if fov_deg is None else float(fov_deg))
        else:
            self.K = np.array(K, dtype=np.float64).reshape(3, 3)
        self.near = float(near)
        self.far = float(far)

    @classmethod
    def from_node(cls, node: Any) -> CameraModel:
        """The model of a world ``CameraNode`` (its resolution, fov or intrinsics, near, far)."""
        w, h = (int(v) for v in node.props["resolution"])
        K = node.props.get("intrinsics")
        if K is not None:
            return cls(w, h, K=K, near=node.props["near"], far=node.props["far"])
        return cls(w, h, fov_deg=float(node.props["fov"]), near=node.props["near"], far=node.props["far"])

    # -- intrinsics -------------------------------------------------------------------------
    @property
    def fx(self) -> float:
        return float(self.K[0, 0])

    @property
    def fy(self) -> float:
        return float(self.K[1, 1])

    @property
    def cx(self) -> float:
        return float(self.K[0, 2])

    @property
    def cy(self) -> float:
        return float(self.K[1, 2])

    @property
    def resolution(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return self.width, self.height

    @property
    def fov_deg(self) -> float:
        """Vertical field of view in degrees."""
        return math.degrees(2.0 * math.atan(0.5 * self.height / self.fy))

    # -- frames -----------------------------------------------------------------------------
    @staticmethod
    def world_to_camera(P_world: ArrayLike, T_world_camera: ArrayLike) -> Array:
        """Points (N, 3) in the world -> the same points (N, 3) in the camera frame."""
        T = np.asarray(T_world_camera, dtype=np.float64)
        R, t = T[:3, :3], T[:3, 3]
        return (_points(P_world) - t) @ R

    @staticmethod
    def camera_to_world(P_camera: ArrayLike, T_world_camera: ArrayLike) -> Array:
        """Points (N, 3) in the camera frame -> world (N, 3)."""
        T = np.asarray(T_world_camera, dtype=np.float64)
        return _points(P_camera) @ T[:3, :3].T + T[:3, 3]

    # -- projection -------------------------------------------------------------------------
    def project_camera(self, P_camera: ArrayLike) -> Array:
        """Camera-frame points (N, 3) -> pixels (N, 2) as (x, y); nan for points with Z <= 0."""
        P = _points(P_camera)
        with np.errstate(divide="ignore", invalid="ignore"):
            uvw = P @ self.K.T
            px = uvw[:, :2] / uvw[:, 2:3]
        px[P[:, 2] <= 0] = np.nan
        return px

    def project(self, P_world: ArrayLike, T_world_camera: ArrayLike) -> Array:
        """World points (N, 3) seen by a camera at ``T_world_camera`` (4, 4) -> pixels (N, 2) (x, y).

        Points behind the camera give nan.
        """
        return self.project_camera(self.world_to_camera(P_world, T_world_camera))

    def depth(self, P_world: ArrayLike, T_world_camera: ArrayLike) -> Array:
        """Depth Z (N,) along the optical axis of world points (N, 3), metres."""
        return self.world_to_camera(P_world, T_world_camera)[:, 2]

    def normalized(self, pixels: ArrayLike) -> Array:
        """Pixels (N, 2) (x, y) -> normalised image coordinates (N, 2), i.e. (X/Z, Y/Z)."""
        px = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        h = np.column_stack([px, np.ones(len(px))])
        return (h @ np.linalg.inv(self.K).T)[:, :2]

    def denormalized(self, xy: ArrayLike) -> Array:
        """Normalised image coordinates (N, 2) -> pixels (N, 2) (x, y)."""
        n = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        h = np.column_stack([n, np.ones(len(n))])
        uvw = h @ self.K.T
        return uvw[:, :2] / uvw[:, 2:3]

    def backproject(self, pixels: ArrayLike, depth: ArrayLike, T_world_camera: ArrayLike | None = None) -> Array:
        """Pixels (N, 2) (x, y) with depths Z (N,) (metres along the optical axis) -> 3-D points (N, 3).

        In the camera frame, or in the world when ``T_world_camera`` (4, 4) is given.
        """
        xy = self.normalized(pixels)
        Z = np.broadcast_to(np.asarray(depth, dtype=np.float64).reshape(-1), (len(xy),))
        P = np.column_stack([xy * Z[:, None], Z])
        return P if T_world_camera is None else self.camera_to_world(P, T_world_camera)

    def in_image(self, pixels: ArrayLike) -> NDArray[np.bool_]:
        """Which pixels (N, 2) fall inside the image (nan counts as outside)."""
        px = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        with np.errstate(invalid="ignore"):
            return (
                (px[:, 0] >= -0.5) & (px[:, 0] <= self.width - 0.5) & (px[:, 1] >= -0.5) & (px[:, 1] <= self.height - 0.5)
            )

    def frustum(self, T_world_camera: ArrayLike | None = None, *, near: float | None = None, far: float | None = None) -> Array:
        """The 8 corners (8, 3) of the view frustum: 4 at ``near`` then 4 at ``far``.

        Each set goes top-left, top-right, bottom-right, bottom-left in the image; camera
        frame, or world frame when ``T_world_camera`` is given (for drawing the camera).
        """
        n = self.near if near is None else float(near)
        f = self.far if far is None else float(far)
        w, h = self.width - 0.5, self.height - 0.5
        corners = np.array([[-0.5, -0.5], [w, -0.5], [w, h], [-0.5, h]])
        P = np.concatenate([self.backproject(corners, n), self.backproject(corners, f)])
        return P if T_world_camera is None else self.camera_to_world(P, T_world_camera)

    def frustum_lines(self, T_world_camera: ArrayLike | None = None, *, depth: float = 0.2) -> Array:
        """Line segments (8, 2, 3) of a small pyramid (apex at the optical centre) for drawing."""
        base = self.frustum(None, near=depth, far=depth)[:4]
        apex = np.zeros(3)
        segs = [(apex, base[i]) for i in range(4)] + [(base[i], base[(i + 1) % 4]) for i in range(4)]
        out = np.array(segs)
        if T_world_camera is not None:
            out = self.camera_to_world(out.reshape(-1, 3), T_world_camera).reshape(-1, 2, 3)
        return out

    def __repr__(self) -> str:
        return f"CameraModel({self.width}x{self.height}, fx={self.fx:.1f}, fy={self.fy:.1f}, cx={self.cx:.1f}, cy={self.cy:.1f})"
