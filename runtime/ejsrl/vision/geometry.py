"""Geometric image transforms: resize, rotate, flip, crop, affine and perspective warps.

Pixel coordinates are ``(x, y)`` = (column, row), as in OpenCV.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_image, as_points

__all__ = [
    "resize",
    "rotate",
    "flip",
    "crop",
    "warp_affine",
    "warp_perspective",
    "perspective_matrix",
    "affine_matrix",
]

_INTERP = {"nearest": cv2.INTER_NEAREST, "linear": cv2.INTER_LINEAR, "cubic": cv2.INTER_CUBIC, "area": cv2.INTER_AREA}


def _img(img: ArrayLike) -> NDArray:
    return np.ascontiguousarray(as_image(img))


def resize(
    img: ArrayLike, size: tuple[int, int] | None = None, *, scale: float | None = None, interpolation: str = "linear"
) -> NDArray:
    """Resize to ``size`` = (width, height) or by ``scale``; ``interpolation``: nearest, linear, cubic, area.

    Returns the resized image, same dtype.
    """
    a = _img(img)
    if size is None:
        if scale is None:
            raise ValueError("resize needs size=(width, height) or scale=")
        size = (max(1, round(a.shape[1] * scale)), max(1, round(a.shape[0] * scale)))
    return cv2.resize(a, (int(size[0]), int(size[1])), interpolation=_INTERP[interpolation])


def rotate(
    img: ArrayLike, angle_deg: float, *, center: tuple[float, float] | None = None, scale: float = 1.0, border: int = 0
) -> NDArray:
    """Rotate by ``angle_deg`` (degrees, counter-clockwise on screen) about ``center`` (x, y).

    Default centre: the image centre ((w - 1) / 2, (h - 1) / 2). The output keeps the input
    size; uncovered pixels get ``border``.
    """
    a = _img(img)
    h, w = a.shape[:2]
    c = ((w - 1) / 2.0, (h - 1) / 2.0) if center is None else (float(center[0]), float(center[1]))
    M = cv2.getRotationMatrix2D(c, float(angle_deg), float(scale))
    return cv2.warpAffine(a, M, (w, h), flags=cv2.INTER_LINEAR, borderValue=border)


def flip(img: ArrayLike, axis: str = "horizontal") -> NDArray:
    """Mirror the image: "horizontal" (left-right), "vertical" (up-down) or "both"."""
    code = {"horizontal": 1, "vertical": 0, "both": -1}[axis]
    return cv2.flip(_img(img), code)


def crop(img: ArrayLike, x: int, y: int, width: int, height: int) -> NDArray:
    """The ``width`` x ``height`` window whose top-left pixel is (``x``, ``y``), clipped to the image (a copy)."""
    a = as_image(img)
    H, W = a.shape[:2]
    x0, y0 = max(0, int(x)), max(0, int(y))
    x1, y1 = min(W, int(x) + int(width)), min(H, int(y) + int(height))
    return a[y0:y1, x0:x1].copy()


def affine_matrix(src: ArrayLike, dst: ArrayLike) -> NDArray[np.float64]:
    """The (2, 3) affine matrix that maps 3 points ``src`` (3, 2) (x, y) onto ``dst`` (3, 2)."""
    return cv2.getAffineTransform(as_points(src).astype(np.float32), as_points(dst).astype(np.float32))


def perspective_matrix(src: ArrayLike, dst: ArrayLike) -> NDArray[np.float64]:
    """The (3, 3) homography that maps 4 points ``src`` (4, 2) (x, y) onto ``dst`` (4, 2)."""
    return cv2.getPerspectiveTransform(as_points(src).astype(np.float32), as_points(dst).astype(np.float32))


def warp_affine(img: ArrayLike, M: ArrayLike, size: tuple[int, int] | None = None, *, border: int = 0) -> NDArray:
    """Warp by the (2, 3) affine matrix ``M`` (destination (x, y) = M [x, y, 1] of the source).

    ``size``: output (width, height), default the input size; ``border``: fill value.
    """
    a = _img(img)
    h, w = a.shape[:2]
    dsize = (w, h) if size is None else (int(size[0]), int(size[1]))
    return cv2.warpAffine(a, np.asarray(M, dtype=np.float64).reshape(2, 3), dsize, flags=cv2.INTER_LINEAR, borderValue=border)


def warp_perspective(img: ArrayLike, H: ArrayLike, size: tuple[int, int] | None = None, *, border: int = 0) -> NDArray:
    """Warp by the (3, 3) homography ``H`` (source points map to ``H [x, y, 1]``, dehomogenised).

    ``size``: output (width, height), default the input size; ``border``: fill value.
    """
    a = _img(img)
    h, w = a.shape[:2]
    dsize = (w, h) if size is None else (int(size[0]), int(size[1]))
    return cv2.warpPerspective(a, np.asarray(H, dtype=np.float64).reshape(3, 3), dsize, flags=cv2.INTER_LINEAR, borderValue=border)
