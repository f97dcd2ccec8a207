"""Scale space: Gaussian and Laplacian pyramids, Laplacian of Gaussian and difference of Gaussians.

Conventions: a pyramid is a list of images, level 0 the input; each level halves the
size (``(w + 1) // 2`` by ``(h + 1) // 2``) after OpenCV's 5 x 5 Gaussian (``pyrDown``).
Filters work in float64 on grey images (RGB is turned grey), with ``sigma`` in pixels and
reflected borders (``BORDER_REFLECT_101``). :func:`log_filter` is scale-normalised by
default (multiplied by sigma^2), so its extreme over scales picks a blob's size: a disc of
radius r responds most at sigma = r / sqrt(2).
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_gray, as_image, to_uint8

__all__ = ["gaussian_pyramid", "laplacian_pyramid", "collapse_laplacian_pyramid", "log_filter", "dog_filter", "log_blobs"]

Float = NDArray[np.float64]


def _levels(levels: int) -> int:
    if int(levels) < 1:
        raise ValueError(f"levels must be at least 1, got {levels}")
    return int(levels)


def _float_gray(img: ArrayLike) -> Float:
    a = as_image(img)  # the shared checks: None, dtype, shape, empty, NaN
    if a.ndim == 2 and a.dtype.kind == "f":
        return a.astype(np.float64)  # a grey float image is filtered in its own units, any range
    return as_gray(a).astype(np.float64)


def gaussian_pyramid(img: ArrayLike, levels: int = 4) -> list[NDArray]:
    """``levels`` images: the input, then each blurred and halved (``cv2.pyrDown``).

    uint8, uint16, int16, float32 and float64 images keep their dtype (floats in any range,
    finite); bool and other integer images (values 0..255) become uint8.
    """
    n = _levels(levels)
    a = as_image(img)  # the shared checks: None, dtype, shape, empty, NaN
    if a.dtype == np.bool_ or (a.dtype.kind in "iu" and a.dtype not in (np.uint8, np.uint16, np.int16)):
        a = to_uint8(a)  # bool -> 0/255; other integers must lie in 0..255, as everywhere
    if a.dtype not in (np.uint8, np.uint16, np.int16, np.float32, np.float64):
        raise ValueError(
            f"img must be uint8, uint16, int16, float32 or float64 (OpenCV's pyrDown), got {a.dtype}; "
            "convert it, e.g. img.astype(np.float32)"
        )
    a = np.ascontiguousarray(a)
    out = [a]
    for _ in range(n - 1):
        if min(out[-1].shape[:2]) < 2:
            break
        out.append(cv2.pyrDown(out[-1]))
    return out


def laplacian_pyramid(img: ArrayLike, levels: int = 4) -> list[Float]:
    """Band-pass levels (float64): each Gaussian level minus the next one expanded, then the coarsest Gaussian level.

    :func:`collapse_laplacian_pyramid` rebuilds the image exactly.
    """
    g = [np.asarray(x, dtype=np.float64) for x in gaussian_pyramid(np.asarray(img), levels)]
    out = []
    for fine, coarse in zip(g[:-1], g[1:]):
        up = cv2.pyrUp(coarse, dstsize=(fine.shape[1], fine.shape[0]))
        out.append(fine - up)
    out.append(g[-1])
    return out


def collapse_laplacian_pyramid(pyramid: list[ArrayLike]) -> Float:
    """The image (float64) a Laplacian pyramid was made from."""
    if len(pyramid) == 0:
        raise ValueError("the pyramid is empty")
    img = np.asarray(pyramid[-1], dtype=np.float64)
    for band in reversed(pyramid[:-1]):
        b = np.asarray(band, dtype=np.float64)
        img = cv2.pyrUp(img, dstsize=(b.shape[1], b.shape[0])) + b
    return img


def _gauss(img: Float, sigma: float) -> Float:
    if not sigma > 0:
        raise ValueError(f"sigma must be positive, got {sigma}")
    return cv2.GaussianBlur(img, (0, 0), float(sigma), borderType=cv2.BORDER_REFLECT_101)


def log_filter(img: ArrayLike, sigma: float = 2.0, *, normalized: bool = True) -> Float:
    """Laplacian of Gaussian (float64, same size): ``sigma^2 (d2/dx2 + d2/dy2) (G_sigma * img)``.

    Dark blobs on light give positive peaks, light blobs negative ones. ``normalized=False``
    drops the sigma^2 factor. The kernel is sampled to 4 sigma; the Laplacian is exact
    on the Gaussian's own derivatives (separable second-derivative-of-Gaussian kernels).
    """
    a = _float_gray(img)
    if not sigma > 0:
        raise ValueError(f"sigma must be positive, got {sigma}")
    r = int(np.ceil(4 * sigma))
    x = np.arange(-r, r + 1, dtype=np.float64)
    g = np.exp(-(x**2) / (2 * sigma**2))
    g /= g.sum()
    g2 = g * (x**2 - sigma**2) / sigma**4  # second derivative of the (normalised) Gaussian
    g2 -= g2.mean()  # a flat image gives exactly 0
    lap = cv2.sepFilter2D(a, cv2.CV_64F, g2, g, borderType=cv2.BORDER_REFLECT_101)
    lap += cv2.sepFilter2D(a, cv2.CV_64F, g, g2, borderType=cv2.BORDER_REFLECT_101)
    return lap * sigma**2 if normalized else lap


def dog_filter(img: ArrayLike, sigma: float = 2.0, k: float = 1.6) -> Float:
    """Difference of Gaussians ``G_{k sigma} * img - G_sigma * img`` (float64), approximately
    ``(k - 1) sigma^2`` times the Laplacian of Gaussian (Lowe's SIFT scale space)."""
    if not k > 1:
        raise ValueError(f"k must be greater than 1, got {k}")
    a = _float_gray(img)
    return _gauss(a, k * sigma) - _gauss(a, sigma)


def log_blobs(img: ArrayLike, sigmas: ArrayLike = (1, 1.5, 2, 3, 4, 6, 8, 11, 16), *, threshold: float = 10.0, dark: bool = False) -> Float:
    """Blobs found as extremes of the normalised LoG over space and scale: (N, 3) rows ``(x, y, radius)``.

    Light blobs by default (``dark=True`` for dark ones); ``threshold`` is the least
    normalised response (grey levels); the radius is ``sqrt(2) * sigma``.
    """
    s = np.asarray(sigmas, dtype=np.float64).ravel()
    if len(s) < 1 or np.any(s <= 0):
        raise ValueError("sigmas must be positive")
    sign = 1.0 if dark else -1.0
    stack = np.stack([sign * log_filter(img, float(si)) for si in s])
    from scipy.ndimage import maximum_filter

    peak = (stack == maximum_filter(stack, size=(3, 3, 3), mode="nearest")) & (stack > threshold)
    k, y, x = np.nonzero(peak)
    order = np.argsort(-stack[k, y, x], kind="stable")
    return np.column_stack([x[order], y[order], np.sqrt(2) * s[k[order]]]).astype(np.float64)
