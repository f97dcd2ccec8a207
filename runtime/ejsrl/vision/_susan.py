"""SUSAN corners and edges (Smith and Brady, 1997), vectorised over the image.

For each pixel (the *nucleus*) the 37-pixel circular mask (radius 3.4) is laid on the
image and every mask pixel is compared with the nucleus brightness with the smooth test
``c = exp(-((I - I0) / t) ** 6)``; ``n``, the sum of ``c`` over the mask, is the area of
the USAN ("univalue segment assimilating nucleus"). A corner or an edge is where the USAN
is small: the response is ``g - n`` where ``n < g``, with the geometric threshold ``g``
half the mask area for corners and three quarters for edges.

The USAN is computed with whole-image OpenCV operations over the 18 offset pairs (d, -d)
(the brightness test is symmetric); the false-positive tests and the direction of edges
look only at candidate pixels, with NumPy indexing.

Corners in anti-aliased (or slightly blurred) images need one addition to the original:
a pixel inside an edge has an in-between grey, so its own USAN is tiny and means nothing.
Such a pixel is judged as the side it belongs to: each mask pixel counts by its share of
that side, and the response is what that side falls short of the half-plane a straight
edge would leave (see ``susan_corners``). This finds obtuse corners, whose only small
USAN is at the anti-aliased apex, and gives true sub-pixel output with ``cornerSubPix``;
X-junctions (checkerboard corners) are recognised by their brighter and darker pixels
lying in opposite quadrants around the nucleus.

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
_CHORD = 6.8  # the mask's diameter in pixels
_MID_SLACK = 1.0  # in-between pixels kept for the test as the side they belong to: whole-image estimate >= min_response - this
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
    """USAN area scaled by 100 (H, W) uint16, the padded image and the LUT.

    The brightness test is symmetric, ``c(p, p + d) = c(p + d, p)``, so each of the 18
    offset pairs (d, -d) needs one difference image and one look-up: over the pixels q of
    the image and of the image shifted by -d, ``E(q) = c(|I(q) - I(q + d)|)``; pixel p gets
    ``E(p)`` for offset d and ``E(p - d)`` for offset -d. The two add exactly in uint8
    (at most 200) before the uint16 sum.
    """
    H, W = gray.shape
    pad = cv2.copyMakeBorder(gray, _R, _R, _R, _R, cv2.BORDER_REPLICATE)
    lut = _lut(t)
    acc = np.full((H, W), _SCALE, dtype=np.uint16)  # the nucleus itself
    pair = np.empty((H, W), np.uint8)
    for dx, dy in SUSAN_MASK:
        if dy < 0 or (dy == 0 and dx <= 0):
            continue  # one offset of each pair (d, -d)
        # q spans rows -dy .. H-1 and columns min(0, -dx) .. max(W, W - dx) - 1 of the image
        r0, c0 = _R - dy, _R + min(0, -dx)
        h, w = H + dy, W + abs(dx)
        a = pad[r0 : r0 + h, c0 : c0 + w]
        b = pad[r0 + dy : r0 + dy + h, c0 + dx : c0 + dx + w]
        E = cv2.LUT(cv2.absdiff(a, b), lut)
        py, px = dy, -min(0, -dx)  # where the image's pixel (0, 0) sits in E
        cv2.add(E[py : py + H, px : px + W], E[py - dy : py - dy + H, px - dx : px - dx + W], dst=pair)
        np.add(acc, pair, out=acc)
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


#: (37, 3) float32: each mask pixel's 1, dx, dy (a matrix product gives the sum, x and y moments)
_MOMENTS = np.column_stack([np.ones(len(SUSAN_MASK)), SUSAN_MASK[:, 0], SUSAN_MASK[:, 1]]).astype(np.float32)


def _corner_tests(pad: NDArray[np.uint8], ys: NDArray, xs: NDArray, similarity, *, return_saddle: bool = False):
    """The false-positive tests on the pixels (ys, xs); returns which pass and their USAN areas n (x100).

    ``similarity(values)`` gives, for the grey values (K, m) uint8 of the pixels around each
    nucleus, c (x100, float32; at most 100) and which of them are brighter than the nucleus
    (bool; a pixel with c = 100 counts as alike, whatever it says).

    1. (Smith and Brady) the USAN centroid lies more than 1/sqrt(2) pixel from the nucleus;
    2. (Smith and Brady) the three pixels from the nucleus towards the centroid are in the USAN;
    3. (one-sided) the pixels unlike the nucleus are not split into brighter ones on one side
       and darker ones on the other, as around a nucleus inside an anti-aliased edge.

    All K pixels are tested at once: the sums and moments over the mask are two matrix
    products (OpenCV's: NumPy's BLAS threads stall on a shared machine); the mask is
    symmetric, so the unlike pixels' moments follow from the USAN's.
    """
    if len(ys) == 0:
        return (np.zeros(0, bool), np.zeros(0), np.zeros(0, bool)) if return_saddle else (np.zeros(0, bool), np.zeros(0))
    Wp = pad.shape[1]
    offs = SUSAN_MASK[:, 1] * Wp + SUSAN_MASK[:, 0]
    centre = (ys + _R) * Wp + (xs + _R)
    vals = pad.ravel().take(centre[:, None] + offs[None, :])
    c, brighter = similarity(vals)
    usan = cv2.gemm(c, _MOMENTS, 1.0, None, 0.0).astype(np.float64)  # exact: sums of integers below 2^24 (or close for coverage)
    n, sx, sy = usan[:, 0], usan[:, 1], usan[:, 2]
    far_enough = sx * sx + sy * sy > 0.5 * n * n
    ax, ay = np.abs(sx), np.abs(sy)
    along_x = ay < ax
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.where(along_x, sy / np.where(ax > 0, ax, 1), sx / np.where(ay > 0, ay, 1))
    sgn = np.where(along_x, np.sign(sx), np.sign(sy)).astype(np.int64)
    steps = np.empty((len(ys), 3), np.uint8)
    for k in (1, 2, 3):
        off = (np.sign(k * slope) * np.floor(np.abs(k * slope) + 0.5)).astype(np.int64)
        oy = np.where(along_x, off, k * sgn)
        ox = np.where(along_x, k * sgn, off)
        steps[:, k - 1] = pad.ravel().take(centre + oy * Wp + ox)
    total = similarity(steps)[0].sum(axis=1, dtype=np.float64)
    contiguous = total > 2.9 * _SCALE
    # the moments of the unlike pixels (weights 100 - c), split into brighter and darker ones
    bright = np.subtract(np.float32(_SCALE), c)
    np.multiply(bright, brighter, out=bright)
    bright_m = cv2.gemm(bright, _MOMENTS, 1.0, None, 0.0).astype(np.float64)
    mb, bx, by = bright_m[:, 0], bright_m[:, 1], bright_m[:, 2]
    md, dx_, dy_ = _SCALE * len(SUSAN_MASK) - n - mb, -sx - bx, -sy - by
    opposite = bx * dx_ + by * dy_ < 0
    balanced = np.minimum(mb, md) > 0.25 * (mb + md)
    two_sided = opposite & balanced
    ok = far_enough & contiguous & ~two_sided
    if not return_saddle:
        return ok, n
    # an X-junction (a saddle: the corner of a checkerboard) is two-sided too, but its brighter
    # and its darker pixels each lie in two opposite quadrants, centred on the nucleus
    with np.errstate(divide="ignore", invalid="ignore"):
        off_b = np.hypot(bx, by) / np.where(mb > 0, mb, 1)
        off_d = np.hypot(dx_, dy_) / np.where(md > 0, md, 1)
    saddle = (np.minimum(mb, md) > 0.3 * (mb + md)) & (mb + md > 0.35 * _SCALE * len(SUSAN_MASK)) & (off_b < 0.8) & (off_d < 0.8)
    return ok, n, saddle


def _smooth_similarity(lut: NDArray[np.uint8], nucleus: NDArray):
    """SUSAN's test ``c = exp(-((I - I0) / t)^6)`` (the LUT) around the nuclei's own grey levels."""
    g0 = np.ascontiguousarray(nucleus, dtype=np.uint8)[:, None]

    def sim(vals: NDArray) -> tuple[NDArray, NDArray]:
        g = g0[: len(vals)]
        d = cv2.absdiff(vals, np.repeat(g, vals.shape[1], axis=1))
        return cv2.LUT(d, lut).astype(np.float32), vals > g

    return sim


def _coverage_response(gray: NDArray[np.uint8], g100: float, where: tuple[NDArray, NDArray] | None = None) -> NDArray:
    """The corner response (x100) of each pixel judged as the dark side of its 7x7 neighbourhood
    (negative: the bright side's, of that size), from the pixels' dark shares.

    ``share = (max7 - I) / (max7 - min7)`` (the part of the pixel covered by the darker region,
    for two grey levels and an anti-aliased edge); the darker side's USAN of a nucleus is the
    sum of the shares over the mask. A straight edge cutting the nucleus pixel so that a share
    a of it is dark leaves about ``g + 6.8 (a - 1/2)`` of the mask dark (the mask's chord is
    6.8 pixels long); the response is what the side falls short of that, on the side that
    falls short (the other side then has more than its share).
    """
    k7 = np.ones((7, 7), np.uint8)
    levels = cv2.medianBlur(gray, 3)  # the two grey levels, without the noise's extremes
    lo = cv2.erode(levels, k7).astype(np.float32)
    hi = cv2.dilate(levels, k7).astype(np.float32)
    share = np.clip((hi - gray.astype(np.float32)) / np.maximum(hi - lo, 1.0), 0.0, 1.0)
    if where is not None:  # only at these pixels (ys, xs): the shares summed over the mask there
        ys, xs = where
        sp = cv2.copyMakeBorder(share, _R, _R, _R, _R, cv2.BORDER_REPLICATE)
        Wp = sp.shape[1]
        offs = SUSAN_MASK[:, 1] * Wp + SUSAN_MASK[:, 0]
        n_dark = sp.ravel()[((ys + _R) * Wp + (xs + _R))[:, None] + offs[None, :]].sum(axis=1)
        return (g100 + _CHORD * _SCALE * (share[ys, xs] - 0.5)) - _SCALE * n_dark
    disc = np.zeros((2 * _R + 1, 2 * _R + 1), np.float32)
    disc[SUSAN_MASK[:, 1] + _R, SUSAN_MASK[:, 0] + _R] = 1.0
    n_dark = cv2.filter2D(share, cv2.CV_32F, disc, borderType=cv2.BORDER_REPLICATE)
    return (g100 + _CHORD * _SCALE * (share - 0.5)) - _SCALE * n_dark


def _coverage_similarity(lo: NDArray, hi: NDArray, dark: bool):
    """For a nucleus inside an anti-aliased edge between grey levels lo and hi: each pixel's
    share of the dark (or bright) side, ``(hi - I) / (hi - lo)`` clipped to [0, 1] (x100)."""
    lo_ = lo.astype(np.float32)[:, None]
    span = np.maximum(hi.astype(np.float32)[:, None] - lo_, np.float32(1.0))

    def sim(vals: NDArray) -> tuple[NDArray, NDArray]:
        share = np.clip((vals.astype(np.float32) - lo_[: len(vals)]) / span[: len(vals)], np.float32(0.0), np.float32(1.0))
        c = np.float32(_SCALE) * (np.float32(1.0) - share if dark else share)
        # the other side is brighter if this is the dark one (darker otherwise)
        return c, (c < _SCALE) if dark else np.zeros(c.shape, bool)

    return sim


@image_function
def susan_corners(
    img: NDArray,
    t: float = 25.0,
    *,
    g: float | None = None,
    nms_radius: int = 3,
    quality: float = 0.0,
    min_response: float = 1.5,
    max_corners: int | None = None,
    subpixel: bool = True,
    return_response: bool = False,
) -> NDArray[np.float64] | tuple[NDArray[np.float64], NDArray[np.float32]]:
    """SUSAN corner detector (Smith and Brady 1997).

    ``img``: grey (H, W) or RGB (H, W, 3) image (uint8, or another type read as
    ``ejsrl.vision._util`` says). ``t``: brightness threshold in grey levels (lower finds
    weaker corners, higher resists noise). ``g``: geometric threshold in mask pixels
    (default half the mask, 18.5). ``nms_radius``: non-maximum suppression window radius
    (3: 7x7, as in the original code). ``min_response``: drop corners whose response
    ``g - n`` is below this many mask pixels (a straight edge gives about 0, a 150-degree
    corner about 3; noise on edges gives up to about 1). ``quality``: also drop corners
    below this fraction of the strongest one (as ``cv2.goodFeaturesToTrack``'s quality
    level; 0: off). ``max_corners``: keep at most this many, strongest first.
    ``subpixel``: refine each corner to sub-pixel accuracy with ``cv2.cornerSubPix``
    (the intersection of the edges through a 7x7 window: the true vertex of an L corner,
    the saddle of an X-junction), kept when it stays within 3 pixels; the pixel found
    otherwise is the one just inside the corner, up to about 1.5 px from the vertex.

    The response is ``g - n`` where the USAN area ``n < g``. The false-positive tests
    (see ``_corner_tests``: the centroid and contiguity tests of the original, and a test
    that rejects pixels inside anti-aliased edges) are applied to every pixel with a
    response, all at once (as in the original); a pixel that fails is removed where it is
    the largest in its window, and otherwise stays, hidden under a larger pixel, and still
    suppresses weaker ones around it (as when local maxima are tested and the windows of
    the rejected ones searched again until every maximum passes). Every peak of the
    returned response is then a corner.

    Returns the corners (N, 2) float64 as ``(x, y)`` pixel coordinates, strongest first
    (ties in raster order); with ``return_response`` also the response map (H, W) float32
    (after the tests: 0 where a maximum was rejected).
    """
    gray = as_gray(img)
    if not float(t) > 0:
        raise ValueError(f"susan_corners: t must be positive, got {t}")
    H, W = gray.shape
    gthr = 0.5 * len(SUSAN_MASK) if g is None else float(g)
    g100 = gthr * _SCALE
    r = int(nms_radius)
    if H <= 2 * _R + 2 or W <= 2 * _R + 2:
        pts = np.zeros((0, 2))
        return (pts, np.zeros((H, W), np.float32)) if return_response else pts
    # only pixels whose 7x7 neighbourhood spans enough grey levels can have a small USAN (with
    # every difference at most s, n >= 37 exp(-(s / t)^6)) or an in-between grey; where they
    # are few (a rendered scene: flat faces), their USANs are gathered one by one, else the
    # whole-image pass is cheaper. The same values either way.
    k7 = np.ones((2 * _R + 1, 2 * _R + 1), np.uint8)
    need = min(0.9 * float(t) * np.log(len(SUSAN_MASK) * _SCALE / g100) ** (1.0 / 6.0), float(t))
    maybe = cv2.subtract(cv2.dilate(gray, k7), cv2.erode(gray, k7)) > need
    _clear_border(maybe, _R + 1)
    sparse = maybe.mean() <= 0.2
    if sparse:
        pad = cv2.copyMakeBorder(gray, _R, _R, _R, _R, cv2.BORDER_REPLICATE)
        lut = _lut(t)
        my_, mx_ = np.nonzero(maybe)
        resp = np.zeros((H, W), np.float32)
        resp[my_, mx_] = g100 - _gather(pad, gray, lut, my_, mx_).sum(axis=1, dtype=np.int32)
    else:
        acc, pad, lut = _usan(gray, t)
        resp = np.float32(g100) - acc.astype(np.float32)  # g - n, x100
    floor = float(min_response) * _SCALE
    # keep what reaches the floor: OpenCV's threshold keeps what exceeds the largest float32 below it
    below = np.float32(floor)
    if below >= floor:
        below = np.nextafter(below, np.float32(-np.inf))
    resp = cv2.threshold(resp, float(below), 0.0, cv2.THRESH_TOZERO)[1]
    _clear_border(resp, _R + 1)
    # pixels with an in-between grey (inside an anti-aliased or blurred edge) have a tiny USAN of
    # their own that means nothing: they are judged as the side they belong to would be. Those
    # that cannot be a corner that way (a straight edge: the whole-image estimate of
    # _coverage_response) are dropped at once; the others are judged one by one below
    k3 = np.ones((3, 3), np.uint8)
    half_t = 0.5 * float(t)
    lo3, hi3 = cv2.erode(gray, k3), cv2.dilate(gray, k3)
    mid = (cv2.subtract(gray, lo3) > half_t) & (cv2.subtract(hi3, gray) > half_t)
    kernel = np.ones((2 * r + 1, 2 * r + 1), np.uint8)
    tested = np.zeros((H, W), bool)
    passed_y, passed_x = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
    # X-junctions (saddles: the corner of a checkerboard) have an in-between centre pixel with a
    # small USAN of its own, its brighter and darker neighbours in opposite quadrants
    # (and, being half dark and half bright, no corner by the side it belongs to)
    if sparse:
        mid &= maybe
        r_dark = np.zeros((H, W), np.float32)
        wy, wx = np.nonzero(mid)
        r_dark[wy, wx] = _coverage_response(gray, g100, (wy, wx))
    else:
        r_dark = _coverage_response(gray, g100)
    flat_side = mid & (np.abs(r_dark) < floor - _MID_SLACK * _SCALE)
    own_mid = np.where(flat_side, resp, 0)
    sy, sx = np.nonzero((own_mid > 0) & (own_mid >= cv2.dilate(own_mid, k3)))
    saddle = _corner_tests(pad, sy, sx, _smooth_similarity(lut, gray[sy, sx]), return_saddle=True)[2]
    sy, sx = sy[saddle], sx[saddle]
    resp[flat_side] = 0
    resp[sy, sx] = own_mid[sy, sx]
    tested[sy, sx] = True
    passed_y.append(sy)
    passed_x.append(sx)
    # every other pixel with a response is tested at once (as Smith and Brady test every pixel
    # before the suppression); those that fail are removed, or, inside an anti-aliased edge,
    # judged again as the side they belong to
    ys, xs = np.nonzero((resp > 0) & ~tested)
    v = gray[ys, xs]
    ok, _ = _corner_tests(pad, ys, xs, _smooth_similarity(lut, v))
    m = mid[ys, xs] & ~ok
    new = np.zeros(len(ys))
    if m.any():
        my, mx, lo, hi = ys[m], xs[m], lo3[ys[m], xs[m]], hi3[ys[m], xs[m]]
        # judged as the side that falls short of its share (the sign of the whole-image
        # estimate): a straight edge cutting the nucleus pixel so that a share a of it lies on
        # one side leaves about g + 6.8 (a - 1/2) of the mask on that side (the disc's chord
        # is 6.8 pixels long); only what falls short of that is a corner
        dark = r_dark[my, mx] > 0
        a_dark = (hi.astype(np.float64) - v[m]) / np.maximum(hi.astype(np.float64) - lo, 1.0)
        a_side = np.where(dark, a_dark, 1.0 - a_dark)
        ok_m = np.zeros(len(my), bool)
        n_m = np.zeros(len(my))
        for side in (True, False):
            k = dark == side
            if k.any():
                ok_m[k], n_m[k] = _corner_tests(pad, my[k], mx[k], _coverage_similarity(lo[k], hi[k], dark=side))
        r_mid = np.where(ok_m, g100 + _CHORD * _SCALE * (a_side - 0.5) - n_m, 0.0)
        new[m] = np.where(r_mid >= floor, r_mid, 0.0)
        ok |= new > 0
    # a pixel that fails is dropped where it is the largest in its window, as a maximum that
    # fails is; where a larger pixel that stays is in its window, it stays too (hidden under
    # that maximum, not a corner) and still suppresses the weaker pixels around it. Which
    # stay is found from the strongest down, a chain of such pixels at a time
    fail = ~ok
    resp[ys[new > 0], xs[new > 0]] = new[new > 0].astype(np.float32)
    fy, fx = ys[fail], xs[fail]
    fv = resp[fy, fx]
    stay = np.zeros(len(fy), bool)
    live = resp.copy()
    live[fy, fx] = 0
    und = np.arange(len(fy))  # the failing pixels not yet found hidden
    while len(und):
        uy, ux = fy[und], fx[und]
        hidden = cv2.dilate(live, kernel)[uy, ux] > fv[und]
        if not hidden.any():
            break
        stay[und[hidden]] = True
        live[uy[hidden], ux[hidden]] = fv[und[hidden]]
        und = und[~hidden]
    resp[fy[~stay], fx[~stay]] = 0
    passed_y.append(ys[ok])
    passed_x.append(xs[ok])
    cy, cx = np.concatenate(passed_y), np.concatenate(passed_x)
    keep = _local_max(resp, r, cy, cx)
    py, px = cy[keep], cx[keep]
    strength = resp[py, px] / _SCALE
    if len(strength) and quality > 0:
        strong = strength >= quality * strength.max()
        py, px, strength = py[strong], px[strong], strength[strong]
    order = np.lexsort((py * W + px, -strength))
    pts = np.column_stack([px[order], py[order]]).astype(np.float64)
    if max_corners is not None:
        pts = pts[: int(max_corners)]
    if subpixel and len(pts):
        pts = _refine(gray, pts)
    return (pts, resp / _SCALE) if return_response else pts


def _refine(gray: NDArray[np.uint8], pts: NDArray[np.float64]) -> NDArray[np.float64]:
    """Sub-pixel corners: ``cv2.cornerSubPix`` in a 7x7 window, kept where it moved at most 3 px."""
    refined = cv2.cornerSubPix(
        gray, pts.astype(np.float32).reshape(-1, 1, 2), (3, 3), (-1, -1),
        (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 20, 0.01),
    ).reshape(-1, 2).astype(np.float64)
    moved = np.linalg.norm(refined - pts, axis=1)
    return np.where((moved <= 3.0)[:, None], refined, pts)


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
