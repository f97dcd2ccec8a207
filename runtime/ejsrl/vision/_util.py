"""Input checks shared by the image functions."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["as_image", "as_gray", "as_rgb", "to_uint8", "as_points"]


def as_image(img: ArrayLike, name: str = "img") -> NDArray:
    """``img`` as a NumPy array of shape (H, W) or (H, W, 3); raise a clear error otherwise."""
    arr = np.asarray(img)
    if arr.ndim == 3 and arr.shape[2] == 1:
        arr = arr[:, :, 0]
    if arr.ndim not in (2, 3) or (arr.ndim == 3 and arr.shape[2] not in (3, 4)):
        raise ValueError(f"{name} must be an H x W grey or H x W x 3 RGB image, got shape {arr.shape}")
    if arr.ndim == 3 and arr.shape[2] == 4:
        arr = arr[:, :, :3]
    return arr


def to_uint8(img: ArrayLike) -> NDArray[np.uint8]:
    """Any image as uint8: floats in [0, 1] are scaled by 255, other values clipped to 0..255."""
    arr = np.asarray(img)
    if arr.dtype == np.uint8:
        return arr
    if arr.dtype == np.bool_:
        return arr.astype(np.uint8) * 255
    if np.issubdtype(arr.dtype, np.floating) and arr.size and float(np.nanmax(arr)) <= 1.0 and float(np.nanmin(arr)) >= 0.0:
        arr = arr * 255.0
    return np.clip(np.rint(arr), 0, 255).astype(np.uint8)


def as_gray(img: ArrayLike) -> NDArray[np.uint8]:
    """A grey uint8 image (H, W) from a grey or RGB image (RGB -> luma, ITU-R 601 weights)."""
    arr = to_uint8(as_image(img))
    if arr.ndim == 3:
        arr = cv2.cvtColor(np.ascontiguousarray(arr), cv2.COLOR_RGB2GRAY)
    return np.ascontiguousarray(arr)


def as_rgb(img: ArrayLike) -> NDArray[np.uint8]:
    """An RGB uint8 image (H, W, 3) from a grey or RGB image."""
    arr = to_uint8(as_image(img))
    if arr.ndim == 2:
        arr = cv2.cvtColor(np.ascontiguousarray(arr), cv2.COLOR_GRAY2RGB)
    return np.ascontiguousarray(arr)


def as_points(pts: ArrayLike) -> NDArray[np.float64]:
    """Points as an (N, 2) float64 array of (x, y)."""
    return np.asarray(pts, dtype=np.float64).reshape(-1, 2)
