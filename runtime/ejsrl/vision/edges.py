"""Edge operators: Sobel, Scharr, Prewitt, Roberts, Laplacian, gradient magnitude, Canny.

The derivative operators return float64 images (signed) so students see the sign of the
gradient; ``normalize`` turns them into viewable uint8. ``x`` is along columns, ``y``
along rows (down). Input: a grey or RGB image (uint8, or another type read as
the ``ejsrl.vision`` module docstring says); bad input is a ``ValueError``.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_gray, choice, image_function

__all__ = ["sobel", "scharr", "prewitt", "roberts", "laplacian", "gradient_magnitude", "canny"]

Float = NDArray[np.float64]

_PREWITT_X = np.array([[-1, 0, 1], [-1, 0, 1], [-1, 0, 1]], dtype=np.float64)
_ROBERTS_1 = np.array([[1, 0], [0, -1]], dtype=np.float64)
_ROBERTS_2 = np.array([[0, 1], [-1, 0]], dtype=np.float64)


def _pair(gx: Float, gy: Float, direction: str) -> Float | tuple[Float, Float]:
    if direction == "x":
        return gx
    if direction == "y":
        return gy
    if direction == "both":
        return gx, gy
    choice(direction, ("x", "y", "both", "magnitude"), "direction")
    return np.hypot(gx, gy)


@image_function
def sobel(img: ArrayLike, direction: str = "magnitude", ksize: int = 3) -> Float | tuple[Float, Float]:
    """Sobel derivative of the grey image (float64).

    ``direction``: "x" (d/dcolumn), "y" (d/drow), "both" -> (gx, gy), or "magnitude".
    ``ksize``: 1, 3, 5 or 7.
    """
    g = as_gray(img)
    gx = cv2.Sobel(g, cv2.CV_64F, 1, 0, ksize=int(ksize))
    gy = cv2.Sobel(g, cv2.CV_64F, 0, 1, ksize=int(ksize))
    return _pair(gx, gy, direction)


@image_function
def scharr(img: ArrayLike, direction: str = "magnitude") -> Float | tuple[Float, Float]:
    """Scharr derivative (a 3x3 kernel more rotation-invariant than Sobel's); see ``sobel``."""
    g = as_gray(img)
    return _pair(cv2.Scharr(g, cv2.CV_64F, 1, 0), cv2.Scharr(g, cv2.CV_64F, 0, 1), direction)


@image_function
def prewitt(img: ArrayLike, direction: str = "magnitude") -> Float | tuple[Float, Float]:
    """Prewitt derivative (kernel [[-1,0,1]]*3 and its transpose); see ``sobel``."""
    g = as_gray(img).astype(np.float64)
    return _pair(cv2.filter2D(g, cv2.CV_64F, _PREWITT_X), cv2.filter2D(g, cv2.CV_64F, _PREWITT_X.T), direction)


@image_function
def roberts(img: ArrayLike, direction: str = "magnitude") -> Float | tuple[Float, Float]:
    """Roberts cross: the two diagonal differences ``I(r,c) - I(r+1,c+1)`` and ``I(r,c+1) - I(r+1,c)``.

    "x" and "y" give the two diagonals; the last row and column are 0.
    """
    g = as_gray(img).astype(np.float64)
    d1 = np.zeros_like(g)
    d2 = np.zeros_like(g)
    d1[:-1, :-1] = g[:-1, :-1] - g[1:, 1:]
    d2[:-1, :-1] = g[:-1, 1:] - g[1:, :-1]
    return _pair(d1, d2, direction)


@image_function
def laplacian(img: ArrayLike, ksize: int = 1) -> Float:
    """Laplacian ``d2I/dx2 + d2I/dy2`` (float64); ``ksize`` 1 is the 4-neighbour kernel."""
    return cv2.Laplacian(as_gray(img), cv2.CV_64F, ksize=int(ksize))


@image_function
def gradient_magnitude(img: ArrayLike) -> NDArray[np.uint8]:
    """Sobel gradient magnitude scaled to uint8 0..255 (for display)."""
    m = sobel(img, "magnitude")
    top = float(m.max())  # type: ignore[union-attr]
    return np.zeros(np.shape(m), np.uint8) if top == 0 else np.rint(255.0 * m / top).astype(np.uint8)  # type: ignore[operator]


@image_function
def canny(img: ArrayLike, low: float = 50.0, high: float = 150.0, *, aperture: int = 3, l2: bool = False) -> NDArray[np.uint8]:
    """Canny edges (H, W) uint8 0/255 with hysteresis thresholds ``low`` < ``high`` on the gradient."""
    return cv2.Canny(as_gray(img), float(low), float(high), apertureSize=int(aperture), L2gradient=bool(l2))
