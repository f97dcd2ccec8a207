"""Stereo vision: rectification, disparity, depth and triangulation (OpenCV underneath).

Conventions: ``T_left_right`` (4, 4) is the pose of the right camera in the left camera's
frame (z forward, x right, y down). Disparity is in pixels, ``d = x_left - x_right`` for
the same scene point on the same rectified row (positive for points in front); depth is
``Z = f * baseline / d`` with ``f`` the rectified focal length in pixels and ``baseline``
in metres. Invalid disparities are nan.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_gray, as_remap_source, choice, image_function
from ejsrl.vision.camera import CameraModel

__all__ = ["StereoRectification", "stereo_rectify", "disparity", "depth_from_disparity", "triangulate"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class StereoRectification:
    """A rectified stereo pair: rotations ``R1``, ``R2`` (3, 3) from each camera's frame to its
    rectified frame, projections ``P1``, ``P2`` (3, 4) of the rectified cameras (left frame),
    ``Q`` (4, 4) disparity-to-depth matrix, ``f`` (px) and ``baseline`` (m)."""

    R1: Array
    R2: Array
    P1: Array
    P2: Array
    Q: Array
    image_size: tuple[int, int]
    _maps: tuple = field(repr=False)

    @property
    def f(self) -> float:
        return float(self.P1[0, 0])

    @property
    def baseline(self) -> float:
        return float(-self.P2[0, 3] / self.P2[0, 0])

    def rectify(self, left: ArrayLike, right: ArrayLike) -> tuple[NDArray, NDArray]:
        """Both images warped to the rectified pair (corresponding points on the same row)."""
        (m1x, m1y), (m2x, m2y) = self._maps[0], self._maps[1]
        out = []
        for img, (mx, my) in ((left, (m1x, m1y)), (right, (m2x, m2y))):
            arr = np.ascontiguousarray(as_remap_source(img, "left" if mx is m1x else "right"))
            if arr.shape[:2] != (self.image_size[1], self.image_size[0]):
                raise ValueError(f"images must be {self.image_size[0]} x {self.image_size[1]}, got shape {arr.shape}")
            out.append(cv2.remap(arr, mx, my, cv2.INTER_LINEAR))
        return out[0], out[1]

    def rectify_points(self, pixels: ArrayLike, side: str) -> Array:
        """Pixels (N, 2) seen by the ``side`` (``"left"`` or ``"right"``) camera -> rectified pixels (N, 2)."""
        if side not in ("left", "right"):
            raise ValueError(f"side must be 'left' or 'right', got {side!r}")
        cam, R, P = (self._cams[0], self.R1, self.P1) if side == "left" else (self._cams[1], self.R2, self.P2)
        px = np.asarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
        return cv2.undistortPoints(px, cam.K, cam.distortion, R=R, P=P, criteria=crit).reshape(-1, 2)

    @property
    def _cams(self) -> tuple[CameraModel, CameraModel]:
        return self._maps[2]


def stereo_rectify(left: CameraModel, right: CameraModel, T_left_right: ArrayLike, *, alpha: float = 0.0) -> StereoRectification:
    """Rectify a calibrated pair (``cv2.stereoRectify``, zero disparity at infinity).

    ``alpha``: 0 keeps only valid pixels (zoomed in), 1 keeps every source pixel.
    """
    if left.resolution != right.resolution:
        raise ValueError(f"both cameras must have the same resolution, got {left.resolution} and {right.resolution}")
    T = np.asarray(T_left_right, dtype=np.float64)
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise ValueError(f"T_left_right must be a finite 4 x 4 pose, got shape {T.shape}")
    T_rl = np.linalg.inv(T)  # X_right = R X_left + t, OpenCV's (R, T)
    size = left.resolution
    R1, R2, P1, P2, Q, _, _ = cv2.stereoRectify(
        left.K, left.distortion, right.K, right.distortion, size, T_rl[:3, :3].copy(), T_rl[:3, 3].reshape(3, 1).copy(),
        flags=cv2.CALIB_ZERO_DISPARITY, alpha=float(alpha),
    )
    m1 = cv2.initUndistortRectifyMap(left.K, left.distortion, R1, P1, size, cv2.CV_32FC1)
    m2 = cv2.initUndistortRectifyMap(right.K, right.distortion, R2, P2, size, cv2.CV_32FC1)
    return StereoRectification(R1, R2, P1, P2, Q, size, (m1, m2, (left, right)))


@image_function
def disparity(
    left: ArrayLike, right: ArrayLike, *, max_disparity: int = 64, block_size: int = 5, method: str = "sgbm"
) -> NDArray[np.float32]:
    """Disparity (H, W) in pixels of a rectified pair, ``x_left - x_right``; nan where none was found.

    ``method``: ``"sgbm"`` (semi-global block matching, default) or ``"bm"`` (block
    matching); ``max_disparity`` is rounded up to a multiple of 16; ``block_size`` odd.
    Sub-pixel to 1/16 px. The images must be wider than the disparities searched plus the
    block (``max_disparity`` rounded up + ``block_size``) and, for ``"bm"``, at least
    ``max(5, block_size)`` px in each direction; smaller ones are a ValueError.
    """
    L, R = as_gray(left, "left"), as_gray(right, "right")
    if L.shape != R.shape:
        raise ValueError(f"left and right must be images of the same size, got {L.shape} and {R.shape}")
    if block_size < 1 or block_size % 2 == 0:
        raise ValueError(f"block_size must be a positive odd number, got {block_size}")
    if max_disparity < 1:
        raise ValueError(f"max_disparity must be positive, got {max_disparity}")
    method = choice(method, ("sgbm", "bm"), "disparity method")
    nd = 16 * int(np.ceil(max_disparity / 16))
    h, w = L.shape
    block = max(5, block_size) if method == "bm" else block_size
    if w < nd + block or h < block:
        raise ValueError(
            f"the images ({w} x {h} px) are too small to search {nd} disparities with a {block} px block: they need "
            f"at least {nd + block} x {block} px; lower max_disparity (and block_size) or use larger images"
        )
    if method == "sgbm":
        m = cv2.StereoSGBM_create(minDisparity=0, numDisparities=nd, blockSize=block_size, P1=8 * block_size**2,
                                  P2=32 * block_size**2, uniquenessRatio=5, mode=cv2.STEREO_SGBM_MODE_HH)
    else:
        m = cv2.StereoBM_create(numDisparities=nd, blockSize=block)
    d = m.compute(L, R).astype(np.float32) / 16.0
    d[d < 0] = np.nan
    return d


def depth_from_disparity(disp: ArrayLike, f: float, baseline: float) -> NDArray[np.float64]:
    """Depth Z = f * baseline / d (same shape as ``disp``; nan where d <= 0 or nan). ``f`` px, ``baseline`` m."""
    if not (f > 0 and baseline > 0):
        raise ValueError(f"f and baseline must be positive, got {f} and {baseline}")
    d = np.asarray(disp, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        Z = f * baseline / d
    Z[~(d > 0)] = np.nan
    return Z


def triangulate(P1: ArrayLike, P2: ArrayLike, pixels1: ArrayLike, pixels2: ArrayLike) -> Array:
    """3-D points (N, 3) from their pixels (N, 2) in two views with projection matrices P1, P2 (3, 4) (linear, DLT)."""
    A, B = np.asarray(P1, dtype=np.float64), np.asarray(P2, dtype=np.float64)
    p1, p2 = np.asarray(pixels1, dtype=np.float64).reshape(-1, 2), np.asarray(pixels2, dtype=np.float64).reshape(-1, 2)
    if A.shape != (3, 4) or B.shape != (3, 4):
        raise ValueError(f"P1 and P2 must be 3 x 4 projection matrices, got {A.shape} and {B.shape}")
    if len(p1) != len(p2):
        raise ValueError(f"{len(p1)} pixels in view 1 but {len(p2)} in view 2")
    X = cv2.triangulatePoints(A, B, p1.T.copy(), p2.T.copy())
    return (X[:3] / X[3]).T
