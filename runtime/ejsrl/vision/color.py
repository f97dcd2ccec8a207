"""Colour conversions, thresholds, intensity adjustment and histograms.

Images are NumPy arrays: (H, W) grey or (H, W, 3) RGB (channel order R, G, B, as the
renderer and the browser give them; OpenCV's BGR never shows outside), uint8 0..255 or
another type read as the ``ejsrl.vision`` module docstring says (bool masks, uint16, floats in [0, 1]);
every function returns uint8 unless it says otherwise. Bad input (empty, NaN, wrong shape
or type, an unknown option) is a ``ValueError``.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_gray, as_image, as_rgb, choice, image_function, to_uint8

__all__ = [
    "to_gray",
    "to_rgb",
    "rgb_to_hsv",
    "hsv_to_rgb",
    "threshold",
    "threshold_otsu",
    "threshold_adaptive",
    "invert",
    "normalize",
    "adjust_brightness_contrast",
    "adjust_gamma",
    "equalize_histogram",
    "clahe",
    "histogram",
]

Image = NDArray[np.uint8]


@image_function
def to_gray(img: ArrayLike) -> Image:
    """Grey (H, W) uint8 of an RGB or grey image: luma ``0.299 R + 0.587 G + 0.114 B`` (OpenCV)."""
    return as_gray(img)


@image_function
def to_rgb(img: ArrayLike) -> Image:
    """RGB (H, W, 3) uint8 of a grey or RGB image (grey is copied to the three channels)."""
    return as_rgb(img)


@image_function
def rgb_to_hsv(img: ArrayLike) -> Image:
    """HSV (H, W, 3) uint8 of an RGB image, OpenCV ranges: hue 0..179 (degrees / 2), S and V 0..255."""
    return cv2.cvtColor(as_rgb(img), cv2.COLOR_RGB2HSV)


@image_function
def hsv_to_rgb(hsv: ArrayLike) -> Image:
    """RGB (H, W, 3) uint8 of an HSV (H, W, 3) image in OpenCV ranges (hue 0..179)."""
    a = to_uint8(hsv, "hsv")
    if a.ndim != 3:
        raise ValueError(f"hsv_to_rgb needs an (H, W, 3) HSV image, got shape {a.shape}")
    return cv2.cvtColor(np.ascontiguousarray(a), cv2.COLOR_HSV2RGB)


@image_function
def threshold(img: ArrayLike, level: float | None = None, *, maxval: int = 255, inverse: bool = False) -> Image:
    """Binary image (H, W) uint8: ``maxval`` where grey > ``level`` (or <= with ``inverse``), else 0.

    ``level`` is in the image's own units: grey levels 0..255 for uint8 (default 128),
    0..1 for a float image (default 0.5), 0..65535 for uint16 (default 32768). An RGB image
    is compared on its luma ``0.299 R + 0.587 G + 0.114 B`` in those units.
    """
    arr = as_image(img)
    kind = cv2.THRESH_BINARY_INV if inverse else cv2.THRESH_BINARY
    if arr.dtype.kind == "f" or arr.dtype == np.uint16:
        to_uint8(arr)  # the range checks
        native = np.asarray(arr, dtype=np.float32)
        if native.ndim == 3:
            native = cv2.cvtColor(np.ascontiguousarray(native), cv2.COLOR_RGB2GRAY)
        top = 1.0 if arr.dtype.kind == "f" else 65535.0
        lv = 0.5 * top if level is None else float(level)
        return cv2.threshold(np.ascontiguousarray(native), lv, maxval, kind)[1].astype(np.uint8)
    return cv2.threshold(as_gray(arr), 128.0 if level is None else float(level), maxval, kind)[1]


@image_function
def threshold_otsu(img: ArrayLike, *, inverse: bool = False) -> tuple[Image, float]:
    """Binary image by Otsu's threshold (the level that best separates two grey classes).

    Returns ``(binary (H, W) uint8 0/255, level)``.
    """
    kind = (cv2.THRESH_BINARY_INV if inverse else cv2.THRESH_BINARY) + cv2.THRESH_OTSU
    level, out = cv2.threshold(as_gray(img), 0, 255, kind)
    return out, float(level)


@image_function
def threshold_adaptive(
    img: ArrayLike, block_size: int = 11, C: float = 2.0, *, method: str = "mean", inverse: bool = False
) -> Image:
    """Binary image thresholded against the local mean (or Gaussian-weighted mean) minus ``C``.

    ``block_size``: odd neighbourhood size in pixels; ``method``: "mean" or "gaussian".
    Returns (H, W) uint8 0/255.
    """
    methods = {"mean": cv2.ADAPTIVE_THRESH_MEAN_C, "gaussian": cv2.ADAPTIVE_THRESH_GAUSSIAN_C}
    m = methods[choice(method, methods, "threshold_adaptive method")]
    kind = cv2.THRESH_BINARY_INV if inverse else cv2.THRESH_BINARY
    return cv2.adaptiveThreshold(as_gray(img), 255, m, kind, int(block_size), float(C))


@image_function
def invert(img: ArrayLike) -> Image:
    """Negative of a uint8 image: ``255 - img`` (grey or RGB)."""
    return cv2.bitwise_not(np.ascontiguousarray(to_uint8(img)))


@image_function
def normalize(img: ArrayLike, lo: float = 0, hi: float = 255) -> Image:
    """Stretch the values linearly so the minimum maps to ``lo`` and the maximum to ``hi``.

    Accepts any numeric image of any range (for example a float gradient; NaN is refused);
    returns uint8 of the same shape.
    """
    arr = np.asarray(as_image(img), dtype=np.float64)
    return cv2.normalize(arr, None, float(lo), float(hi), cv2.NORM_MINMAX).round().clip(0, 255).astype(np.uint8)


@image_function
def adjust_brightness_contrast(img: ArrayLike, brightness: float = 0.0, contrast: float = 1.0) -> Image:
    """``contrast * img + brightness``, rounded and saturated to 0..255 (grey or RGB uint8).

    ``brightness`` in grey levels (-255..255), ``contrast`` a factor (1: unchanged). A
    negative result is 0, not its absolute value.
    """
    lut = np.clip(np.rint(float(contrast) * np.arange(256) + float(brightness)), 0, 255).astype(np.uint8)
    return cv2.LUT(np.ascontiguousarray(to_uint8(img)), lut)


@image_function
def adjust_gamma(img: ArrayLike, gamma: float = 1.0) -> Image:
    """Gamma correction ``255 * (img / 255) ** (1 / gamma)``: gamma > 1 brightens the dark tones."""
    if not float(gamma) > 0:
        raise ValueError(f"adjust_gamma: gamma must be positive, got {gamma}")
    lut = np.clip(np.rint(255.0 * (np.arange(256) / 255.0) ** (1.0 / float(gamma))), 0, 255).astype(np.uint8)
    return cv2.LUT(np.ascontiguousarray(to_uint8(img)), lut)


@image_function
def equalize_histogram(img: ArrayLike) -> Image:
    """Histogram equalisation of a grey image; an RGB image is equalised on its luma (YCrCb)."""
    arr = to_uint8(img)
    if arr.ndim == 2:
        return cv2.equalizeHist(np.ascontiguousarray(arr))
    ycc = cv2.cvtColor(np.ascontiguousarray(arr), cv2.COLOR_RGB2YCrCb)
    ycc[:, :, 0] = cv2.equalizeHist(np.ascontiguousarray(ycc[:, :, 0]))
    return cv2.cvtColor(ycc, cv2.COLOR_YCrCb2RGB)


@image_function
def clahe(img: ArrayLike, clip_limit: float = 2.0, tile_grid: tuple[int, int] = (8, 8)) -> Image:
    """Contrast-limited adaptive histogram equalisation (grey; RGB on its luma).

    ``clip_limit``: contrast limit per tile; ``tile_grid``: tiles across and down.
    """
    op = cv2.createCLAHE(clipLimit=float(clip_limit), tileGridSize=tuple(int(v) for v in tile_grid))
    arr = to_uint8(img)
    if arr.ndim == 2:
        return op.apply(np.ascontiguousarray(arr))
    ycc = cv2.cvtColor(np.ascontiguousarray(arr), cv2.COLOR_RGB2YCrCb)
    ycc[:, :, 0] = op.apply(np.ascontiguousarray(ycc[:, :, 0]))
    return cv2.cvtColor(ycc, cv2.COLOR_YCrCb2RGB)


@image_function
def histogram(img: ArrayLike, bins: int = 256, *, channel: int | None = None) -> NDArray[np.float64]:
    """Histogram of a uint8 image over 0..255 in ``bins`` bins.

    Grey: (bins,) counts. RGB: (3, bins), one row per channel, or (bins,) for ``channel``.
    """
    arr = to_uint8(img)
    if arr.ndim == 2:
        return cv2.calcHist([np.ascontiguousarray(arr)], [0], None, [int(bins)], [0, 256]).ravel().astype(np.float64)
    if channel is not None and int(channel) not in (0, 1, 2):
        raise ValueError(f"histogram: channel must be 0, 1 or 2 (R, G, B), got {channel}")
    chans = range(3) if channel is None else [int(channel)]
    out = np.stack(
        [cv2.calcHist([np.ascontiguousarray(arr)], [c], None, [int(bins)], [0, 256]).ravel() for c in chans]
    ).astype(np.float64)
    return out[0] if channel is not None else out
