"""The pinhole camera model shared by the renderer, the image functions and visual servoing.

Frames and conventions: the camera frame has z forward (the optical axis), x right and
y down, as in OpenCV. Pixel coordinates are ``(x, y)`` = (column, row) with the centre of
pixel ``img[r, c]`` at ``(c, r)``; the image covers ``[-0.5, w - 0.5] x [-0.5, h - 0.5]``.
``T_world_camera`` is the (4, 4) pose of the camera frame in the world.

Lens distortion follows OpenCV's (Brown-Conrady) model and its coefficient order
``(k1, k2, p1, p2, k3)`` (MVTB lists the same five as ``k1, k2, k3, p1, p2``): ideal
normalised coordinates ``(x, y) = (X/Z, Y/Z)`` with ``r^2 = x^2 + y^2`` become

    x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
    y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y

and the pixel is ``K (x_d, y_d, 1)``. Pixels "as observed" are distorted; "ideal" pixels
are those a distortion-free camera with the same K would see.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["CameraModel", "intrinsics_from_fov", "look_at", "pose_from_rvec"]

Array = NDArray[np.float64]

#: remap tables of undistort/distort, by (direction, size, K, distortion); least recently used first
_REMAP_CACHE: dict[tuple, NDArray[np.float32]] = {}


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


def pose_from_rvec(rvec: ArrayLike, tvec: ArrayLike) -> Array:
    """OpenCV's pose ``(rvec, tvec)`` (Rodrigues rotation vector, translation) as a (4, 4) matrix."""
    T = np.eye(4)
    T[:3, :3] = _rodrigues(np.asarray(rvec, dtype=np.float64).reshape(3))
    T[:3, 3] = np.asarray(tvec, dtype=np.float64).reshape(3)
    return T


def _rodrigues(r: Array) -> Array:
    theta = float(np.linalg.norm(r))
    if theta < 1e-15:
        return np.eye(3)
    k = r / theta
    Kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(theta) * Kx + (1.0 - math.cos(theta)) * (Kx @ Kx)


def _distortion(coeffs: ArrayLike | None) -> Array:
    """Coefficients as the 5-vector (k1, k2, p1, p2, k3); 2 (k1, k2) or 4 (no k3) are padded with zeros."""
    if coeffs is None:
        return np.zeros(5)
    d = np.asarray(coeffs, dtype=np.float64).reshape(-1)
    if len(d) not in (0, 2, 4, 5):
        raise ValueError(
            f"distortion takes 5 coefficients (k1, k2, p1, p2, k3), OpenCV's order (or 2 or 4 of them), got {len(d)}"
        )
    if not np.all(np.isfinite(d)):
        raise ValueError(f"distortion coefficients must be finite, got {d.tolist()}")
    return np.concatenate([d, np.zeros(5 - len(d))])


def _pixels(px: ArrayLike, name: str = "pixels") -> Array:
    arr = np.asarray(px, dtype=np.float64)
    if arr.shape[-1:] != (2,) and arr.size != 0:
        raise ValueError(f"{name} must have shape (N, 2) of (x, y), got {arr.shape}")
    return arr.reshape(-1, 2)


def _points(P: ArrayLike) -> Array:
    arr = np.asarray(P, dtype=np.float64)
    if arr.shape[-1] != 3:
        raise ValueError(f"expected points of shape (N, 3), got {arr.shape}")
    return arr.reshape(-1, 3)


class Intrinsics:
    """``fx``, ``fy`` (focal lengths) and ``cx``, ``cy`` (principal point), in pixels, read from
    the 3x3 camera matrix ``K`` of a camera model or a calibration."""

    K: NDArray[np.float64]

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


class CameraModel(Intrinsics):
    """A pinhole camera: ``width`` x ``height`` pixels and intrinsics ``K`` (3, 3).

    Give either ``fov_deg`` (vertical field of view in degrees, square pixels, centred
    principal point) or ``K``; with neither, a 60 degree field of view is used. ``near`` and
    ``far`` (metres) bound what the renderer draws. ``distortion``: lens distortion
    coefficients ``(k1, k2, p1, p2, k3)`` in OpenCV's order (see the module docstring);
    projecting applies it, :meth:`normalized` and :meth:`backproject` invert it, and
    :meth:`undistort` / :meth:`distort` convert images.
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
        distortion: ArrayLike | None = None,
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
            K = np.array(K, dtype=np.float64)
            if K.size == 9:
                K = K.reshape(3, 3)
            if K.shape != (3, 3) or not np.all(np.isfinite(K)) or K[0, 0] <= 0 or K[1, 1] <= 0:
                raise ValueError(f"K must be a finite 3 x 3 matrix with fx, fy > 0, got {K.tolist()}")
            self.K = K
        self.distortion = _distortion(distortion)
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
    def k1(self) -> float:
        return float(self.distortion[0])

    @property
    def k2(self) -> float:
        return float(self.distortion[1])

    @property
    def p1(self) -> float:
        return float(self.distortion[2])

    @property
    def p2(self) -> float:
        return float(self.distortion[3])

    @property
    def k3(self) -> float:
        return float(self.distortion[4])

    @property
    def distorted(self) -> bool:
        """Whether the lens has any distortion."""
        return bool(np.any(self.distortion != 0.0))

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
            xy = P[:, :2] / P[:, 2:3]
        xy[P[:, 2] <= 0] = np.nan
        return self.denormalized(xy)

    def project(self, P_world: ArrayLike, T_world_camera: ArrayLike) -> Array:
        """World points (N, 3) seen by a camera at ``T_world_camera`` (4, 4) -> pixels (N, 2) (x, y).

        Points behind the camera give nan.
        """
        return self.project_camera(self.world_to_camera(P_world, T_world_camera))

    def depth(self, P_world: ArrayLike, T_world_camera: ArrayLike) -> Array:
        """Depth Z (N,) along the optical axis of world points (N, 3), metres."""
        return self.world_to_camera(P_world, T_world_camera)[:, 2]

    def normalized(self, pixels: ArrayLike) -> Array:
        """Pixels (N, 2) (x, y), as observed -> ideal normalised coordinates (N, 2), i.e. (X/Z, Y/Z).

        With lens distortion the distortion is inverted (Newton's method, to ~1e-12).
        """
        px = _pixels(pixels)
        h = np.column_stack([px, np.ones(len(px))])
        xy = (h @ np.linalg.inv(self.K).T)[:, :2]
        return self.undistort_normalized(xy) if self.distorted else xy

    def denormalized(self, xy: ArrayLike) -> Array:
        """Ideal normalised coordinates (N, 2) -> pixels (N, 2) (x, y) as observed (distortion applied)."""
        n = _pixels(xy, "xy")
        if self.distorted:
            n = self.distort_normalized(n)
        h = np.column_stack([n, np.ones(len(n))])
        uvw = h @ self.K.T
        return uvw[:, :2] / uvw[:, 2:3]

    # -- lens distortion --------------------------------------------------------------------
    def distort_normalized(self, xy: ArrayLike) -> Array:
        """Ideal normalised coordinates (N, 2) -> distorted normalised coordinates (N, 2)."""
        n = _pixels(xy, "xy")
        k1, k2, p1, p2, k3 = self.distortion
        x, y = n[:, 0], n[:, 1]
        r2 = x * x + y * y
        radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
        return np.column_stack(
            [x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x), y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y]
        )

    def undistort_normalized(self, xy_distorted: ArrayLike, *, iterations: int = 30) -> Array:
        """Distorted normalised coordinates (N, 2) -> ideal ones (N, 2), by Newton's method.

        Converges where the distortion is invertible (inside the image for any real lens);
        a point where it does not converge comes back as nan.
        """
        target = _pixels(xy_distorted, "xy_distorted")
        k1, k2, p1, p2, k3 = self.distortion
        n = target.copy()
        for _ in range(iterations):
            x, y = n[:, 0], n[:, 1]
            r2 = x * x + y * y
            radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
            drad = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2)  # d radial / d r^2
            res = self.distort_normalized(n) - target
            a = radial + 2.0 * x * x * drad + 2.0 * p1 * y + 6.0 * p2 * x
            b = 2.0 * x * y * drad + 2.0 * p1 * x + 2.0 * p2 * y
            d = radial + 2.0 * y * y * drad + 6.0 * p1 * y + 2.0 * p2 * x
            det = a * d - b * b
            with np.errstate(divide="ignore", invalid="ignore"):
                step = np.column_stack([(d * res[:, 0] - b * res[:, 1]) / det, (a * res[:, 1] - b * res[:, 0]) / det])
            n = n - step
            if np.nanmax(np.abs(step), initial=0.0) < 1e-14:
                break
        with np.errstate(invalid="ignore"):
            bad = np.abs(self.distort_normalized(n) - target).max(axis=1) > 1e-9
        n[bad] = np.nan
        return n

    def distort_points(self, pixels: ArrayLike) -> Array:
        """Ideal pixels (N, 2) (distortion-free, same K) -> pixels as observed through the lens."""
        px = _pixels(pixels)
        h = np.column_stack([px, np.ones(len(px))])
        return self.denormalized((h @ np.linalg.inv(self.K).T)[:, :2])

    def undistort_points(self, pixels: ArrayLike) -> Array:
        """Observed pixels (N, 2) -> ideal pixels (N, 2): where a distortion-free camera with the same K sees them."""
        n = self.normalized(pixels)
        return n @ self.K[:2, :2].T + self.K[:2, 2]

    def _remap(self, img: ArrayLike, source_of: Any, interpolation: str, K_source: ArrayLike | None = None) -> NDArray:
        import cv2

        from ejsrl.vision._util import as_remap_source

        arr = as_remap_source(img)
        if K_source is not None:
            Ks = np.asarray(K_source, dtype=np.float64)
            if Ks.shape != (3, 3) or not np.all(np.isfinite(Ks)):
                raise ValueError(f"K_source must be a finite 3 x 3 matrix, got {Ks.tolist()}")
            # output pixel -> ideal normalised coordinates -> pixel of the source pinhole image
            inner = source_of
            Kinv = np.linalg.inv(self.K)

            def source_of(px: Array) -> Array:  # noqa: F811 - same role, other source camera
                n = (np.column_stack([inner(px), np.ones(len(px))]) @ Kinv.T)[:, :2]
                uvw = np.column_stack([n, np.ones(len(n))]) @ Ks.T
                return uvw[:, :2] / uvw[:, 2:3]

            source_of.__name__ = f"{inner.__name__}:{Ks.tobytes().hex()}"
        elif arr.shape[:2] != (self.height, self.width):
            raise ValueError(
                f"img is {arr.shape[1]} x {arr.shape[0]} pixels but the camera is {self.width} x {self.height}"
            )
        modes = {"linear": cv2.INTER_LINEAR, "nearest": cv2.INTER_NEAREST, "cubic": cv2.INTER_CUBIC}
        if interpolation not in modes:
            raise ValueError(f"interpolation must be one of {sorted(modes)}, got {interpolation!r}")
        if not self.distorted and K_source is None:
            return arr.copy()
        # the maps depend only on the camera's numbers: keep the last few (a lab distorts every
        # frame, and a reset makes a new but equal CameraModel)
        key = (source_of.__name__, self.width, self.height, self.K.tobytes(), self.distortion.tobytes())
        maps = _REMAP_CACHE.pop(key, None)
        if maps is None:
            v, u = np.mgrid[0 : self.height, 0 : self.width]
            src = source_of(np.column_stack([u.ravel(), v.ravel()]).astype(np.float64))
            maps = np.nan_to_num(src, nan=-1e6).astype(np.float32).reshape(self.height, self.width, 2)
        _REMAP_CACHE[key] = maps  # most recently used last
        while len(_REMAP_CACHE) > 4:
            del _REMAP_CACHE[next(iter(_REMAP_CACHE))]
        return cv2.remap(np.ascontiguousarray(arr), maps[..., 0], maps[..., 1], modes[interpolation], borderMode=cv2.BORDER_CONSTANT)

    def undistort(self, img: ArrayLike, *, interpolation: str = "linear") -> NDArray:
        """The image (H, W[, C]) a distortion-free camera with the same K would have seen (as ``cv2.undistort``).

        Pixels whose source falls outside the input are black. uint8, uint16, int16 and float
        images keep their dtype; bool and other integer images (0..255) become uint8. Float
        values are moved, not judged: a depth map's ``inf`` (nothing seen) or NaN stays so.
        """
        return self._remap(img, self.distort_points, interpolation)

    def distort(self, img: ArrayLike, *, interpolation: str = "linear", K_source: ArrayLike | None = None) -> NDArray:
        """The inverse of :meth:`undistort`: an ideal (pinhole) image as this lens would see it.

        Use it to give a rendered image this camera's distortion; a scene point at ideal
        pixel p appears at ``distort_points(p)``. ``img`` is (H, W[, C]) at this camera's
        resolution, taken with its K; or, with ``K_source``, a pinhole image of any size
        taken from the same pose with intrinsics ``K_source`` (e.g. rendered with a margin
        around the frame, so that barrel distortion does not pull black borders in). The
        result is always this camera's size; pixels with no source are black.
        """
        return self._remap(img, self.undistort_points, interpolation, K_source)

    # -- pose from points (PnP) -------------------------------------------------------------
    def estimate_pose(self, P_object: ArrayLike, pixels: ArrayLike, *, method: str = "sqpnp") -> Array:
        """``T_camera_object`` (4, 4): the pose of an object in the camera frame from N >= 4 of its points.

        ``P_object`` (N, 3): the points in the object's own frame (metres); ``pixels``
        (N, 2): where they are seen, (x, y) as observed (this camera's K and distortion
        are used). ``method``: ``"sqpnp"`` (global, any N >= 4 points, default),
        ``"iterative"`` (Levenberg-Marquardt from a DLT/homography start), ``"ippe"``
        (coplanar points, z = 0 in the object frame) or ``"epnp"``; every result is refined
        with Levenberg-Marquardt (OpenCV ``solvePnP`` + ``solvePnPRefineLM``). The camera's
        pose in the object frame is ``np.linalg.inv(T_camera_object)``; with ``P_object``
        in world coordinates that is ``T_world_camera``.
        """
        import cv2

        methods = {"sqpnp": cv2.SOLVEPNP_SQPNP, "iterative": cv2.SOLVEPNP_ITERATIVE, "ippe": cv2.SOLVEPNP_IPPE, "epnp": cv2.SOLVEPNP_EPNP}
        if method not in methods:
            raise ValueError(f"method must be one of {sorted(methods)}, got {method!r}")
        P = np.asarray(P_object, dtype=np.float64)
        px = np.asarray(pixels, dtype=np.float64)
        if P.ndim != 2 or P.shape[1] != 3:
            raise ValueError(f"P_object must have shape (N, 3), got {P.shape}")
        if px.ndim != 2 or px.shape[1] != 2:
            raise ValueError(f"pixels must have shape (N, 2), got {px.shape}")
        if len(P) != len(px):
            raise ValueError(f"{len(P)} object points but {len(px)} pixels: give one pixel per point")
        if len(P) < 4:
            raise ValueError(f"estimate_pose needs at least 4 points, got {len(P)}")
        if not (np.all(np.isfinite(P)) and np.all(np.isfinite(px))):
            raise ValueError("P_object and pixels must be finite (drop the points that were not seen)")
        ok, rvec, tvec = cv2.solvePnP(P, px, self.K, self.distortion, flags=methods[method])
        if not ok:
            raise ValueError("no pose fits these points (are they degenerate, e.g. all on one line?)")
        rvec, tvec = cv2.solvePnPRefineLM(P, px, self.K, self.distortion, rvec, tvec)
        return pose_from_rvec(rvec, tvec)

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
        extra = f", distortion={np.round(self.distortion, 6).tolist()}" if self.distorted else ""
        return f"CameraModel({self.width}x{self.height}, fx={self.fx:.1f}, fy={self.fy:.1f}, cx={self.cx:.1f}, cy={self.cy:.1f}{extra})"
