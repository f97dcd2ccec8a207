"""Smoothing and sharpening filters, teaching noise, and morphology.

Filters take a grey (H, W) or RGB (H, W, 3) image (uint8, or another type read as
the ``ejsrl.vision`` module docstring says) and return uint8 of the same shape; borders are reflected
(OpenCV's default, ``BORDER_REFLECT_101``). Bad input (empty, NaN, wrong shape or type, an
unknown option, an even kernel size where an odd one is needed) is a ``ValueError``.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_image, choice, image_function, to_uint8

__all__ = [
    "box_filter",
    "gaussian_blur",
    "median_blur",
    "bilateral_filter",
    "sharpen",
    "convolve",
    "add_gaussian_noise",
    "add_salt_pepper_noise",
    "structuring_element",
    "erode",
    "dilate",
    "morph_open",
    "morph_close",
    "morph_gradient",
    "top_hat",
    "black_hat",
]


def _u8(img: ArrayLike) -> NDArray[np.uint8]:
    return np.ascontiguousarray(to_uint8(img))


@image_function
def box_filter(img: ArrayLike, ksize: int = 3) -> NDArray[np.uint8]:
    """Mean of each ``ksize`` x ``ksize`` neighbourhood."""
    return cv2.blur(_u8(img), (int(ksize), int(ksize)))


@image_function
def gaussian_blur(img: ArrayLike, ksize: int = 5, sigma: float = 0.0) -> NDArray[np.uint8]:
    """Gaussian smoothing with an odd ``ksize`` kernel; ``sigma`` in pixels (0: from ksize, as OpenCV)."""
    return cv2.GaussianBlur(_u8(img), (int(ksize), int(ksize)), float(sigma))


@image_function
def median_blur(img: ArrayLike, ksize: int = 3) -> NDArray[np.uint8]:
    """Median of each odd ``ksize`` x ``ksize`` neighbourhood (removes salt-and-pepper noise)."""
    return cv2.medianBlur(_u8(img), int(ksize))


@image_function
def bilateral_filter(img: ArrayLike, d: int = 9, sigma_color: float = 75.0, sigma_space: float = 75.0) -> NDArray[np.uint8]:
    """Edge-preserving smoothing: neighbours (diameter ``d``) weigh by distance and by grey difference."""
    return cv2.bilateralFilter(_u8(img), int(d), float(sigma_color), float(sigma_space))


@image_function
def sharpen(img: ArrayLike, amount: float = 1.0) -> NDArray[np.uint8]:
    """Sharpen with the kernel ``[[0,-a,0],[-a,1+4a,-a],[0,-a,0]]`` (``a`` = ``amount``), saturated."""
    a = float(amount)
    k = np.array([[0, -a, 0], [-a, 1 + 4 * a, -a], [0, -a, 0]], dtype=np.float64)
    return cv2.filter2D(_u8(img), -1, k)


@image_function
def convolve(img: ArrayLike, kernel: ArrayLike, *, output: str = "uint8") -> NDArray:
    """Correlate the image with any 2-D ``kernel`` (as ``cv2.filter2D``: the kernel is not flipped).

    ``output``: "uint8" (saturated) or "float" (float64, signed values kept).
    """
    k = np.asarray(kernel, dtype=np.float64)
    if k.ndim != 2 or k.size == 0 or not np.isfinite(k).all():
        raise ValueError(f"convolve: kernel must be a non-empty finite 2-D array, got shape {k.shape}")
    if choice(output, ("uint8", "float"), "convolve output") == "float":
        return cv2.filter2D(np.asarray(as_image(img), dtype=np.float64), cv2.CV_64F, k)
    return cv2.filter2D(_u8(img), -1, k)


@image_function
def add_gaussian_noise(img: ArrayLike, sigma: float = 10.0, *, seed: int | None = None) -> NDArray[np.uint8]:
    """Add zero-mean Gaussian noise of standard deviation ``sigma`` grey levels, saturated to 0..255.

    ``seed``: for a repeatable result.
    """
    a = _u8(img)
    rng = np.random.default_rng(seed)
    return np.clip(np.rint(a + rng.normal(0.0, float(sigma), a.shape)), 0, 255).astype(np.uint8)


@image_function
def add_salt_pepper_noise(img: ArrayLike, amount: float = 0.05, *, salt_ratio: float = 0.5, seed: int | None = None) -> NDArray[np.uint8]:
    """Set a fraction ``amount`` of the pixels to white (salt) or black (pepper).

    ``salt_ratio``: share of them set white. ``seed``: for a repeatable result.
    """
    a = _u8(img).copy()
    rng = np.random.default_rng(seed)
    H, W = a.shape[:2]
    hit = rng.random((H, W)) < float(amount)
    salt = rng.random((H, W)) < float(salt_ratio)
    a[hit & salt] = 255
    a[hit & ~salt] = 0
    return a


@image_function
def structuring_element(shape: str = "rect", size: int = 3) -> NDArray[np.uint8]:
    """A ``size`` x ``size`` structuring element: "rect", "ellipse" or "cross" (uint8 0/1)."""
    shapes = {"rect": cv2.MORPH_RECT, "ellipse": cv2.MORPH_ELLIPSE, "cross": cv2.MORPH_CROSS}
    s = shapes[choice(shape, shapes, "structuring element shape")]
    if int(size) < 1:
        raise ValueError(f"structuring_element: size must be at least 1, got {size}")
    return cv2.getStructuringElement(s, (int(size), int(size)))


def _kernel(size: int | ArrayLike, shape: str) -> NDArray[np.uint8]:
    if np.ndim(size) == 0:
        return structuring_element(shape, int(size))  # type: ignore[arg-type]
    k = np.asarray(size, dtype=np.uint8)
    if k.ndim != 2 or k.size == 0:
        raise ValueError(f"a structuring element must be a non-empty 2-D 0/1 array, got shape {k.shape}")
    return k


@image_function
def erode(img: ArrayLike, size: int | ArrayLike = 3, *, shape: str = "rect", iterations: int = 1) -> NDArray[np.uint8]:
    """Minimum over the structuring element (``size`` or an explicit 0/1 kernel): shrinks bright regions."""
    return cv2.erode(_u8(img), _kernel(size, shape), iterations=int(iterations))


@image_function
def dilate(img: ArrayLike, size: int | ArrayLike = 3, *, shape: str = "rect", iterations: int = 1) -> NDArray[np.uint8]:
    """Maximum over the structuring element: grows bright regions."""
    return cv2.dilate(_u8(img), _kernel(size, shape), iterations=int(iterations))


def _morph(op: int, img: ArrayLike, size: int | ArrayLike, shape: str) -> NDArray[np.uint8]:
    return cv2.morphologyEx(_u8(img), op, _kernel(size, shape))


@image_function
def morph_open(img: ArrayLike, size: int | ArrayLike = 3, *, shape: str = "rect") -> NDArray[np.uint8]:
    """Opening (erode then dilate): removes bright specks smaller than the element."""
    return _morph(cv2.MORPH_OPEN, img, size, shape)


@image_function
def morph_close(img: ArrayLike, size: int | ArrayLike = 3, *, shape: str = "rect") -> NDArray[np.uint8]:
    """Closing (dilate then erode): fills dark holes smaller than the element."""
    return _morph(cv2.MORPH_CLOSE, img, size, shape)


@image_function
def morph_gradient(img: ArrayLike, size: int | ArrayLike = 3, *, shape: str = "rect") -> NDArray[np.uint8]:
    """Morphological gradient (dilation minus erosion): the outlines of regions."""
    return _morph(cv2.MORPH_GRADIENT, img, size, shape)


@image_function
def top_hat(img: ArrayLike, size: int | ArrayLike = 9, *, shape: str = "rect") -> NDArray[np.uint8]:
    """White top-hat (image minus its opening): bright details smaller than the element."""
    return _morph(cv2.MORPH_TOPHAT, img, size, shape)


@image_function
def black_hat(img: ArrayLike, size: int | ArrayLike = 9, *, shape: str = "rect") -> NDArray[np.uint8]:
    """Black top-hat (closing minus image): dark details smaller than the element."""
    return _morph(cv2.MORPH_BLACKHAT, img, size, shape)
