"""Shape descriptors from moments: Hu's seven invariants, and the equivalent ellipse.

Conventions as :func:`ejsrl.vision.moments` (OpenCV's ``cv2.moments``): a grey image
(bool or real numbers of any integer or float type, finite) weighs each pixel by its value
(``binary=True`` counts non-zero pixels as 1); a NaN, complex or empty image is a ``ValueError``; a contour
(M, 2) of float (x, y) points gives the moments of the polygon it encloses.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_image

__all__ = ["hu_moments", "ellipse_from_moments"]


def _moments(img_or_contour: ArrayLike, binary: bool) -> dict[str, float]:
    a = np.asarray(img_or_contour)
    if a.ndim == 2 and a.shape[1] == 2 and a.dtype.kind == "f":
        if len(a) < 3 or not np.all(np.isfinite(a)):
            raise ValueError("a contour needs at least 3 finite (x, y) points")
        m = cv2.moments(a.astype(np.float32).reshape(-1, 1, 2))
    else:
        a = as_image(img_or_contour)  # the shared checks: None, dtype, shape, empty, NaN
        if a.ndim != 2:
            raise ValueError(f"expected an (H, W) grey image or an (M, 2) float contour, got shape {a.shape}; use to_gray first")
        if a.dtype == np.bool_:
            a = a.astype(np.uint8)
        elif a.dtype.kind == "f":
            a = a.astype(np.float32)
        elif a.dtype not in (np.uint8, np.uint16, np.int16):
            a = a.astype(np.float64)  # cv2.moments takes no int32/int64: weigh by the same values in float
        m = cv2.moments(np.ascontiguousarray(a), binaryImage=bool(binary))
    if m["m00"] == 0:
        raise ValueError("the shape has zero area (an empty image or a degenerate contour)")
    return m


def hu_moments(img_or_contour: ArrayLike, *, binary: bool = False, log: bool = False) -> NDArray[np.float64]:
    """Hu's seven moment invariants (7,): unchanged by translation, scale and rotation (h7 changes sign under a mirror).

    ``log=True`` gives ``-sign(h) log10 |h|``, the usual scale for comparing shapes.
    """
    h = cv2.HuMoments(_moments(img_or_contour, binary)).ravel().astype(np.float64)
    if log:
        with np.errstate(divide="ignore"):
            h = -np.sign(h) * np.log10(np.abs(h))
    return h


def ellipse_from_moments(img_or_contour: ArrayLike, *, binary: bool = True) -> tuple[float, float, float, float, float]:
    """The ellipse with the same second moments: ``(x, y, a, b, theta)``: centre (px), semi-axes ``a >= b``
    (px) and the angle (radians) of the major axis from the x axis towards y (image rows)."""
    m = _moments(img_or_contour, binary)
    x, y = m["m10"] / m["m00"], m["m01"] / m["m00"]
    mu20, mu02, mu11 = m["mu20"] / m["m00"], m["mu02"] / m["m00"], m["mu11"] / m["m00"]
    common = math.sqrt(4 * mu11**2 + (mu20 - mu02) ** 2)
    l1, l2 = (mu20 + mu02 + common) / 2, (mu20 + mu02 - common) / 2
    return x, y, 2 * math.sqrt(l1), 2 * math.sqrt(max(l2, 0.0)), 0.5 * math.atan2(2 * mu11, mu20 - mu02)
