"""SUSAN corners and edges (Smith and Brady, 1997), vectorised over the image.

For each pixel (the *nucleus*) the 37-pixel circular mask (radius 3.4) is laid on the
image and every mask pixel is compared with the nucleus brightness with the smooth test
``c = exp(-((I - I0) / t) ** 6)``; ``n``, the sum of ``c`` over the mask, is the area of
the USAN ("univalue segment assimilating nucleus"). A corner or an edge is where the USAN
is small: the response is ``g - n`` where ``n < g``, with the geometric threshold ``g``
half the mask area for corners and three quarters for edges.

The loop runs over the 37 mask offsets only, each step a whole-image OpenCV operation
(absolute difference, look-up table, add); the false-positive tests and the direction of
edges look only at the candidate pixels (``n < g``), all at once with NumPy indexing.

Features are ``(x, y)`` = (column, row) pixel coordinates, as in OpenCV.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from ejsrl.vision._util import as_gray, choice, image_function

__all__ = ["SUSAN_MASK", "usan_area", "susan_corners", "susan_edges", "susan"]

#: the (dx, dy) offsets of the 37-pixel circular mask, nucleus included
SUSAN_MASK: NDArray[np.int64] = np.array(
    [(dx, dy) for dy in range(-3, 4) for dx in range(-3, 4) if dx * dx + dy * dy <= 11.56], dtype=np.int64
)
_R = 3  # mask radius in whole pixels
_SCALE = 100  # c is stored as round(100 c) in a uint8 look-up table, as in the original code


def _lut(t: float) -> NDArray[np.uint8]:
    d = np.arange(256, dtype=np.float64)
    return np.rint(_SCALE * np.exp(-((d / float(t)) ** 6))).astype(np.uint8)


@image_function
def usan_area(img: NDArray, t: float = 20.0) -> NDArray[np.float32]:
    """The USAN area ``n`` (H, W) float32 in mask pixels (0..37) of each pixel of a grey image.

    ``t``: brightness threshold (grey levels). Pixels closer than 3 to the border see a
    replicated border.
    """
    n, _, _ = _usan(as_gray(img), t)
    return n.astype(np.float32) / _SCALE


def _usan(gray: NDArray[np.uint8], t: float) -> tuple[NDArray[np.uint16], NDArray[np.uint8], NDArray[np.uint8]]:
    """USAN area scaled by 100 (H, W) uint16, the padded image and the LUT."""
    H, W = gray.shape
    pad = cv2.copyMakeBorder(gray, _R, _R, _R, _R, cv2.BORDER_REPLICATE)
    lut = _lut(t)
    acc = np.zeros((H, W), dtype=np.uint16)
    for dx, dy in SUSAN_MASK:
        if dx == 0 and dy == 0:
            continue
        view = pad[_R + dy : _R + dy + H, _R + dx : _R + dx + W]
        c = cv2.LUT(cv2.absdiff(gray, view), lut)
        cv2.add(acc, c, dst=acc, dtype=cv2.CV_16U)
    acc += _SCALE  # the nucleus itself
    return acc, pad, lut


def _local_max(resp: NDArray[np.float32], radius: int, ys: NDArray, xs: NDArray) -> NDArray[np.bool_]:
    """Which of the pixels (ys, xs) are maxima of ``resp`` in their (2r+1)^2 window.

    On a plateau only the first pixel in raster order is kept: a pixel must be >= every
    neighbour and > those before it (rows above, or to its left on its row).
    """
    if len(ys) == 0:
        return np.zeros(0, bool)
    r = int(radius)
    rp = np.pad(resp, r)
    dy, dx = np.mgrid[-r : r + 1, -r : r + 1]
    dy, dx = dy.ravel(), dx.ravel()
    centre = (dy == 0) & (dx == 0)
    before = (dy < 0) | ((dy == 0) & (dx < 0))
    win = rp[(ys + r)[:, None] + dy[None, :], (xs + r)[:, None] + dx[None, :]]
    v = resp[ys, xs][:, None]
    ok_after = (win <= v) | centre[None, :]
    ok_before = (win < v) | ~before[None, :]
    return (v[:, 0] > 0) & ok_after.all(axis=1) & ok_before.all(axis=1)


def _gather(pad: NDArray[np.uint8], gray: NDArray[np.uint8], lut: NDArray[np.uint8], ys: NDArray, xs: NDArray):
    """c (K, 37) uint8 in [0, 100] of the mask pixels around the candidate pixels (ys, xs)."""
    Wp = pad.shape[1]
    offs = SUSAN_MASK[:, 1] * Wp + SUSAN_MASK[:, 0]
    base = (ys + _R) * Wp + (xs + _R)
    vals = pad.ravel()[base[:, None] + offs[None, :]].astype(np.int16)
    diff = np.abs(vals - gray.ravel()[ys * gray.shape[1] + xs].astype(np.int16)[:, None])
    return np.take(lut, diff)


def _candidates(gray: NDArray[np.uint8], t: float, g100: float):
    """Pixels whose USAN area (x100) is below ``g100``: rows, columns, their c (K, 37) and n (K,).

    Only pixels whose 7x7 neighbourhood spans enough grey levels can have a small USAN:
    with every difference at most ``r``, ``n >= 37 exp(-(r / t)^6)``. Those few pixels are
    evaluated by gathering their 37 neighbours; if they are many (a busy or noisy image),
    the whole-image pass of ``_usan`` is cheaper and is used instead. Same result either way.
    """
    H, W = gray.shape
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, len(SUSAN_MASK))), np.zeros(0))
    pad = cv2.copyMakeBorder(gray, _R, _R, _R, _R, cv2.BORDER_REPLICATE)
    lut = _lut(t)
    if H <= 2 * _R + 2 or W <= 2 * _R + 2:
        return (*empty, pad, lut)
    nmax = len(SUSAN_MASK) * _SCALE
    if g100 >= nmax:
        maybe = np.ones((H, W), bool)
    else:
        need = 0.9 * float(t) * np.log(nmax / g100) ** (1.0 / 6.0)
        k = np.ones((2 * _R + 1, 2 * _R + 1), np.uint8)
        spread = cv2.subtract(cv2.dilate(gray, k), cv2.erode(gray, k))
        maybe = spread > need
    _clear_border(maybe, _R + 1)
    if maybe.mean() > 0.25:
        acc, _, _ = _usan(gray, t)
        maybe &= acc < g100
    ys, xs = np.divmod(np.flatnonzero(maybe), W)
    c8 = _gather(pad, gray, lut, ys, xs)
    n = c8.sum(axis=1, dtype=np.int32)
    small = np.flatnonzero(n < g100)
    return ys[small], xs[small], c8[small].astype(np.float64), n[small].astype(np.float64), pad, lut


def _clear_border(resp: NDArray, b: int) -> None:
    resp[:b] = 0
    resp[-b:] = 0
    resp[:, :b] = 0
    resp[:, -b:] = 0


@image_function
def susan_corners(
    img: NDArray,
    t: float = 20.0,
    *,
    g: float | None = None,
    nms_radius: int = 3,
    quality: float = 0.25,
    max_corners: int | None = None,
    subpixel: bool = True,
    return_response: bool = False,
) -> NDArray[np.float64] | tuple[NDArray[np.float64], NDArray[np.float32]]:
    """SUSAN corner detector (Smith and Brady 1997).

    ``img``: grey (H, W) or RGB (H, W, 3) uint8. ``t``: brightness threshold in grey levels
    (lower finds weaker corners, higher resists noise). ``g``: geometric threshold in mask
    pixels (default half the mask, 18.5). ``nms_radius``: non-maximum suppression window
    radius (3: 7x7, as in the original code). ``quality``: drop corners whose response is
    below this fraction of the strongest one (as ``cv2.goodFeaturesToTrack``'s quality
    level; straight staircase edges give weak responses that noise can turn into local
    maxima). ``max_corners``: keep at most this many, strongest first. ``subpixel``: refine
    each corner with ``cv2.cornerSubPix`` in a 5x5 window (the original reports the pixel
    just inside the corner, up to about 1.5 px from the true vertex).

    The false-positive tests of the original are applied: the USAN centroid must lie more
    than 1/sqrt(2) pixel from the nucleus, and the three pixels from the nucleus towards the
    centroid must belong to the USAN.

    Returns the corners (N, 2) float64 as ``(x, y)`` pixel coordinates, strongest first
    (ties in raster order); with ``return_response`` also the response map (H, W) float32.
    """
    gray = as_gray(img)
    H, W = gray.shape
    gthr = 0.5 * len(SUSAN_MASK) if g is None else float(g)
    g100 = gthr * _SCALE
    ys, xs, c, n, pad, lut = _candidates(gray, t, g100)
    resp = np.zeros((H, W), np.float32)
    if len(ys):
        sx = c @ SUSAN_MASK[:, 0]
        sy = c @ SUSAN_MASK[:, 1]
        far_enough = sx * sx + sy * sy > 0.5 * n * n
        # pixels at 1, 2, 3 steps from the nucleus towards the centroid must be in the USAN
        ax, ay = np.abs(sx), np.abs(sy)
        along_x = ay < ax
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = np.where(along_x, sy / np.where(ax > 0, ax, 1), sx / np.where(ay > 0, ay, 1))
        sgn = np.where(along_x, np.sign(sx), np.sign(sy)).astype(np.int64)
        total = np.zeros(len(ys))
        for k in (1, 2, 3):
            off = (np.sign(k * slope) * np.floor(np.abs(k * slope) + 0.5)).astype(np.int64)
            oy = np.where(along_x, off, k * sgn)
            ox = np.where(along_x, k * sgn, off)
            v = pad[ys + _R + oy, xs + _R + ox].astype(np.int16)
            total += lut[np.abs(v - gray[ys, xs].astype(np.int16))]
        ok = far_enough & (total > 2.9 * _SCALE)
        resp[ys[ok], xs[ok]] = ((g100 - n[ok]) / _SCALE).astype(np.float32)
    cy, cx = (ys[ok], xs[ok]) if len(ys) else (ys, xs)
    peak = _local_max(resp, nms_radius, cy, cx)
    py, px = cy[peak], cx[peak]
    strength = resp[py, px]
    if len(strength) and quality > 0:
        strong = strength >= quality * strength.max()
        py, px, strength = py[strong], px[strong], strength[strong]
    order = np.lexsort((py * W + px, -strength))
    pts = np.column_stack([px[order], py[order]]).astype(np.float64)
    if max_corners is not None:
        pts = pts[: int(max_corners)]
    if subpixel and len(pts):
        refined = cv2.cornerSubPix(
            gray, pts.astype(np.float32).reshape(-1, 1, 2), (2, 2), (-1, -1),
            (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 20, 0.01),
        ).reshape(-1, 2).astype(np.float64)
        # keep the pixel estimate where the refinement wandered off (a flat or noisy patch)
        moved = np.linalg.norm(refined - pts, axis=1)
        pts = np.where((moved <= 2.0)[:, None], refined, pts)
    return (pts, resp) if return_response else pts


@image_function
def susan_edges(
    img: NDArray,
    t: float = 20.0,
    *,
    g: float | None = None,
    return_response: bool = False,
) -> tuple[NDArray[np.uint8], NDArray[np.float64]] | tuple[NDArray[np.uint8], NDArray[np.float64], NDArray[np.float32]]:
    """SUSAN edge detector (Smith and Brady 1997) with non-maximum suppression across the edge.

    ``img``: grey or RGB uint8; ``t``: brightness threshold; ``g``: geometric threshold in
    mask pixels (default three quarters of the mask, 27.75). The edge normal comes from the
    USAN centroid where the USAN is large and off-centre (an edge between pixels), and from
    the USAN's second moments otherwise (an edge through the nucleus); a pixel is kept when
    its response is a maximum along that normal.

    Returns ``edges`` (H, W) uint8 (255 on edges) and the edge points (N, 2) ``(x, y)`` in
    raster order; with ``return_response`` also the response (H, W) float32.
    """
    gray = as_gray(img)
    H, W = gray.shape
    gthr = 0.75 * len(SUSAN_MASK) if g is None else float(g)
    g100 = gthr * _SCALE
    ys, xs, c, n, pad, lut = _candidates(gray, t, g100)
    resp = np.zeros((H, W), np.float32)
    resp[ys, xs] = ((g100 - n) / _SCALE).astype(np.float32)
    edges = np.zeros((H, W), np.uint8)
    if len(ys):
        dx, dy = SUSAN_MASK[:, 0].astype(np.float64), SUSAN_MASK[:, 1].astype(np.float64)
        sx, sy = c @ dx, c @ dy
        mxx, myy, mxy = c @ (dx * dx), c @ (dy * dy), c @ (dx * dy)
        inter = (n > 6 * _SCALE) & (sx * sx + sy * sy > n * n)  # centroid more than 1 px away
        theta_normal = np.where(
            inter,
            np.arctan2(sy, sx),
            0.5 * np.arctan2(2 * mxy, mxx - myy) + np.pi / 2,  # the USAN's minor axis
        )
        # quantise the normal to 0, 45, 90, 135 degrees and compare with both neighbours
        q = np.mod(np.rint(theta_normal / (np.pi / 4)).astype(np.int64), 4)
        steps = np.array([[1, 0], [1, 1], [0, 1], [-1, 1]])
        ox, oy = steps[q, 0], steps[q, 1]
        r0 = resp[ys, xs]
        r_plus = resp[np.clip(ys + oy, 0, H - 1), np.clip(xs + ox, 0, W - 1)]
        r_minus = resp[np.clip(ys - oy, 0, H - 1), np.clip(xs - ox, 0, W - 1)]
        keep = (r0 > r_plus) & (r0 >= r_minus)
        edges[ys[keep], xs[keep]] = 255
    ey, ex = np.nonzero(edges)
    pts = np.column_stack([ex, ey]).astype(np.float64)
    if return_response:
        return edges, pts, resp
    return edges, pts


@image_function
def susan(img: NDArray, t: float = 20.0, *, kind: str = "corners", **options):
    """SUSAN in one call: ``kind="corners"`` -> ``susan_corners``; ``kind="edges"`` -> ``susan_edges``.

    ``t``: brightness threshold; other options go to the chosen detector.
    """
    if choice(kind, ("corners", "edges"), "SUSAN kind") == "corners":
        return susan_corners(img, t, **options)
    return susan_edges(img, t, **options)
