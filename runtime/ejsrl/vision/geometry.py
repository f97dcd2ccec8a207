"""Geometric image transforms: resize, rotate, flip, crop, affine and perspective warps.

Pixel coordinates are ``(x, y)`` = (column, row), as in OpenCV. The warps keep the
image's dtype for uint8, uint16, float32 and float64 (floats must be finite); other types
(bool, other integers) become uint8 as the ``ejsrl.vision`` module docstring says. Bad input is a
``ValueError``.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_image, as_points, choice, image_function, to_uint8

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
    a = as_image(img)
    if a.dtype not in (np.uint8, np.uint16, np.float32, np.float64):
        a = to_uint8(a)
    return np.ascontiguousarray(a)


def _n_points(p: ArrayLike, n: int, name: str) -> NDArray[np.float32]:
    a = as_points(p, name)
    if len(a) != n or not np.isfinite(a).all():
        raise ValueError(f"{name} must be {n} finite (x, y) points, got shape {np.shape(p)}")
    return a.astype(np.float32)


def _matrix(M: ArrayLike, shape: tuple[int, int], name: str) -> NDArray[np.float64]:
    a = np.asarray(M, dtype=np.float64)
    if a.size != shape[0] * shape[1] or not np.isfinite(a).all():
        raise ValueError(f"{name} must be a finite {shape[0]} x {shape[1]} matrix, got shape {a.shape}")
    return a.reshape(shape)


@image_function
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
        if not float(scale) > 0:
            raise ValueError(f"resize: scale must be positive, got {scale}")
        size = (max(1, round(a.shape[1] * scale)), max(1, round(a.shape[0] * scale)))
    if int(size[0]) < 1 or int(size[1]) < 1:
        raise ValueError(f"resize: size (width, height) must be at least 1 x 1, got {tuple(size)}")
    return cv2.resize(a, (int(size[0]), int(size[1])), interpolation=_INTERP[choice(interpolation, _INTERP, "interpolation")])


@image_function
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


@image_function
def flip(img: ArrayLike, axis: str = "horizontal") -> NDArray:
    """Mirror the image: "horizontal" (left-right), "vertical" (up-down) or "both"."""
    codes = {"horizontal": 1, "vertical": 0, "both": -1}
    code = codes[choice(axis, codes, "flip axis")]
    return cv2.flip(_img(img), code)


@image_function
def crop(img: ArrayLike, x: int, y: int, width: int, height: int) -> NDArray:
    """The ``width`` x ``height`` window whose top-left pixel is (``x``, ``y``), clipped to the image (a copy)."""
    a = as_image(img)
    H, W = a.shape[:2]
    if int(width) < 1 or int(height) < 1:
        raise ValueError(f"crop: width and height must be at least 1, got {width} x {height}")
    x0, y0 = max(0, int(x)), max(0, int(y))
    x1, y1 = min(W, int(x) + int(width)), min(H, int(y) + int(height))
    if x1 <= x0 or y1 <= y0:
        raise ValueError(f"crop: the window ({x}, {y}, {width} x {height}) lies outside the {W} x {H} image")
    return a[y0:y1, x0:x1].copy()


@image_function
def affine_matrix(src: ArrayLike, dst: ArrayLike) -> NDArray[np.float64]:
    """The (2, 3) affine matrix that maps 3 points ``src`` (3, 2) (x, y) onto ``dst`` (3, 2)."""
    return cv2.getAffineTransform(_n_points(src, 3, "src"), _n_points(dst, 3, "dst"))


@image_function
def perspective_matrix(src: ArrayLike, dst: ArrayLike) -> NDArray[np.float64]:
    """The (3, 3) homography that maps 4 points ``src`` (4, 2) (x, y) onto ``dst`` (4, 2)."""
    return cv2.getPerspectiveTransform(_n_points(src, 4, "src"), _n_points(dst, 4, "dst"))


@image_function
def warp_affine(img: ArrayLike, M: ArrayLike, size: tuple[int, int] | None = None, *, border: int = 0) -> NDArray:
    """Warp by the (2, 3) affine matrix ``M`` (destination (x, y) = M [x, y, 1] of the source).

    ``size``: output (width, height), default the input size; ``border``: fill value.
    """
    a = _img(img)
    h, w = a.shape[:2]
    dsize = (w, h) if size is None else (int(size[0]), int(size[1]))
    return cv2.warpAffine(a, _matrix(M, (2, 3), "M"), dsize, flags=cv2.INTER_LINEAR, borderValue=border)


@image_function
def warp_perspective(img: ArrayLike, H: ArrayLike, size: tuple[int, int] | None = None, *, border: int = 0) -> NDArray:
    """Warp by the (3, 3) homography ``H`` (source points map to ``H [x, y, 1]``, dehomogenised).

    ``size``: output (width, height), default the input size; ``border``: fill value.
    """
    a = _img(img)
    h, w = a.shape[:2]
    dsize = (w, h) if size is None else (int(size[0]), int(size[1]))
    return cv2.warpPerspective(a, _matrix(H, (3, 3), "H"), dsize, flags=cv2.INTER_LINEAR, borderValue=border)
