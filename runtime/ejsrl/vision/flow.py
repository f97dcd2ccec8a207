"""Dense optical flow between two frames (OpenCV's Farnebäck and DIS).

Convention: ``flow[r, c] = (dx, dy)`` in pixels, the motion of the content at pixel
``(x, y) = (c, r)`` of the first frame, so that ``next[y + dy, x + dx] ≈ prev[y, x]``.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_gray, as_image, image_function, resampled_dtype

__all__ = ["optical_flow", "flow_magnitude", "warp_by_flow"]

#: the smallest side (px) of frames for DIS: OpenCV 5's DIS raises on some smaller frames and
#: crashes the interpreter on others (8 to 14 rows and 60 columns, for one)
DIS_MIN_SIDE = 16


@image_function
def optical_flow(prev: ArrayLike, next: ArrayLike, method: str = "farneback", *, levels: int = 4, window: int = 15) -> NDArray[np.float32]:
    """Dense flow (H, W, 2) of ``(dx, dy)`` from ``prev`` to ``next`` (grey or RGB images of the same size).

    ``method``: ``"farneback"`` (polynomial expansion, default) or ``"dis"`` (dense inverse
    search, faster, OpenCV's "medium" preset; frames of at least 16 x 16 px: OpenCV's DIS
    refuses or crashes on smaller ones); ``levels`` and ``window`` (px) tune Farnebäck's
    pyramid and averaging window.
    """
    a, b = as_gray(prev), as_gray(next)
    if a.shape != b.shape or a.size == 0:
        raise ValueError(f"prev and next must be non-empty images of the same size, got {a.shape} and {b.shape}")
    if method == "farneback":
        if levels < 1 or window < 3:
            raise ValueError(f"levels must be >= 1 and window >= 3, got {levels} and {window}")
        return cv2.calcOpticalFlowFarneback(a, b, None, 0.5, int(levels), int(window), 5, 5, 1.1, 0)
    if method == "dis":
        if min(a.shape) < DIS_MIN_SIDE:
            raise ValueError(
                f"optical_flow 'dis' needs frames of at least {DIS_MIN_SIDE} x {DIS_MIN_SIDE} px, got "
                f"{a.shape[1]} x {a.shape[0]}; use 'farneback' for smaller ones"
            )
        dis = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM)
        return dis.calc(a, b, None)
    raise ValueError(f"method must be 'farneback' or 'dis', got {method!r}")


def _flow(flow: ArrayLike) -> NDArray[np.float32]:
    """A flow field as (H, W, 2) float32; ValueError if it is not one (shape, empty, complex, NaN)."""
    f = np.asarray(flow)
    if f.dtype.kind not in "iuf":
        raise ValueError(f"flow must be real numbers, got dtype {f.dtype}")
    if f.ndim != 3 or f.shape[2] != 2 or f.size == 0:
        raise ValueError(f"flow must have shape (H, W, 2), H and W at least 1, got {f.shape}")
    f = f.astype(np.float32)
    if not np.isfinite(f).all():
        raise ValueError("flow has NaN or infinite values; replace them first (np.nan_to_num)")
    return f


def flow_magnitude(flow: ArrayLike) -> NDArray[np.float32]:
    """The speed (H, W) in pixels per frame of a flow field (H, W, 2)."""
    f = _flow(flow)
    return np.hypot(f[..., 0], f[..., 1])


@image_function
def warp_by_flow(next: ArrayLike, flow: ArrayLike) -> NDArray:
    """``next`` sampled at ``(x + dx, y + dy)``: an estimate of the first frame (for checking a flow).

    The image keeps its dtype (uint8, uint16, int16, float32/64); bool and other integer
    images (0..255) come back as uint8.
    """
    img = np.ascontiguousarray(resampled_dtype(as_image(next, "next"), "next"))  # the shared checks: None, dtype, shape, empty, NaN
    f = _flow(flow)
    if f.shape[:2] != img.shape[:2]:
        raise ValueError(f"flow must have shape (H, W, 2) matching the image, got {f.shape} and {img.shape}")
    h, w = f.shape[:2]
    gx, gy = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
    return cv2.remap(img, gx + f[..., 0], gy + f[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
