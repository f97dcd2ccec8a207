"""Distance transform, watershed segmentation and skeletons of binary images.

Conventions: a binary image is an (H, W) array of bool or real numbers (0/1, 0/255, ...)
whose non-zero pixels are foreground; an empty, complex or non-finite (NaN, inf) one is a
``ValueError``, as for every image function (the rules: :mod:`ejsrl.vision`). Distances are in pixels between pixel centres. Label images are
int32: 0 background, 1..n regions, and for :func:`watershed` -1 on the lines where
regions meet (OpenCV's convention).
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_image, as_rgb

__all__ = ["distance_transform", "watershed", "split_touching", "skeleton"]

_METRICS = {"euclidean": cv2.DIST_L2, "l1": cv2.DIST_L1, "chessboard": cv2.DIST_C}


def _binary(img: ArrayLike, name: str = "binary") -> NDArray[np.uint8]:
    a = as_image(img, name)  # the shared checks: None, dtype, shape, empty, NaN
    if a.ndim != 2:
        raise ValueError(f"{name} must be a 2-D (H, W) binary image, got {a.shape}; for an RGB image threshold it first")
    return (a != 0).astype(np.uint8)


def distance_transform(binary: ArrayLike, metric: str = "euclidean") -> NDArray[np.float32]:
    """For each foreground pixel, the distance (px) to the nearest background pixel (0 on the background).

    ``metric``: ``"euclidean"`` (exact), ``"l1"`` (city block) or ``"chessboard"``. An image
    with no background pixel gets a large value (OpenCV's) everywhere.
    """
    if metric not in _METRICS:
        raise ValueError(f"metric must be one of {sorted(_METRICS)}, got {metric!r}")
    mask = cv2.DIST_MASK_PRECISE if metric == "euclidean" else 3
    return cv2.distanceTransform(_binary(binary), _METRICS[metric], mask)


def watershed(img: ArrayLike, markers: ArrayLike, *, lines: bool = True) -> NDArray[np.int32]:
    """Marker-based watershed: the seeds flood the relief ``img`` from its lowest values up.

    ``img``: grey relief (H, W) uint8 (RGB is turned grey; floats are scaled to 0..255);
    ``markers`` (H, W) int: 1..n seed regions, 0 unknown. Every unknown pixel reachable
    from a seed gets the label of the basin that reaches it first, flooding level by
    level (Vincent and Soille's immersion, as MVTB, MATLAB and scikit-image do; OpenCV's
    ``cv2.watershed`` floods on colour differences instead). Fronts that meet in the same
    step are split to within a pixel. ``lines``: mark the pixels where basins meet with
    -1 (OpenCV's convention), on the lower-right side of each meeting.
    """
    a = as_image(img)  # the shared checks: None, dtype, shape, empty, NaN
    if a.ndim == 3:
        a = cv2.cvtColor(as_rgb(a), cv2.COLOR_RGB2GRAY)
    if a.dtype != np.uint8:
        f = a.astype(np.float64)
        lo, hi = f.min(), f.max()
        a = np.zeros(f.shape, np.uint8) if hi == lo else np.rint(255 * (f - lo) / (hi - lo)).astype(np.uint8)
    m = np.asarray(markers)
    if m.shape != a.shape:
        raise ValueError(f"markers must have the image's shape {a.shape}, got {m.shape}")
    if not np.issubdtype(m.dtype, np.integer):
        raise ValueError(f"markers must be integer labels, got {m.dtype}")
    if m.min(initial=0) < 0 or m.max(initial=0) >= 1 << 24:
        raise ValueError("markers must be in 0 .. 2**24 - 1 (0 for unknown pixels)")
    labels = m.astype(np.float32)
    cross = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
    for level in np.unique(a):
        allowed = (a <= level) & (labels == 0)
        while allowed.any():
            grown = cv2.dilate(labels, cross)
            new = allowed & (grown > 0)
            if not new.any():
                break
            labels[new] = grown[new]
            allowed &= ~new
    out = labels.astype(np.int32)
    if lines:
        edge = np.zeros(out.shape, bool)
        edge[:, 1:] |= (out[:, 1:] != out[:, :-1]) & (out[:, :-1] > 0) & (out[:, 1:] > 0)
        edge[1:, :] |= (out[1:, :] != out[:-1, :]) & (out[:-1, :] > 0) & (out[1:, :] > 0)
        out[edge] = -1
    return out


def split_touching(binary: ArrayLike, *, min_distance: float = 5.0) -> NDArray[np.int32]:
    """Separate touching round blobs: watershed of the distance transform seeded at its peaks.

    Peaks are local maxima of the distance at least ``min_distance`` px from the background
    and from each other. Returns labels (H, W) int32: 0 background, 1..n one per blob,
    the dividing lines given to the background.
    """
    fg = _binary(binary)
    d = distance_transform(fg)
    size = 2 * int(max(1.0, min_distance)) + 1
    peaks = (d == cv2.dilate(d, np.ones((size, size), np.uint8))) & (d >= min_distance)
    n, seeds = cv2.connectedComponents(peaks.astype(np.uint8), connectivity=8)
    markers = seeds.astype(np.int32)
    markers[fg == 0] = n  # the background is a basin of its own
    relief = np.rint(255 * (1 - d / max(float(d.max()), 1e-9))).astype(np.uint8)
    labels = watershed(relief, markers)
    labels[(labels == n) | (labels < 0) | (fg == 0)] = 0
    return labels


def skeleton(binary: ArrayLike, *, max_iterations: int = 10_000) -> NDArray[np.uint8]:
    """The skeleton (H, W) uint8 (255 on it) of a binary image by Zhang-Suen thinning.

    Thinning peels boundary pixels in two alternating sub-iterations until none can go,
    keeping each 8-connected shape connected and one pixel wide. Pixels on the image's
    border count as having background outside.
    """
    img = np.pad(_binary(binary), 1)
    for _ in range(max_iterations):
        changed = False
        for step in (0, 1):
            P = img
            # neighbours p2..p9 clockwise from north
            p2, p3, p4 = P[:-2, 1:-1], P[:-2, 2:], P[1:-1, 2:]
            p5, p6, p7 = P[2:, 2:], P[2:, 1:-1], P[2:, :-2]
            p8, p9 = P[1:-1, :-2], P[:-2, :-2]
            nbrs = (p2, p3, p4, p5, p6, p7, p8, p9)
            B = sum(n.astype(np.int32) for n in nbrs)
            seq = nbrs + (p2,)
            A = sum(((seq[i] == 0) & (seq[i + 1] == 1)).astype(np.int32) for i in range(8))
            if step == 0:
                c1, c2 = p2 * p4 * p6, p4 * p6 * p8
            else:
                c1, c2 = p2 * p4 * p8, p2 * p6 * p8
            remove = (P[1:-1, 1:-1] == 1) & (B >= 2) & (B <= 6) & (A == 1) & (c1 == 0) & (c2 == 0)
            if remove.any():
                img = img.copy()
                img[1:-1, 1:-1][remove] = 0
                changed = True
        if not changed:
            break
    return (img[1:-1, 1:-1] * 255).astype(np.uint8)
