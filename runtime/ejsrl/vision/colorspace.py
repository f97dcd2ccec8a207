"""Colour spaces: sRGB <-> CIE XYZ <-> CIE L*a*b* (D65 white, 2 degree observer).

Conventions: RGB images are sRGB, (H, W, 3) uint8 (0..255) or float in [0, 1]; XYZ is
float64 with Y = 1 for the white (sRGB white -> (0.9505, 1, 1.0888)); L*a*b* is float64
with L* in [0, 100] and a*, b* roughly in [-128, 127]. The sRGB transfer curve is
removed before the linear map to XYZ (as scikit-image and OpenCV's Lab do; OpenCV's own
RGB2XYZ skips it). Results back in RGB are float in [0, 1], clipped; use ``to_uint8``
style rounding (``np.rint(x * 255)``) for 8 bits.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["rgb_to_xyz", "xyz_to_rgb", "xyz_to_lab", "lab_to_xyz", "rgb_to_lab", "lab_to_rgb", "delta_e"]

Array = NDArray[np.float64]

#: linear sRGB -> XYZ (IEC 61966-2-1, D65), the matrix of OpenCV and scikit-image
XYZ_FROM_RGB = np.array([[0.412453, 0.357580, 0.180423], [0.212671, 0.715160, 0.072169], [0.019334, 0.119193, 0.950227]])
RGB_FROM_XYZ = np.linalg.inv(XYZ_FROM_RGB)
#: the D65 reference white (2 degree observer)
WHITE_D65 = np.array([0.95047, 1.0, 1.08883])


def _rgb(img: ArrayLike) -> Array:
    a = np.asarray(img)
    if a.ndim == 0 or a.shape[-1] != 3:
        raise ValueError(f"expected RGB values with 3 channels last, e.g. (H, W, 3), got shape {a.shape}")
    if a.dtype == np.uint8:
        return a.astype(np.float64) / 255.0
    if not np.issubdtype(a.dtype, np.floating):
        raise ValueError(f"RGB must be uint8 (0..255) or float in [0, 1], got {a.dtype}")
    a = a.astype(np.float64)
    if a.size and (not np.all(np.isfinite(a)) or a.min() < -1e-6 or a.max() > 1 + 1e-6):
        raise ValueError("float RGB must be finite and in [0, 1] (divide 8-bit values by 255)")
    return np.clip(a, 0.0, 1.0)


def _three(a: ArrayLike, name: str) -> Array:
    arr = np.asarray(a)
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"{name} must be real numbers, got dtype {arr.dtype}")
    arr = arr.astype(np.float64)
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise ValueError(f"{name} must have 3 channels last, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return arr


def rgb_to_xyz(img: ArrayLike) -> Array:
    """sRGB (uint8 or float in [0, 1]) -> CIE XYZ (float, Y of white = 1)."""
    c = _rgb(img)
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return lin @ XYZ_FROM_RGB.T


def xyz_to_rgb(xyz: ArrayLike) -> Array:
    """CIE XYZ -> sRGB float in [0, 1] (out-of-gamut colours clipped)."""
    lin = np.clip(_three(xyz, "xyz") @ RGB_FROM_XYZ.T, 0.0, 1.0)
    return np.clip(np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055), 0.0, 1.0)


_EPS = (6 / 29) ** 3  # 0.008856
_KAPPA = (29 / 6) ** 2 / 3  # 7.787


def xyz_to_lab(xyz: ArrayLike, white: ArrayLike = WHITE_D65) -> Array:
    """CIE XYZ -> L*a*b* relative to ``white`` (D65 by default)."""
    t = _three(xyz, "xyz") / np.asarray(white, dtype=np.float64)
    f = np.where(t > _EPS, np.cbrt(t), _KAPPA * t + 4 / 29)
    L = 116 * f[..., 1] - 16
    return np.stack([L, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], axis=-1)


def lab_to_xyz(lab: ArrayLike, white: ArrayLike = WHITE_D65) -> Array:
    """L*a*b* -> CIE XYZ relative to ``white`` (D65 by default)."""
    lab = _three(lab, "lab")
    fy = (lab[..., 0] + 16) / 116
    f = np.stack([fy + lab[..., 1] / 500, fy, fy - lab[..., 2] / 200], axis=-1)
    t = np.where(f > 6 / 29, f**3, (f - 4 / 29) / _KAPPA)
    return t * np.asarray(white, dtype=np.float64)


def rgb_to_lab(img: ArrayLike) -> Array:
    """sRGB (uint8 or float in [0, 1]) -> CIE L*a*b* (D65)."""
    return xyz_to_lab(rgb_to_xyz(img))


def lab_to_rgb(lab: ArrayLike) -> Array:
    """CIE L*a*b* (D65) -> sRGB float in [0, 1]."""
    return xyz_to_rgb(lab_to_xyz(lab))


def delta_e(lab1: ArrayLike, lab2: ArrayLike) -> Array:
    """CIE76 colour difference: the Euclidean distance between L*a*b* colours (about 2.3 is just noticeable)."""
    return np.linalg.norm(_three(lab1, "lab1") - _three(lab2, "lab2"), axis=-1)
