"""Input checks shared by the image functions: one place that says what an image is.

(The rules below are stated for users in the ``ejsrl.vision`` module docstring; keep the two alike.)

The conventions every image function of ``ejsrl.vision`` follows:

- **Shape.** (H, W) grey, (H, W, 3) RGB or (H, W, 4) RGBA (the alpha channel is dropped);
  (H, W, 1) counts as grey. Any other shape, and an empty image (H or W of 0), is a
  ``ValueError``.
- **Channel order.** R, G, B, as the renderer and the browser give them; OpenCV's BGR
  never shows outside.
- **Values.** uint8 0..255 is the native type. Other types are read as follows, and
  anything else is a ``ValueError`` rather than a silent guess:

  ========================  ================================================================
  bool                      False -> 0, True -> 255 (a mask)
  uint8                     as is
  uint16                    the full range 0..65535 scaled to 0..255 (``round(v / 257)``)
  other integers            must already lie in 0..255 (Python ints give int64 arrays)
  float16/32/64             must be finite and lie in [0, 1] (scaled by 255); use
                            ``normalize`` for another range
  ========================  ================================================================

- **Options** given as strings ("mean", "ellipse", ...) are checked: an unknown one is a
  ``ValueError`` that lists the known ones.
"""

from __future__ import annotations

import difflib
import functools
from collections.abc import Callable, Iterable
from typing import Any, TypeVar

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["as_image", "as_gray", "as_rgb", "to_uint8", "as_points", "as_remap_source", "resampled_dtype", "choice", "image_function", "IMAGE_CONVENTIONS"]

#: one line on what the image functions accept, for error messages
IMAGE_CONVENTIONS = (
    "an image is an (H, W) grey or (H, W, 3) RGB array of uint8 0..255, uint16, bool, "
    "or finite floats in [0, 1]"
)

F = TypeVar("F", bound=Callable[..., Any])


def _describe(arr: NDArray) -> str:
    return f"shape {arr.shape}, dtype {arr.dtype}"


def as_image(img: ArrayLike, name: str = "img", *, finite: bool = True) -> NDArray:
    """``img`` as a NumPy array of shape (H, W) or (H, W, 3), any supported dtype; ValueError otherwise.

    Checks the shape (an (H, W, 4) RGBA image loses its alpha, (H, W, 1) becomes grey), that
    the image is not empty, that the dtype is a number or bool, and (``finite``) that a float
    image has no NaN or infinity.
    """
    if img is None:
        raise ValueError(f"{name} is None; {IMAGE_CONVENTIONS}")
    try:
        arr = np.asarray(img)
    except Exception as e:  # ragged lists and the like
        raise ValueError(f"{name} is not an image ({e}); {IMAGE_CONVENTIONS}") from None
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"{name} has dtype {arr.dtype}, not a number; {IMAGE_CONVENTIONS}")
    if arr.ndim == 3 and arr.shape[2] == 1:
        arr = arr[:, :, 0]
    if arr.ndim not in (2, 3) or (arr.ndim == 3 and arr.shape[2] not in (3, 4)):
        raise ValueError(f"{name} must be an H x W grey or H x W x 3 RGB image, got {_describe(arr)}")
    if arr.shape[0] == 0 or arr.shape[1] == 0:
        raise ValueError(f"{name} is empty ({arr.shape[0]} x {arr.shape[1]} pixels); an image needs at least one pixel")
    if arr.ndim == 3 and arr.shape[2] == 4:
        arr = arr[:, :, :3]
    if finite and arr.dtype.kind == "f" and not np.isfinite(arr).all():
        bad = int(np.size(arr) - np.count_nonzero(np.isfinite(arr)))
        raise ValueError(f"{name} has {bad} NaN or infinite value(s); replace them first (np.nan_to_num) or mask them out")
    if arr.dtype == np.float16:
        arr = arr.astype(np.float32)
    return arr


def to_uint8(img: ArrayLike, name: str = "img") -> NDArray[np.uint8]:
    """Any supported image as uint8 0..255, by the rules in this module's docstring; ValueError otherwise."""
    arr = as_image(img, name)
    kind = arr.dtype.kind
    if arr.dtype == np.uint8:
        return arr
    if kind == "b":
        return arr.astype(np.uint8) * np.uint8(255)
    if arr.dtype == np.uint16:
        return ((arr.astype(np.uint32) * 255 + 32767) // 65535).astype(np.uint8)
    lo, hi = arr.min(), arr.max()
    if kind in "iu":
        if lo < 0 or hi > 255:
            raise ValueError(
                f"{name} is an integer image ({arr.dtype}) with values {lo}..{hi}, outside 0..255; "
                "rescale it (normalize(img) maps any range to 0..255) or clip it (np.clip(img, 0, 255))"
            )
        return arr.astype(np.uint8)
    if lo < 0.0 or hi > 1.0:
        raise ValueError(
            f"{name} is a float image with values {float(lo):.4g}..{float(hi):.4g}; float images must lie in [0, 1]. "
            "Scale it (img / 255 for 0..255 values, or normalize(img) for any range) or clip it (np.clip(img, 0, 1))"
        )
    return np.rint(arr * 255.0).astype(np.uint8)


def as_gray(img: ArrayLike, name: str = "img") -> NDArray[np.uint8]:
    """A grey uint8 image (H, W) from a grey or RGB image (RGB -> luma, ITU-R 601 weights)."""
    arr = to_uint8(img, name)
    if arr.ndim == 3:
        arr = cv2.cvtColor(np.ascontiguousarray(arr), cv2.COLOR_RGB2GRAY)
    return np.ascontiguousarray(arr)


def as_rgb(img: ArrayLike, name: str = "img") -> NDArray[np.uint8]:
    """An RGB uint8 image (H, W, 3) from a grey or RGB image."""
    arr = to_uint8(img, name)
    if arr.ndim == 2:
        arr = cv2.cvtColor(np.ascontiguousarray(arr), cv2.COLOR_GRAY2RGB)
    return np.ascontiguousarray(arr)


def as_remap_source(img: ArrayLike, name: str = "img") -> NDArray:
    """An image or depth map to be resampled (``cv2.remap``): (H, W) or (H, W, C), non-empty, real.

    uint8, uint16, int16 and float32/64 keep their type and values, NaN and infinity included
    (a depth map's ``inf`` means nothing seen); bool and other integers (0..255) become uint8,
    float16 becomes float32; anything else is a ValueError.
    """
    if img is None:
        raise ValueError(f"{name} is None; {IMAGE_CONVENTIONS}")
    arr = np.asarray(img)
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"{name} has dtype {arr.dtype}, not real numbers; {IMAGE_CONVENTIONS}")
    if arr.ndim not in (2, 3) or arr.shape[0] == 0 or arr.shape[1] == 0 or (arr.ndim == 3 and arr.shape[2] == 0):
        raise ValueError(f"{name} must be a non-empty H x W or H x W x C image, got shape {arr.shape}")
    return resampled_dtype(arr, name)


def resampled_dtype(arr: NDArray, name: str = "img") -> NDArray:
    """An image in a type that resampling (``cv2.remap``) keeps: uint8, uint16, int16 and
    float32/64 as they are; bool and other integers (0..255) as uint8; float16 as float32."""
    if arr.dtype == np.bool_ or (arr.dtype.kind in "iu" and arr.dtype not in (np.uint8, np.uint16, np.int16)):
        return to_uint8(arr, name)
    if arr.dtype == np.float16:
        return arr.astype(np.float32)
    return arr


def as_points(pts: ArrayLike, name: str = "points", *, k: int = 2) -> NDArray[np.float64]:
    """Points as an (N, k) float64 array (``k`` = 2: (x, y)); ValueError if they do not reshape so."""
    try:
        a = np.asarray(pts, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name} must be numbers, an (N, {k}) array: {e}") from None
    if a.size % k:
        raise ValueError(f"{name} must be an (N, {k}) array, got shape {a.shape}")
    return a.reshape(-1, k)


def choice(value: Any, options: Iterable[str], what: str) -> str:
    """``value`` if it is one of ``options``; else a ValueError naming ``what`` and the known options."""
    opts = list(options)
    if isinstance(value, str) and value in opts:
        return value
    close = difflib.get_close_matches(str(value), opts, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise ValueError(f"unknown {what} {value!r}{hint} (use one of {', '.join(repr(o) for o in opts)})")


def image_function(fn: F) -> F:
    """Decorate an image function: OpenCV's own refusals (``cv2.error``) become a ValueError naming it.

    The inputs are checked by ``as_image`` and friends first; what is left for OpenCV to refuse
    are option values (an even kernel size, say), reported here with OpenCV's reason.
    """

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except cv2.error as e:
            reason = str(e).strip().splitlines()[-1] if str(e).strip() else "no reason given"
            raise ValueError(f"{fn.__name__}: OpenCV refused the arguments: {reason}") from None

    return wrapper  # type: ignore[return-value]
