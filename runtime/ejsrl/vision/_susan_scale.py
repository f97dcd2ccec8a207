"""SUSAN at the image's own scale and contrast: the mask widened for blurred images
(``susan_corners(blur=...)``), the brightness threshold read from the image (``t="auto"``:
``auto_threshold``, from ``estimate_noise`` and ``edge_steps``).

SUSAN's 37-pixel mask (radius 3.4 px) was made for sharp edges: an edge blurred by a
Gaussian of sigma about 1 px or more spreads over most of the mask, the nucleus' grey is
shared by too many pixels, and corners vanish (X-junctions first). Here the detector keeps its
tests and its threshold and works at a coarser scale instead: the image is averaged down by
``f = SCALE_PER_BLUR * sigma`` (``cv2.INTER_AREA``), which is the paper's mask laid over
``f x f`` pixel cells (a mask of radius 3.4 f px); the corners found there are refined there
(a blurred corner fills the coarse refinement window as a sharp one fills the fine one),
brought back, and refined again on the full image in the refinement's window widened by the
same factor (Foerstner's point in (6f + 1)^2 pixels: a 7 x 7 window sees only the middle of a
blurred corner, and put blurred checkerboards' corners 0.38 px off, now 0.10).

Measured (bench/susan_recall.py --suite blur, 5 scenes each; tests/vision/test_susan_blur.py
on other seeds), recall / precision / median error against GFTT + ``cornerSubPix`` asked for
as many corners: checkerboards blurred 1 px 1.00/0.63/0.09 px (GFTT 1.00/0.62/0.10), 1.5 px
0.97/0.63/0.10 (1.00/0.61/0.13); rendered boxes at the camera's blur 1 px and noise 2
0.62/0.66/0.19 (0.66/0.70/0.28), 1.5 px 0.59/0.68/0.27 (0.53/0.61/0.43); small polygons blurred
1 px 0.97/0.99/0.22 (0.96/0.98/0.33), 1.5 px 0.96/0.98/0.36 (0.86/0.88/0.58).

``sigma`` is given (the virtual camera's ``blur``, added in quadrature to the ~0.65 px a sharp
anti-aliased edge already has) or estimated: ``estimate_blur`` (the re-blur gradient ratio of
Zhuo and Sim 2011: at the strongest edge pixels, the gradient of the image over the gradient
of the image blurred again by sigma0 = 1 px is ``sqrt(sigma^2 + sigma0^2) / sigma``; the median
over edges). It reads about 0.65-0.75 px on sharp anti-aliased pictures, 1.0-1.2 at a blur of
1 px, 1.5-1.6 at 1.5 px (checkerboards and rendered cubes; small polygons in noise read low,
about 1.1 at 1.5 px; 0.95-1.0 at 1 px). Images that read at most ``BLUR_LIMIT`` are searched as
before (sharp anti-aliased pictures read 0.65-0.75).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import cv2
import numpy as np
from numpy.typing import NDArray

__all__ = ["estimate_blur", "estimate_noise", "edge_steps", "auto_threshold", "blur_scale", "BLUR_LIMIT", "SCALE_PER_BLUR", "SHARP_BLUR",
           "T_MIN", "T_MAX", "T_PER_NOISE", "T_PER_STEP"]

#: images whose blur reads at most this (px) are searched at full resolution (0.9: small polygons
#: blurred 1 px read 0.95-1.0, and were searched so, at 0.86 of GFTT's 0.96-0.99)
BLUR_LIMIT: float = 0.9
#: the averaging factor per pixel of blur (measured on the scene suites of bench/susan_recall.py)
SCALE_PER_BLUR: float = 1.7
#: the blur a sharp, anti-aliased edge reads (px): a camera's own blur adds to it in quadrature
SHARP_BLUR: float = 0.65


def _gradient(a: NDArray[np.float32]) -> NDArray[np.float32]:
    gx = cv2.Sobel(a, cv2.CV_32F, 1, 0, ksize=1)
    gy = cv2.Sobel(a, cv2.CV_32F, 0, 1, ksize=1)
    return cv2.magnitude(gx, gy)


def estimate_blur(gray: NDArray[np.uint8], sigma0: float = 1.0) -> float:
    """The blur of a grey image, as the sigma (px) of a Gaussian: the median over its strongest
    edge pixels (top 3 % of the gradient, at their 3x3 maxima) of ``sigma0 / sqrt(R^2 - 1)``,
    R the gradient's ratio before and after blurring again by ``sigma0``. 0 when the image has
    fewer than 20 such pixels (nothing to read it from). About 1.5 ms at 640x480."""
    g = np.asarray(gray, dtype=np.float32)
    m1 = _gradient(g)
    m2 = _gradient(cv2.GaussianBlur(g, (0, 0), sigma0))
    thr = float(np.percentile(m1[::2, ::2], 97))
    peak = cv2.dilate(m1, np.ones((3, 3), np.uint8))
    sel = (m1 >= thr) & (m1 >= peak) & (m1 > 8.0)
    if int(sel.sum()) < 20:
        return 0.0
    R = m1[sel] / np.maximum(m2[sel], 1e-6)
    R = R[R > 1.0001]
    if not len(R):
        return 0.0
    return float(np.median(sigma0 / np.sqrt(R * R - 1.0)))


#: ``t="auto"`` (``auto_threshold``): at least this many times the image's noise (``estimate_noise``) ...
T_PER_NOISE: float = 4.5
#: ... and at least this (grey levels): a noise-free picture still has its anti-aliasing and rounding;
T_MIN: float = 10.0
#: below that, this fraction of the step of the image's weaker edges (``edge_steps``' ``STEP_PERCENTILE``) ...
T_PER_STEP: float = 0.5
STEP_PERCENTILE: float = 10.0
#: ... up to the paper's threshold, which higher-contrast pictures keep
T_MAX: float = 25.0
#: the Laplacian-difference mask of Immerkaer's noise estimate (zero on any plane and ramp)
_NOISE_MASK = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)


def estimate_noise(gray: NDArray[np.uint8], edges: float = 0.1) -> float:
    """The standard deviation (grey levels) of the image's Gaussian noise: Immerkaer's estimate
    (1996: the mean absolute response to a mask that is zero on planes and ramps, times
    ``sqrt(pi / 2) / 6``) over the pixels that are not on edges (Tai and Yang 2008: the
    ``edges`` fraction with the strongest Sobel gradient left out, where the mask answers to the
    picture rather than to the noise). 0 for an image smaller than 3 x 3. About 1 ms at 640x480."""
    g = np.asarray(gray, dtype=np.float32)
    if g.shape[0] < 3 or g.shape[1] < 3:
        return 0.0
    return _noise(g, _sobel(g), edges)


def _sobel(g: NDArray[np.float32]) -> NDArray[np.float32]:
    """The magnitude of the image's 3x3 Sobel gradient."""
    return cv2.magnitude(cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3), cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3))


def _noise(g: NDArray[np.float32], mag: NDArray[np.float32], edges: float) -> float:
    """``estimate_noise`` of the float image ``g`` (at least 3 x 3), given its Sobel magnitude ``mag``."""
    r = np.abs(cv2.filter2D(g, cv2.CV_32F, _NOISE_MASK)[1:-1, 1:-1])
    mag = mag[1:-1, 1:-1]
    keep = mag <= np.percentile(mag, 100.0 * (1.0 - edges))
    if not keep.any():
        return 0.0
    return float(np.sqrt(np.pi / 2.0) / 6.0 * r[keep].mean())


def edge_steps(gray: NDArray[np.uint8], sigma: float | None = None, mag: NDArray[np.float32] | None = None) -> NDArray[np.float32]:
    """The grey-level steps of the image's edges: at the pixels whose Sobel gradient is the
    largest in its 3x3 window and stands out of the noise (``sigma``: ``estimate_noise``'s), the
    range (largest less smallest) of their 5x5 window. ``mag``: the Sobel magnitude, if known."""
    g = np.asarray(gray, dtype=np.float32)
    sigma = estimate_noise(gray) if sigma is None else sigma
    mag = _sobel(g) if mag is None else mag
    peak = cv2.dilate(mag, np.ones((3, 3), np.uint8))
    k5 = np.ones((5, 5), np.uint8)
    span = cv2.dilate(g, k5) - cv2.erode(g, k5)
    # noise alone: Sobel magnitudes of scale 3.5 sigma (past 12 sigma one in 300) and 5x5 ranges
    # of about 4 sigma (past 6 sigma one in 500): both at once, hardly ever
    sel = (mag >= peak) & (mag > max(16.0, 12.0 * sigma)) & (span > max(T_MIN, 6.0 * sigma))
    sel[:2], sel[-2:], sel[:, :2], sel[:, -2:] = False, False, False, False
    return span[sel]


def auto_threshold(gray: NDArray[np.uint8]) -> float:
    """``susan_corners(t="auto")``'s brightness threshold (grey levels): half the step of the
    image's weaker edges (the lower quartile of ``edge_steps``), so that the faces of a dimly lit
    box, 10-20 grey levels apart, are told apart; at most the paper's 25 (checkerboards and other
    high-contrast pictures keep it); and at least ``T_MIN`` and ``T_PER_NOISE`` times the noise,
    so that noise does not break a region's USAN up. About 3 ms at 640x480."""
    g = np.asarray(gray, dtype=np.float32)
    mag = _sobel(g)  # once, for the noise and the edges
    sigma = _noise(g, mag, 0.1) if min(g.shape) >= 3 else 0.0
    floor = max(T_MIN, T_PER_NOISE * sigma)
    steps = edge_steps(gray, sigma, mag)
    if len(steps) < 20:  # next to no edges: nothing to fit it to
        return max(floor, T_MAX)
    return max(floor, min(T_MAX, T_PER_STEP * float(np.percentile(steps, STEP_PERCENTILE))))


def blur_scale(gray: NDArray[np.uint8], blur: float | str) -> tuple[float, float]:
    """``(sigma, f)``: the blur read or given, and the averaging factor (1: full resolution)."""
    if isinstance(blur, str):
        if blur != "auto":
            raise ValueError(f"susan_corners: blur is a number of pixels, 'auto' or None, got {blur!r}")
        sigma = estimate_blur(gray)
    else:
        b = float(blur)
        if not (math.isfinite(b) and b >= 0):
            raise ValueError(f"susan_corners: blur is the image's blur in pixels (>= 0), 'auto' or None, got {blur!r}")
        sigma = math.hypot(b, SHARP_BLUR)
    return sigma, (SCALE_PER_BLUR * sigma if sigma > BLUR_LIMIT else 1.0)


def scaled_corners(
    gray: NDArray[np.uint8], f: float, detect: Callable[[NDArray[np.uint8]], tuple[NDArray[np.float64], NDArray[np.float32]]],
    refine: Callable[[NDArray[np.uint8], NDArray[np.float64]], NDArray[np.float64]] | None,
) -> tuple[NDArray[np.float64], NDArray[np.float32]]:
    """Corners (N, 2) of ``gray`` found by ``detect`` on the image averaged down by ``f``, in full-image
    pixels (refined by ``refine`` when given), and the coarse response brought to full size (nearest)."""
    H, W = gray.shape
    w, h = max(8, int(round(W / f))), max(8, int(round(H / f)))
    small = cv2.resize(gray, (w, h), interpolation=cv2.INTER_AREA)
    pts, resp = detect(small)
    sx, sy = W / w, H / h
    out = np.column_stack([(pts[:, 0] + 0.5) * sx - 0.5, (pts[:, 1] + 0.5) * sy - 0.5]) if len(pts) else np.zeros((0, 2))
    if refine is not None and len(out):
        out = refine(gray, out)
    return out, cv2.resize(resp, (W, H), interpolation=cv2.INTER_NEAREST)
