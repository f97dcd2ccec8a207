"""SUSAN corners' loops compiled with numba (the ``[fast]`` extra), imported by ``_susan`` lazily.

The NumPy/OpenCV path of ``_susan.susan_corners`` spends its time in whole-image passes and
in gathering the 37 mask pixels of the 15-25 thousand pixels with a response of a photograph;
here the bound, the exact USAN and its moments, the false-positive tests (the in-between
pixels' coverage test too) and the suppression are loops over the image or over those
pixels, with the same arithmetic (integer sums, float64 sums that are exact, the same
float64 and float32 operations), so the corners, the response and the sub-pixel positions
are the same, bit for bit (tests/vision/test_susan_numba.py). What stays in OpenCV: the
side shares' grey levels (a 3x3 median, a 7x7 minimum and maximum), and, when the response
map is asked for, the dilation that finds the failing pixels under a larger passing one.

Hot loops index with unsigned integers, or count from 0 over 1-D views (``share_image``):
numba wraps negative indices, and a loop whose indices it cannot prove non-negative stays
scalar (LLVM does not vectorise it); branches that depend on each pixel are written as
arithmetic where they would be mispredicted (``candidates``' pixels left by the bound, the
smooth test's brighter pixels).

The kernels release the GIL (``nogil``: a classroom server's sessions run them side by side
in threads) and each runs on one thread (``parallel`` is not used: numba's thread pools do not
take calls from several threads at once, as a server's sessions make them). Outside a served
class, ``_susan`` runs them on parts of their pixels (bands of rows, ranges of candidates) in two
threads, and independent ones side by side (``_susan._shared``, ``_susan.set_threads``). They are cached on disk
(``cache``): numba writes next to this file when it can (an editable install), else to its
user-wide cache (``~/.cache/numba``, or ``$NUMBA_CACHE_DIR``: a wheel in a read-only
site-packages), so only the first process on a machine compiles them.
"""

from __future__ import annotations

import numba as nb
import numpy as np


def _jit(fn=None, **options):
    """``numba.njit(nogil=True, cache=True, **options)``; without a writable cache (a read-only
    install and no user cache directory: numba refuses ``cache=True``) compiled again in each process."""
    if fn is None:
        return lambda fn: _jit(fn, **options)
    try:
        return nb.njit(nogil=True, cache=True, **options)(fn)
    except RuntimeError:  # "cannot cache function ...: no locator available"
        return nb.njit(nogil=True, **options)(fn)


_UNFIX = 2.0**-25  # the coverage shares are in fixed point, times 2^25 (``_susan._share_table``)
_HALF = (1, 2, 3, 3, 3, 2, 1)  # the mask's half-widths on its rows dy = -3 .. 3 (37 pixels)


@_jit
def candidates(gray, lut, mdx, mdy, T, m, L_max, g100, below, y0, y1, idx, rv, v0s, lo3, hi3, mom):
    """The pixels at least 4 from the border with a response ``g - n > below`` (x100, float32),
    on the rows ``y0 .. y1 - 1`` (two calls on two row ranges: the same pixels, split).

    ``mdx``/``mdy``: the mask offsets (nucleus included). A ramp sum over the 36 neighbours,
    ``L = sum min((T - d)+, m)``, bounds the USAN from below (``_susan._ramp_bound``): only the
    pixels with ``L <= L_max`` get the exact USAN from the look-up table. Row by row, one
    offset at a time over the row, in uint8 (LLVM makes it byte-wide SIMD).

    Writes, for the K pixels found, their flat indices (raster order) into ``idx``, the response
    ``rv`` (float32), the grey level ``v0s``, the 3x3 minimum and maximum ``lo3``/``hi3`` (what
    OpenCV's 3x3 ``erode``/``dilate`` give: the pixels are inside the image), and the USAN's
    integer moments ``mom`` (K, 3): n and its x and y moments; returns K. The arrays have room
    for every pixel of the rows (``_susan._search``): numba counts the references of an array
    grown in a loop on every pass, which cost 13 % here.
    """
    H, W = gray.shape
    f = gray.ravel()
    b = 4
    nm = len(mdx)
    K = 0
    # the bound's rows are a whole number of 64 pixels long (the SIMD width of uint8 on AVX-512),
    # read from a copy of the rows it needs with that room on the right: a row of 632 pixels left
    # 56 to the scalar remainder loop of each offset, which took 5 times the SIMD loop's time
    Wv = (W - 2 * b + 63) // 64 * 64
    ya, yb = max(max(y0, b) - b, 0), min(min(y1, H - b) + b, H)
    wide = np.empty((max(yb - ya, 0), Wv + 2 * b), np.uint8)
    wide[:, :W] = gray[ya:yb]
    wide[:, W:] = 0  # (read by the lanes past the row's end, whose sums are never read)
    acc = np.zeros(Wv, np.uint8)
    xs = np.empty(W, np.int64)
    Tu, mu, sat = np.uint8(T), np.uint8(m), np.uint8(255)
    g = np.float32(g100)
    Lm = np.int64(L_max)
    for y in range(max(y0, b), min(y1, H - b)):
        acc[:] = 0
        r = wide[y - ya, b : b + Wv]
        for k in range(nm):
            dx, dy = mdx[k], mdy[k]
            if dx == 0 and dy == 0:
                continue
            o = wide[y + dy - ya, b + dx : b + dx + Wv]
            # uint8 throughout, each step truncated back to uint8: byte-wide SIMD (absolute
            # difference, saturating subtraction, minimum, saturating sum)
            for x in range(Wv):
                p, q = r[x], o[x]
                d = np.uint8(max(p, q) - min(p, q))
                e = min(np.uint8(max(Tu, d) - d), mu)
                s = np.uint8(acc[x] + e)
                acc[x] = s if s >= e else sat
        nx = 0
        for x in range(W - 2 * b):  # the pixels the bound leaves, without a branch per pixel
            xs[nx] = x
            nx += np.int64(acc[x]) <= Lm
        for j in range(nx):  # their exact USAN, kept (K moves on) where there is a response
            pc = y * W + xs[j] + b
            v = np.int32(f[pc])
            n, sx, sy = np.int32(0), np.int32(0), np.int32(0)
            for dy in range(-3, 4):
                w = _HALF[dy + 3]
                base = pc + dy * W
                for dx in range(-w, w + 1):
                    c = np.int32(lut[np.uint32(abs(np.int32(f[np.uint64(base + dx)]) - v))])
                    n += c
                    sx += c * dx
                    sy += c * dy
            rr = g - np.float32(n)
            idx[K] = pc
            rv[K] = rr
            mom[K, 0] = n
            mom[K, 1] = sx
            mom[K, 2] = sy
            # the grey level and the 3x3 minimum and maximum (in cache now; straight-line code)
            u, uw = np.uint64(pc), np.uint64(W)
            a0, a1, a2 = f[u - uw - 1], f[u - uw], f[u - uw + 1]
            a3, a4, a5 = f[u - 1], f[u], f[u + 1]
            a6, a7, a8 = f[u + uw - 1], f[u + uw], f[u + uw + 1]
            v0s[K] = a4
            lo3[K] = min(min(min(a0, a1), min(a2, a3)), min(min(a4, a5), min(min(a6, a7), a8)))
            hi3[K] = max(max(max(a0, a1), max(a2, a3)), max(max(a4, a5), max(max(a6, a7), a8)))
            K += rr > below
    return K


@_jit
def _contiguity(sx, sy, W):
    """The flat offsets of the three pixels from the nucleus towards the USAN centroid (sx, sy)
    (``_susan._corner_tests``: along the centroid's larger axis, rounded half away from zero)."""
    ax, ay = abs(sx), abs(sy)
    along_x = ay < ax
    if along_x:
        slope = sy / (ax if ax > 0 else 1.0)
        sgn = np.int64(np.sign(sx))
    else:
        slope = sx / (ay if ay > 0 else 1.0)
        sgn = np.int64(np.sign(sy))
    return _step(1, slope, sgn, along_x, W), _step(2, slope, sgn, along_x, W), _step(3, slope, sgn, along_x, W)


@_jit
def _step(k, slope, sgn, along_x, W):
    ks = k * slope
    o = np.int64(np.trunc(ks + np.copysign(0.5, ks)))
    along = k * sgn
    return o * W + along if along_x else along * W + o


@_jit
def smooth_tests(gray, lut, mom, rows, idx, contig, saddle_area, full):
    """SUSAN's false-positive tests (``_susan._corner_tests`` with the smooth test) on the
    pixels ``idx[rows]``, from their moments ``mom`` (``candidates``): which pass, and which
    are saddles (X-junctions; only when ``saddle_area`` > 0).

    The moments are integers (exact in float64, as the float32 matrix products of the NumPy
    path are), every comparison the same float64 expression:
    1. the USAN centroid lies more than 1/sqrt(2) pixel from the nucleus;
    2. the three pixels towards it are in the USAN (their c sums to more than ``contig``);
    3. the unlike pixels are not split into brighter ones on one side and darker ones on
       the other (``full``: the mask's area x100; ``saddle_area``: 0.35 of it).
    """
    W = gray.shape[1]
    f = gray.ravel()
    N = len(rows)
    ok = np.zeros(N, np.bool_)
    saddle = np.zeros(N, np.bool_)
    for i in range(N):
        j = rows[i]
        n, sx, sy = np.float64(mom[j, 0]), np.float64(mom[j, 1]), np.float64(mom[j, 2])
        centroid = sx * sx + sy * sy > 0.5 * n * n
        if not centroid and saddle_area <= 0:
            continue
        p = idx[j]
        v = np.int32(f[p])
        s1, s2, s3 = _contiguity(sx, sy, W)
        total = 0.0
        for st in (s1, s2, s3):
            total += lut[np.uint64(abs(np.int32(f[np.uint64(p + st)]) - v))]
        if not total > contig and saddle_area <= 0:
            continue
        # the moments of the unlike pixels brighter than the nucleus (weights 100 - c)
        mb_, bx_, by_ = np.int32(0), np.int32(0), np.int32(0)
        for dy in range(-3, 4):
            w = _HALF[dy + 3]
            base = p + dy * W
            for dx in range(-w, w + 1):
                d = np.int32(f[np.uint64(base + dx)]) - v
                u = (100 - np.int32(lut[np.uint64(abs(d))])) * np.int32(d > 0)  # no branch per pixel
                mb_ += u
                bx_ += u * dx
                by_ += u * dy
        mb, bx, by = np.float64(mb_), np.float64(bx_), np.float64(by_)
        md = full - n - mb
        ddx = -sx - bx
        ddy = -sy - by
        if saddle_area > 0:
            ob = np.hypot(bx, by) / (mb if mb > 0 else 1.0)
            od = np.hypot(ddx, ddy) / (md if md > 0 else 1.0)
            saddle[i] = min(mb, md) > 0.3 * (mb + md) and mb + md > saddle_area and ob < 0.8 and od < 0.8
        if not (centroid and total > contig):
            continue
        opposite = bx * ddx + by * ddy < 0
        balanced = min(mb, md) > 0.25 * (mb + md)
        ok[i] = not (opposite and balanced)
    return ok, saddle


@_jit
def side_tests(gray, share, idx, rows, lo, hi, v, dark, contig, g100, floor, chord):
    """The in-between pixels ``idx[rows]`` that failed their own tests, judged as the side they
    belong to (``_susan._judge_mid``: ``_coverage_test``, then ``_mid_response``): which are
    corners that way, and their response (x100, float64; meaningful where they are).

    Each mask pixel counts by its share of that side (the dark one where ``dark``) between the
    grey levels ``lo`` and ``hi``: ``share[dark, span, x]`` is the NumPy path's float32 share
    (x100) of a pixel ``x`` grey levels above ``lo``, for a span ``hi - lo``, times 2^25 (an
    integer: the shares are multiples of 2^-25; uint32: the table's half a megabyte stays in a
    core's cache better than int64's whole one, 2 % of a texture's call); integer sums, times 2^-25, are the exact
    float64 sums of the NumPy path (``_susan._moments``), so the result is the same bit for bit.
    The side's USAN comes first: most pixels (about 9 in 10 on a photograph) fall short of the
    floor with it, whatever the centroid and contiguity tests would say, and skip them.
    """
    W = gray.shape[1]
    f = gray.ravel()
    tf = share.ravel()
    N = len(rows)
    got = np.zeros(N, np.bool_)
    r_mid = np.zeros(N, np.float64)
    for i in range(N):
        p = idx[rows[i]]
        l8 = np.int32(lo[i])
        span = max(np.int32(hi[i]) - l8, np.int32(1))
        # the table's row by its flat index: a view of it per pixel (``share[dark, span]``) cost numba
        # a reference count up and down each time, a quarter of this loop (page: 1.14 -> 0.85 ms)
        row = (np.int64(dark[i]) * 256 + np.int64(span)) * 256
        # the side's USAN and its moments in one pass (integers: the same sums in any order)
        n_, sx_, sy_ = 0, 0, 0
        for dy in range(-3, 4):
            w = _HALF[dy + 3]
            base = p + dy * W
            for dx in range(-w, w + 1):
                c = np.int64(tf[np.uint64(row + min(max(np.int32(f[np.uint64(base + dx)]) - l8, np.int32(0)), span))])
                n_ += c
                sx_ += c * dx
                sy_ += c * dy
        n = n_ * _UNFIX  # exact: below 2^53, times a power of 2
        # _mid_response: what the side falls short of a straight edge through the nucleus pixel
        h = np.float64(hi[i])
        a_dark = (h - np.float64(v[i])) / max(h - np.float64(lo[i]), 1.0)
        a_side = a_dark if dark[i] else 1.0 - a_dark
        rr = (g100 + chord * (a_side - 0.5)) - n
        if not (rr >= floor and rr > 0):
            continue
        # the centroid and contiguity tests of the side's USAN
        sx, sy = sx_ * _UNFIX, sy_ * _UNFIX
        if not sx * sx + sy * sy > 0.5 * n * n:
            continue
        s1, s2, s3 = _contiguity(sx, sy, W)
        total = 0.0
        for st in (s1, s2, s3):
            total += tf[np.uint64(row + min(max(np.int32(f[np.uint64(p + st)]) - l8, np.int32(0)), span))] * _UNFIX
        if total > contig:
            got[i] = True
            r_mid[i] = rr
    return got, r_mid


@_jit(inline="always")
def _disc_sum(sf, W, p):
    """The float32 sum over the mask of the flat image ``sf`` around pixel ``p``, adding the mask's
    pixels in raster order from 0 (OpenCV's ``filter2D`` with the disc: ``_susan._disc_sums_match``)."""
    s = np.float32(0.0)
    for dy in range(-3, 4):
        w = _HALF[dy + 3]
        base = p + dy * W
        for dx in range(-w, w + 1):
            s = s + sf[np.uint64(base + dx)]
    return s


@_jit
def judge(gray, share_img, lut, table, idx, rv, v0, lo3, hi3, mom, r_dark, a, b, c, value, ok, flat, resp):
    """Judge the candidates ``a .. b - 1`` (``candidates``' rows) each on its own, as
    ``_susan._judge`` does: ``value`` (their response after the tests, float32 x100), ``ok``
    (passed) and ``flat`` (an in-between grey that is no corner by the side it belongs to) are
    written in place, so calls on parts of the rows may run at once.

    An in-between pixel (its grey more than t/2 from its 3x3 minimum and maximum) gets the side
    estimate ``(g + chord (share - 1/2)) - sum of the shares over the mask`` in float32 from
    ``share_img`` (``_susan._coverage_response``; or ``r_dark[i]``, given, when ``c[9]`` is set):
    flat when it falls short of ``min_response`` less the slack; the others go through the
    false-positive tests, and an in-between one that fails them through the side's coverage
    test (``side_tests``).

    ``c``: float64 constants ``[t/2, g100, floor, chord x100, contig, full, g100 (as float32),
    slack (as float32), x100 (as float32), r_dark given, the side test's contiguity]``.

    ``resp`` (H, W) float32, zeros: the flat pixels' own response ``rv`` is written there (for
    ``saddles``, until ``settle``).
    """
    W = gray.shape[1]
    f = gray.ravel()
    sf = share_img.ravel()
    rf = resp.ravel()
    half_t, g100, floor, chord, contig, full = c[0], c[1], c[2], c[3], c[4], c[5]
    g32, slack32, scale32 = np.float32(c[6]), np.float32(c[7]), np.float32(c[8])
    chord32, half32 = np.float32(chord), np.float32(0.5)
    given = c[9] != 0
    n = b - a
    tested = np.empty(n, np.int64)  # the pixels that are not flat
    mids = np.empty(n, np.int64)  # the in-between ones, then those of them that are not flat
    r_mid_side = np.empty(n, np.float32)
    # in passes without a branch per pixel: whether a pixel is in-between or flat is as good as
    # random on a texture (2 in 3 candidates are in-between there), and each mispredicted branch
    # also cut short the overlap of the disc sums' chains of float32 additions (page: 1.1 ms -> ...)
    nm = 0
    for i in range(a, b):
        v, lo, hi = np.int32(v0[i]), np.int32(lo3[i]), np.int32(hi3[i])
        value[i] = rv[i]
        ok[i] = False
        flat[i] = False
        mids[nm] = i
        nm += (np.float64(v - lo) > half_t) & (np.float64(hi - v) > half_t)
    for j in range(nm):
        i = mids[j]
        r_mid_side[j] = r_dark[i] if given else (g32 + chord32 * (sf[idx[i]] - half32)) - scale32 * _disc_sum(sf, W, idx[i])
    kept = 0
    for j in range(nm):
        i = mids[j]
        rd = r_mid_side[j]
        is_flat = abs(rd) < slack32
        flat[i] = is_flat
        # the flat pixels' own response, for ``saddles`` (rv > 0: the other pixels' 0 is never above it)
        rf[idx[i]] = rv[i] * np.float32(is_flat)
        mids[kept] = i
        r_mid_side[kept] = rd
        kept += not is_flat
    nm = kept
    nt = 0
    for i in range(a, b):
        # the centroid test (``smooth_tests``' first) here: only the pixels that pass it go on to
        # the others (on a texture about 4 in 10 fail it, at random)
        n_, sx_, sy_ = np.float64(mom[i, 0]), np.float64(mom[i, 1]), np.float64(mom[i, 2])
        tested[nt] = i
        nt += (sx_ * sx_ + sy_ * sy_ > 0.5 * n_ * n_) & ~flat[i]
    good = smooth_tests(gray, lut, mom, tested[:nt], idx, contig, 0.0, full)[0]
    for j in range(nt):
        ok[tested[j]] = good[j]
    # the in-between pixels that fail their own tests, judged as the side they belong to
    sel = np.empty(nm, np.int64)
    dark = np.empty(nm, np.bool_)
    ns = 0
    for j in range(nm):
        if not ok[mids[j]]:
            sel[ns] = mids[j]
            dark[ns] = r_mid_side[j] > 0
            ns += 1
    sel, dark = sel[:ns], dark[:ns]
    got, r_mid = side_tests(gray, table, idx, sel, lo3[sel], hi3[sel], v0[sel], dark, c[10], g100, floor, chord)
    for j in range(ns):
        if got[j]:
            ok[sel[j]] = True
            value[sel[j]] = np.float32(r_mid[j])


@_jit
def saddles(gray, lut, idx, rv, mom, flat, resp, a, b, contig, saddle_area, full):
    """The rows of the saddles (X-junctions) among the ``flat`` candidates ``a .. b - 1``: those
    whose ``rv`` is at least that of every flat pixel in their 3x3 window (``_corners_numpy``'s 3x3
    dilation of the flat pixels' own response) and that pass the saddle test (``_smooth_one``).
    ``resp``: ``judge``'s map of the flat pixels' ``rv`` (zeros elsewhere), read only: calls on
    parts of the rows may run at once."""
    W = gray.shape[1]
    s = resp.ravel()
    top = np.empty(b - a, np.int64)
    n = 0
    for i in range(a, b):
        if not flat[i]:
            continue
        p = idx[i]
        v = rv[i]
        best = True
        for dy in range(-1, 2):
            for dx in range(-1, 2):
                best &= s[np.uint64(p + dy * W + dx)] <= v
        if best:
            top[n] = i
            n += 1
    top = top[:n]
    return top[smooth_tests(gray, lut, mom, top, idx, contig, saddle_area, full)[1]]


@_jit
def settle(resp, idx, value, ok, flat, a, b):
    """The response map of the candidates ``a .. b - 1`` (after ``saddles``): their value, negated
    where they failed (undecided: ``put_back``, ``lazy_maxima``), 0 where flat (the saddles'
    values follow: ``_susan._corners_compiled``). Calls on parts of the rows may run at once."""
    f = resp.ravel()
    for i in range(a, b):
        f[idx[i]] = np.float32(0.0) if flat[i] else (value[i] if ok[i] else -value[i])


@_jit
def assemble(idx, value, ok, flat, ws):
    """The passing pixels (the saddles, rows ``ws``, first, then the others in raster order), the
    failing ones and their values (``put_back``)."""
    K = len(idx)
    n_pass = len(ws)
    n_fail = 0
    for i in range(K):
        if not flat[i]:
            if ok[i]:
                n_pass += 1
            else:
                n_fail += 1
    passing = np.empty(n_pass, np.int64)
    failing = np.empty(n_fail, np.int64)
    fv = np.empty(n_fail, np.float32)
    for j in range(len(ws)):
        passing[j] = idx[ws[j]]
    jp, jf = len(ws), 0
    for i in range(K):
        if flat[i]:
            continue
        if ok[i]:
            passing[jp] = idx[i]
            jp += 1
        else:
            failing[jf] = idx[i]
            fv[jf] = value[i]
            jf += 1
    return passing, failing, fv


@_jit
def put_back(resp, r, failing, fv, seed):
    """Put back the failing pixels (``failing``, values ``fv``, zero in ``resp``) that are hidden
    under a larger pixel that stays (``_susan._hidden_failures``: a failing pixel stays when a
    larger pixel that stays lies in its window): the ``seed`` ones (under a larger passing one), then, from the windows of the pixels found to stay, the smaller failing
    ones, which stay in turn (depth first: the least set closed under that rule, the NumPy
    path's pixels). The failing pixels not found to stay wait in ``resp`` as their negated
    value meanwhile, and are zero at the end. ``resp`` is updated in place."""
    H, W = resp.shape
    f = resp.ravel()
    stack = np.empty(len(failing), np.int64)
    top = 0
    for i in range(len(failing)):
        p = failing[i]
        if seed[i]:
            f[p] = fv[i]
            stack[top] = p
            top += 1
        else:
            f[p] = -fv[i]
    while top > 0:
        top -= 1
        p = stack[top]
        v = f[p]
        y, x = p // W, p % W
        y0, y1, x0, x1 = max(y - r, 0), min(y + r + 1, H), max(x - r, 0), min(x + r + 1, W)
        for yy in range(y0, y1):
            row = yy * W
            hit = False  # first without branches (most rows of a window have none to put back)
            for xx in range(x0, x1):
                u = f[np.uint64(row + xx)]
                hit |= (u < 0) & (-u < v)
            if not hit:
                continue
            for xx in range(x0, x1):
                q = np.uint64(row + xx)
                u = f[q]
                if u < 0 and -u < v:
                    f[q] = -u
                    stack[top] = q
                    top += 1
    for i in range(len(failing)):
        if f[failing[i]] <= 0:
            f[failing[i]] = 0.0


@_jit
def window_maxima(resp, r, passing):
    """Which pixels of ``passing`` (flat indices) are maxima of ``resp`` (H, W) in their (2r+1)^2
    window, above 0 (on a plateau the first in raster order). Reads ``resp`` only."""
    H, W = resp.shape
    f = resp.ravel()
    keep = np.zeros(len(passing), np.bool_)
    for i in range(len(passing)):
        p = passing[i]
        v = f[p]
        if not v > 0:
            continue
        y, x = p // W, p % W
        good = True
        for yy in range(max(y - r, 0), min(y + r + 1, H)):
            for xx in range(max(x - r, 0), min(x + r + 1, W)):
                q = f[yy * W + xx]
                if q > v or (q == v and (yy < y or (yy == y and xx < x))):
                    good = False
            if not good:
                break
        keep[i] = good
    return keep


@_jit
def share_image(gray, lo, hi, out, y0, y1):
    """``out`` (H, W) float32, rows ``y0 .. y1 - 1``: ``min((hi - I)+ / max(hi - lo, 1), 1)``, the
    dark share of each pixel, as ``_susan._coverage_response`` computes it with OpenCV (a
    float32 division of the same integers: the correctly rounded quotient either way)."""
    g, l, h, o = gray[y0:y1].ravel(), lo[y0:y1].ravel(), hi[y0:y1].ravel(), out[y0:y1].ravel()
    one, zero = np.float32(1.0), np.float32(0.0)
    # from 0 over 1-D views: indices numba knows are not negative, so LLVM makes the loop SIMD
    # (over the image's flat index from y0 * W it was scalar: 0.5 ms, now 0.06 ms at 640x480)
    for i in range(len(g)):
        hf = np.float32(h[i])  # grey levels: their differences are exact in float32
        o[i] = min(max(hf - np.float32(g[i]), zero) / max(hf - np.float32(l[i]), one), one)
    return out


@_jit
def disc_sums(share, idx):
    """``_disc_sum`` around the pixels ``idx`` (flat, at least 3 from the border) of ``share`` (H, W) float32."""
    W = share.shape[1]
    f = share.ravel()
    out = np.empty(len(idx), np.float32)
    for i in range(len(idx)):
        out[i] = _disc_sum(f, W, idx[i])
    return out


@_jit
def refine(gray, pts, wq, moves, out):
    """``_susan._refine``'s NumPy code for the corners ``pts`` (N, 2) float64 (whole pixels), into
    ``out`` (N, 2) float64: the same integer sums (exact in any order) and float64 steps."""
    H, W = gray.shape
    w = (wq.shape[0] - 1) // 2
    for i in range(len(pts)):
        x0, y0 = np.int64(pts[i, 0]), np.int64(pts[i, 1])
        cx, cy = x0, y0
        ex, ey = pts[i, 0], pts[i, 1]
        for _ in range(moves + 1):
            if cx < w + 1 or cy < w + 1 or cx > W - w - 2 or cy > H - w - 2:
                break
            a = b = c = bx = by = np.int64(0)
            for dy in range(-w, w + 1):
                y = np.uint64(cy + dy)
                for dx in range(-w, w + 1):
                    x = np.uint64(cx + dx)
                    gx = np.int64(gray[y, x + np.uint64(1)]) - np.int64(gray[y, x - np.uint64(1)])
                    gy = np.int64(gray[y + np.uint64(1), x]) - np.int64(gray[y - np.uint64(1), x])
                    m = wq[dy + w, dx + w]
                    xx, xy, yy = m * gx * gx, m * gx * gy, m * gy * gy
                    a += xx
                    b += xy
                    c += yy
                    bx += xx * dx + xy * dy
                    by += xy * dx + yy * dy
            det = a * c - b * b
            if det <= 0:
                break
            ex = cx + np.float64(c * bx - b * by) / np.float64(det)
            ey = cy + np.float64(a * by - b * bx) / np.float64(det)
            nx, ny = np.int64(np.floor(ex + 0.5)), np.int64(np.floor(ey + 0.5))
            if nx == cx and ny == cy:
                break
            cx, cy = nx, ny
        if (ex - x0) ** 2 + (ey - y0) ** 2 <= 9.0:
            out[i, 0], out[i, 1] = ex, ey
        else:
            out[i, 0], out[i, 1] = pts[i, 0], pts[i, 1]
    return out


@_jit(inline="always")
def _range7(f, W, p, others):
    """``_window_range`` of a 7 x 7 window inside the image: a maximum and a minimum per column, then
    of the columns (seven chains of seven comparisons side by side, not one of 49)."""
    h0 = h1 = h2 = h3 = h4 = h5 = h6 = np.float32(-np.inf)
    l0 = l1 = l2 = l3 = l4 = l5 = l6 = np.float32(np.inf)
    one = np.uint64(1)
    q = np.uint64(p - 3 * W - 3)
    for yy in range(7):
        u0, u1, u2 = f[q], f[q + one], f[q + np.uint64(2)]
        u4, u5, u6 = f[q + np.uint64(4)], f[q + np.uint64(5)], f[q + np.uint64(6)]
        h0, h1, h2, h4, h5, h6 = max(h0, u0), max(h1, u1), max(h2, u2), max(h4, u4), max(h5, u5), max(h6, u6)
        l0, l1, l2, l4, l5, l6 = min(l0, u0), min(l1, u1), min(l2, u2), min(l4, u4), min(l5, u5), min(l6, u6)
        if yy != 3 or not others:
            u3 = f[q + np.uint64(3)]
            h3, l3 = max(h3, u3), min(l3, u3)
        q += np.uint64(W)
    hi = max(max(max(h0, h1), max(h2, h3)), max(max(h4, h5), h6))
    lo = min(min(min(l0, l1), min(l2, l3)), min(min(l4, l5), l6))
    return hi, lo


@_jit(inline="always")
def _window_range(f, H, W, r, p, others):
    """The largest and the smallest value of ``f`` (an (H, W) image, flat) in the (2r+1)^2 window of
    ``p`` (with ``others``, leaving ``p`` out), without branches per pixel (LLVM makes it SIMD)."""
    y, x = p // W, p % W
    if r == 3 and 3 <= y < H - 3 and 3 <= x < W - 3:
        return _range7(f, W, p, others)
    x0, x1 = max(x - r, 0), min(x + r + 1, W)
    hi, lo = np.float32(-np.inf), np.float32(np.inf)
    for yy in range(max(y - r, 0), min(y + r + 1, H)):
        row = yy * W
        cut = x if others and yy == y else x1  # the centre row in two parts, around p
        for xx in range(x0, cut):
            u = f[np.uint64(row + xx)]
            hi = max(hi, u)
            lo = min(lo, u)
        for xx in range(min(cut + 1, x1), x1):
            u = f[np.uint64(row + xx)]
            hi = max(hi, u)
            lo = min(lo, u)
    return hi, lo


@_jit
def lazy_maxima(resp, r, passing, a, b, frames, larger, keep):
    """``window_maxima`` of the passing pixels after ``put_back``, deciding only the failing pixels
    that could hide a corner: those at least as large as a passing pixel that is the largest in
    its window of the pixels that stay for certain.

    ``resp``: the response map of ``assemble`` (the passing pixels' values, the failing ones'
    negated: undecided, zeros elsewhere), in which a failing pixel, once asked, is written as its
    value (it stays: a larger pixel that stays lies in its window) or 0 (it does not). A failing pixel
    stays when a chain of ever larger failing pixels, each in the window of the one before,
    reaches a larger passing pixel: searched depth first up such chains, each pixel decided
    once, its window read once. The same maxima as ``put_back`` then ``window_maxima``, which
    decide every failing pixel (the response map is left half-decided).

    The passing pixels ``passing[a:b]``, into ``keep[a:b]``: two calls on two parts may run at
    once, each on its own copy of the map (``_susan._corners_compiled``): this kernel assumes no
    one else writes the map while it runs (two calls sharing one gave other corners now and then).

    ``frames`` (4, D) int64 and ``larger`` (L,) int64: room for a chain of D pixels and the L
    larger ones in their windows. False when the room ran out: call again with more (what was
    decided stays so). (numba counts the references of an array variable assigned again in a
    loop, on every pass: growing them here cost 3x.)"""
    H, W = resp.shape
    f = resp.ravel()
    # the chain searched, smallest first; each one's next larger pixel to try in `larger` (-1: its
    # window not read yet), and where its larger pixels are there
    chain, nxt, begin, end = frames[0], frames[1], frames[2], frames[3]
    keep[a:b] = False
    for i in range(a, b):
        p = passing[i]
        v = f[p]
        if not v > 0:
            continue
        hi, lo = _window_range(f, H, W, r, p, True)
        if hi > v:  # a larger pixel stays
            continue
        if hi < v and -lo < v:  # nor could an undecided one be as large
            keep[i] = True
            continue
        # a pixel as large (ties: the first in raster order, the flat index's), or a failing one that could stay
        y, x = p // W, p % W
        y0, y1, x0, x1 = max(y - r, 0), min(y + r + 1, H), max(x - r, 0), min(x + r + 1, W)
        good, threat = True, False
        for yy in range(y0, y1):
            row = yy * W
            for xx in range(x0, x1):
                q = row + xx
                u = f[q]
                e = q < p
                good &= (u < v) | ((u == v) & ~e)
                threat |= (-u > v) | ((-u == v) & e)
        if good and threat:
            for yy in range(y0, y1):
                row = yy * W
                for xx in range(x0, x1):
                    q = row + xx
                    u = f[q]
                    if not (-u > v or (-u == v and q < p)):
                        continue
                    # does it stay? up the chains of larger undecided failing pixels from it
                    chain[0], nxt[0] = q, -1
                    top, m, stays = 1, 0, False
                    while top > 0:
                        j = top - 1
                        s = chain[j]
                        if nxt[j] < 0:  # first visit: a larger pixel that stays in its window, or the larger undecided ones
                            sv = -f[s]
                            top_v, low_v = _window_range(f, H, W, r, s, False)
                            if top_v > sv:
                                stays = True
                                break
                            begin[j] = m
                            if -low_v > sv:
                                sy, sx = s // W, s % W
                                for ty in range(max(sy - r, 0), min(sy + r + 1, H)):
                                    trow = ty * W
                                    for tx in range(max(sx - r, 0), min(sx + r + 1, W)):
                                        if -f[trow + tx] > sv:
                                            if m == len(larger):
                                                return False
                                            larger[m] = trow + tx
                                            m += 1
                            nxt[j], end[j] = begin[j], m
                        if nxt[j] == end[j]:  # none of the larger ones stays: neither does this one
                            f[s] = 0.0
                            m = begin[j]
                            top -= 1
                            continue
                        t = larger[nxt[j]]
                        nxt[j] += 1
                        if f[t] < 0:  # still undecided (0: found not to stay since, up another chain)
                            if top == len(chain):
                                return False
                            chain[top], nxt[top] = t, -1
                            top += 1
                    if stays:  # and so does every pixel of the chain below it, each in the next one's window
                        for j in range(top):
                            f[chain[j]] = -f[chain[j]]
                        good = False
                        break
                if not good:
                    break
        keep[i] = good
    return True
