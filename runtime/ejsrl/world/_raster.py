"""A z-buffer triangle rasterizer in NumPy (the CPU back end of ``ejsrl.world.render``).

How it works, all vectorised over triangles, rows and fragments (no Python loop over them):

1. drop back faces, triangles behind the near plane or wholly beyond the far one, and clip
   the camera-frame triangles that cross the near plane (one becomes one or two);
2. project them with K; ``1/Z`` is an affine function of the pixel coordinates over a
   triangle, so each triangle gets its plane ``1/Z = p u + q v + r``;
3. cut every triangle into one horizontal span per pixel row it covers, from its three
   edge functions (a pixel centre (u, v) with integer u, v is inside when all three edge
   functions are >= 0, with a tiny tolerance so that shared edges leave no pinholes);
   each triangle's edges are sorted once into a left one, a right one and a third, so a
   span needs two bounds and one conditional bound rather than three conditional ones;
4. expand the spans into fragments (pixel index, span index, depth) with one ``np.repeat``
   of the span index and gathers;
5. z-test with one ``np.minimum.at`` over a 64-bit key: the float32 depth's bits (which
   order like the depths, the depths being positive) in the high word and the span index
   in the low word, so the nearest fragment wins and ties go to the lower span, that is
   the lower triangle: the output is deterministic. An empty pixel keeps the key
   (inf, number of spans), which decodes to depth inf directly.

Speed: the work arrays are laid out vertex-major ((3, 3, F) and (k, S) rows, contiguous),
and the large per-fragment and per-pixel work buffers are kept per thread and reused
from frame to frame: a fresh multi-megabyte array costs a page fault per 4 KiB, which
was half the frame time. Nothing returned to the caller aliases these buffers.
"""

from __future__ import annotations

import sys
import threading

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["ZBuffer", "clip_near", "face_normals", "front_faces", "rasterize", "vertex_major", "zbuffer"]

_EDGE_EPS = 1e-7
_INF_BITS = int(np.float32(np.inf).view(np.int32))
_FMAX = np.float32(np.finfo(np.float32).max)
_LOW32 = np.int64(0xFFFFFFFF)
_F32_EXACT = 1 << 24  # integers below this are exact in float32
_HI = 1 if sys.byteorder == "little" else 0  # which int32 of an int64 holds its high word


class _Scratch(threading.local):
    """Work buffers of one thread, grown on demand and reused by the next frame."""

    def __init__(self) -> None:
        self.bufs: dict[str, np.ndarray] = {}

    def get(self, name: str, n: int, dtype: type, cols: int = 0) -> np.ndarray:
        """A buffer of ``n`` elements (or ``(n, cols)``) of ``dtype``; its contents are stale."""
        size = n * max(cols, 1)
        buf = self.bufs.get(name)
        if buf is None or buf.size < size or buf.dtype != dtype:
            buf = np.empty(size + size // 4 + 4096, dtype=dtype)
            self.bufs[name] = buf
        out = buf[:size]
        return out.reshape(n, cols) if cols else out

    def arange(self, n: int, dtype: type = np.int64) -> np.ndarray:
        """0, 1, ..., n - 1, computed once per size class and dtype and kept."""
        name = f"arange_{np.dtype(dtype).name}"
        a = self.bufs.get(name)
        if a is None or a.size < n:
            a = np.arange(n + n // 4 + 4096, dtype=dtype)
            self.bufs[name] = a
        return a[:n]


_scratch = _Scratch()


def clip_near(tris_cam: NDArray[np.float64], near: float) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Clip camera-frame triangles (F, 3, 3) against the plane Z = ``near``.

    Returns the clipped triangles (G, 3, 3), winding kept, and for each the index of the
    input triangle it came from (G,).
    """
    z = tris_cam[:, :, 2]
    inside = z >= near
    n_in = inside.sum(axis=1)
    keep = np.nonzero(n_in == 3)[0]
    mixed = np.nonzero((n_in == 1) | (n_in == 2))[0]
    if mixed.size == 0:
        return tris_cam[keep], keep
    t = tris_cam[mixed]
    ins = inside[mixed]
    one_in = n_in[mixed] == 1
    # the odd vertex: the lone inside one (one_in) or the lone outside one
    odd = np.where(one_in, np.argmax(ins, axis=1), np.argmin(ins, axis=1))
    order = (odd[:, None] + np.arange(3)[None, :]) % 3  # cyclic roll keeps the winding
    t = np.take_along_axis(t, order[:, :, None], axis=1)
    v0, v1, v2 = t[:, 0], t[:, 1], t[:, 2]

    def cut(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
        s = (near - a[:, 2]) / (b[:, 2] - a[:, 2])
        p = a + s[:, None] * (b - a)
        p[:, 2] = near
        return p

    i01, i02 = cut(v0, v1), cut(v0, v2)
    a = one_in
    b = ~one_in
    tri_a = np.stack([v0[a], i01[a], i02[a]], axis=1)
    tri_b1 = np.stack([i01[b], v1[b], v2[b]], axis=1)
    tri_b2 = np.stack([i01[b], v2[b], i02[b]], axis=1)
    out = np.concatenate([tris_cam[keep], tri_a, tri_b1, tri_b2])
    src = np.concatenate([keep, mixed[a], mixed[b], mixed[b]])
    return out, src


def vertex_major(tris: NDArray[np.float64]) -> NDArray[np.float64]:
    """Triangles (F, 3, 3) -> the same numbers laid out (3, 3, F): ``P[v, c]`` is coordinate c of vertex v."""
    return np.ascontiguousarray(np.asarray(tris, dtype=np.float64).reshape(-1, 3, 3).transpose(1, 2, 0))


def face_normals(P: NDArray[np.float64]) -> NDArray[np.float64]:
    """Unnormalised normals ``(v1 - v0) x (v2 - v0)`` (3, F) of vertex-major triangles ``P`` (3, 3, F)."""
    (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = P
    ax, ay, az = x1 - x0, y1 - y0, z1 - z0
    bx, by, bz = x2 - x0, y2 - y0, z2 - z0
    return np.stack([ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx])


class ZBuffer:
    """The result of ``zbuffer``: per-pixel keys and what their low words mean.

    ``keys`` (H * W,) int64: float32 depth bits << 32 | span index, ``(inf bits, n_spans)``
    where empty; a per-thread work buffer, valid until the next call in this thread.
    ``ids`` (G,) int64: the input triangle of each rasterized (clipped) triangle.
    ``span_tri`` (n_spans,) int64: the rasterized triangle of each span.
    """

    __slots__ = ("keys", "ids", "span_tri", "width", "height")

    def __init__(
        self, keys: NDArray[np.int64], ids: NDArray[np.int64], span_tri: NDArray[np.int64], width: int, height: int
    ) -> None:
        self.keys, self.ids, self.span_tri, self.width, self.height = keys, ids, span_tri, width, height

    def lookup(self, per_tri: np.ndarray, empty: ArrayLike) -> np.ndarray:
        """A new (H, W, ...) array: ``per_tri[i]`` where rasterized triangle i is seen, ``empty`` elsewhere.

        ``per_tri``: (G, ...) values of the rasterized triangles (for example ``ids``).
        """
        table = np.concatenate([per_tri[self.span_tri], np.asarray(empty, dtype=per_tri.dtype)[None]])
        idx = _scratch.get("key_index", self.keys.size, np.int64)
        np.bitwise_and(self.keys, _LOW32, out=idx)
        return table.take(idx, axis=0).reshape((self.height, self.width) + table.shape[1:])

    def depth(self) -> NDArray[np.float32]:
        """A new (H, W) float32 array: Z in metres, inf where empty."""
        return self.keys.view(np.float32)[_HI::2].reshape(self.height, self.width).copy()

    def face(self) -> NDArray[np.int64]:
        """A new (H, W) int64 array: the input triangle seen at each pixel, -1 where none."""
        return self.lookup(self.ids, -1)


def zbuffer(
    P: NDArray[np.float64],
    K: NDArray[np.float64],
    width: int,
    height: int,
    *,
    near: float = 0.01,
    far: float = np.inf,
    front: NDArray[np.bool_] | None = None,
) -> ZBuffer:
    """Z-buffer vertex-major camera-frame triangles ``P`` (3, 3, F) (see ``vertex_major``).

    ``front``: (F,) bool, the faces to draw (the front faces when culling), or None for all.
    """
    W, H = int(width), int(height)
    npix = W * H
    F_in = P.shape[2]
    Z = P[:, 2]
    zmax = np.maximum(np.maximum(Z[0], Z[1]), Z[2])
    keep = zmax >= near
    if front is not None:
        keep &= front
    zmin = np.minimum(np.minimum(Z[0], Z[1]), Z[2])
    if np.isfinite(far):
        keep &= zmin <= far  # drop triangles wholly beyond the far plane
    ids = np.flatnonzero(keep)
    if len(ids) < F_in:
        P = P.take(ids, axis=2)
    if len(ids) and zmin[ids].min() < near:
        clipped, src = clip_near(P.transpose(2, 0, 1), near)
        ids = ids[src]
        P = vertex_major(clipped)

    # -- project: u = (K @ P)_x / Z ...
    X, Y, Z = P[:, 0], P[:, 1], P[:, 2]
    beyond_far = bool(np.isfinite(far) and Z.size and Z.max() > far)
    w = 1.0 / Z
    u = (K[0, 0] * X + K[0, 1] * Y) * w + K[0, 2]
    v = (K[1, 1] * Y) * w + K[1, 2]
    u0, u1, u2 = u
    v0, v1, v2 = v
    area2 = (u1 - u0) * (v2 - v0) - (u2 - u0) * (v1 - v0)
    # bounding boxes in whole pixels, clipped to the image
    xmin = np.maximum(np.ceil(np.minimum(np.minimum(u0, u1), u2) - _EDGE_EPS), 0)
    xmax = np.minimum(np.floor(np.maximum(np.maximum(u0, u1), u2) + _EDGE_EPS), W - 1)
    ymin = np.maximum(np.ceil(np.minimum(np.minimum(v0, v1), v2) - _EDGE_EPS), 0)
    ymax = np.minimum(np.floor(np.maximum(np.maximum(v0, v1), v2) + _EDGE_EPS), H - 1)
    ok = (np.abs(area2) > 1e-12) & (xmin <= xmax) & (ymin <= ymax)
    if not ok.all():
        sel = np.flatnonzero(ok)
        u, v, w = u.take(sel, axis=1), v.take(sel, axis=1), w.take(sel, axis=1)
        u0, u1, u2 = u
        v0, v1, v2 = v
        area2, xmin, xmax, ymin, ymax, ids = area2[sel], xmin[sel], xmax[sel], ymin[sel], ymax[sel], ids[sel]
    F = len(area2)

    def empty() -> ZBuffer:
        keys = _scratch.get("zbuf", npix, np.int64)
        keys.fill(np.int64(_INF_BITS << 32))
        return ZBuffer(keys, ids[:0], np.zeros(0, dtype=np.int64), W, H)

    if F == 0:
        return empty()

    # -- the plane 1/Z = p u + q v + r of each triangle
    w0, w1, w2 = w
    inv_a = 1.0 / area2
    p = ((w1 - w0) * (v2 - v0) - (w2 - w0) * (v1 - v0)) * inv_a
    q = ((u1 - u0) * (w2 - w0) - (u2 - u0) * (w1 - w0)) * inv_a
    r = w0 - p * u0 - q * v0

    # -- edge functions E = A u + B v + C, >= 0 inside for a positively oriented triangle
    sgn = np.sign(area2)
    A = np.stack([v0 - v1, v1 - v2, v2 - v0]) * sgn
    B = np.stack([u1 - u0, u2 - u1, u0 - u2]) * sgn
    C = np.stack([u0 * (v1 - v0) - v0 * (u1 - u0), u1 * (v2 - v1) - v1 * (u2 - u1), u2 * (v0 - v2) - v2 * (u0 - u2)]) * sgn
    # The A of the three edges sum to zero and are not all zero: the largest is > 0 (a
    # left edge: a lower bound on u along a row), the smallest < 0 (a right edge).
    a0, a1, a2 = A
    imax = np.where(a0 >= a1, np.where(a0 >= a2, 0, 2), np.where(a1 >= a2, 1, 2))
    imin = np.where(a0 < a1, np.where(a0 < a2, 0, 2), np.where(a1 < a2, 1, 2))
    imid = 3 - imax - imin
    col = np.arange(F)
    nrows = (ymax - ymin + 1).astype(np.int64)
    first = np.cumsum(nrows) - nrows
    # one row of this table per triangle and span parameter, gathered once per span
    table = np.stack(
        [ymin - first, xmin, xmax]
        + [E[i, col] for i in (imax, imid, imin) for E in (A, B, C)]
        + [p, q, r]
    )

    # -- one span per (triangle, row): the pixels [lo, hi] of the row inside the triangle.
    # Work arrays are rows of reused buffers and the arithmetic runs in place.
    S = int(nrows.sum())
    tri_of_span = np.repeat(np.arange(F), nrows.astype(np.intp))  # counts as intp: 32-bit in a browser's Python
    cols = table.take(tri_of_span, axis=1, out=_scratch.get("span_table", 15 * S, np.float64).reshape(15, S), mode="clip")
    ys = cols[0]
    ys += _scratch.arange(S)
    t, lo, hi, rhs, c = _scratch.get("span_work", 5 * S, np.float64).reshape(5, S)

    def crossing(a: int, out: NDArray[np.float64]) -> NDArray[np.float64]:
        """u where edge E = A u + B v + C of table rows a, a + 1, a + 2 crosses the row: -(B v + C) / A."""
        np.multiply(cols[a + 1], ys, out=out)
        out += cols[a + 2]
        np.negative(out, out=out)
        out /= cols[a]
        return out

    with np.errstate(divide="ignore", invalid="ignore"):
        crossing(3, t)  # the left edge: u >= t
        t -= _EDGE_EPS
        np.maximum(cols[1], np.ceil(t, out=t), out=lo)
        crossing(9, t)  # the right edge: u <= t
        t += _EDGE_EPS
        np.minimum(cols[2], np.floor(t, out=t), out=hi)
        A1 = cols[6]  # the third edge: left, right or horizontal
        np.multiply(cols[7], ys, out=rhs)
        rhs += cols[8]
        np.negative(rhs, out=t)
        t /= A1
        np.subtract(t, _EDGE_EPS, out=c)
        np.maximum(lo, np.ceil(c, out=c), out=lo, where=A1 > 0)
        np.add(t, _EDGE_EPS, out=c)
        np.minimum(hi, np.floor(c, out=c), out=hi, where=A1 < 0)
        flat = A1 == 0
        if flat.any():
            hi[flat & (rhs < -_EDGE_EPS)] = -1.0
    np.subtract(hi, lo, out=t)
    t += 1.0  # pixels in the span
    has = t > 0
    pqr = cols[12:15]
    if not has.all():
        sel = np.flatnonzero(has)
        S = len(sel)
        kept = _scratch.get("span_kept", 6 * S, np.float64).reshape(6, S)
        for src, dst in zip((t, lo, ys, pqr[0], pqr[1], pqr[2]), kept):
            src.take(sel, out=dst, mode="clip")
        t, lo, ys, pqr = kept[0], kept[1], kept[2], kept[3:6]
        tri_of_span = tri_of_span[sel]
    count = _scratch.get("count", S, np.int64)
    np.copyto(count, t, casting="unsafe")
    N = int(count.sum())
    if N == 0:
        return empty()
    start = np.cumsum(count, out=_scratch.get("start", S, np.int64))
    start -= count
    # the pixel of fragment k is pix0[span] + k
    pix0 = _scratch.get("pix0", S, np.int64)
    np.multiply(ys, W, out=rhs[:S])
    rhs[:S] += lo
    np.copyto(pix0, rhs[:S], casting="unsafe")
    pix0 -= start
    # 1/Z along the span: its value at the first pixel, q v + r + p u, plus p per pixel to the right
    p_s, q_s, r_s = pqr
    np.multiply(q_s, ys, out=rhs[:S])
    rhs[:S] += r_s
    np.multiply(p_s, lo, out=c[:S])
    rhs[:S] += c[:S]
    inv0 = _scratch.get("inv0", S, np.float32)
    np.copyto(inv0, rhs[:S], casting="same_kind")
    p32 = _scratch.get("p32", S, np.float32)
    np.copyto(p32, p_s, casting="same_kind")
    start_f = _scratch.get("start_f", S, np.float32)  # exact below 2**24 fragments
    np.copyto(start_f, start, casting="unsafe")

    # -- fragments: span index, pixel index, 1/Z then Z
    sid = _scratch.get("sid", N, np.int64)  # 0 0 0 1 1 2 ...: a cumulative sum of span starts
    sid.fill(0)
    sid[start[1:]] = 1
    np.cumsum(sid, out=sid)
    pix = pix0.take(sid, out=_scratch.get("pix", N, np.int64), mode="clip")
    pix += _scratch.arange(N)
    # pixels right of the span's first one: k - start (in float32 when that is exact)
    x_local = _scratch.get("x_local", N, np.float32)
    if N < _F32_EXACT:
        start_f.take(sid, out=x_local, mode="clip")
        np.subtract(_scratch.arange(N, np.float32), x_local, out=x_local)
    else:
        np.subtract(_scratch.arange(N), start.take(sid), out=x_local, casting="unsafe")
    z32 = inv0.take(sid, out=_scratch.get("z32", N, np.float32), mode="clip")
    dz = p32.take(sid, out=_scratch.get("dz", N, np.float32), mode="clip")
    dz *= x_local
    z32 += dz
    np.reciprocal(z32, out=z32)
    np.clip(z32, np.float32(0.0), _FMAX, out=z32)  # rounding guard: keys must order like depths
    # the key: the span index (< 2**31) already fills the low word of sid; Z goes in the high one
    sid.view(np.int32).reshape(N, 2)[:, _HI] = z32.view(np.int32)
    key = sid
    empty_key = np.int64((_INF_BITS << 32) | S)
    if beyond_far:
        key[z32 > np.float32(far)] = empty_key  # per-pixel far clipping

    # -- z-test
    zbuf = _scratch.get("zbuf", npix, np.int64)
    zbuf.fill(empty_key)
    np.minimum.at(zbuf, pix, key)
    return ZBuffer(zbuf, ids, tri_of_span, W, H)


def rasterize(
    tris_cam: NDArray[np.float64],
    K: NDArray[np.float64],
    width: int,
    height: int,
    *,
    near: float = 0.01,
    far: float = np.inf,
    cull_backfaces: bool = True,
) -> tuple[NDArray[np.int64], NDArray[np.float32]]:
    """Rasterize camera-frame triangles (F, 3, 3) (x right, y down, z forward, metres).

    ``K``: (3, 3) intrinsics, pixel centres at integer coordinates. Returns ``face`` (H, W)
    int64: the index of the input triangle seen at each pixel, -1 where none; and ``depth``
    (H, W) float32: its Z (distance along the optical axis) there, inf where none.
    """
    P = vertex_major(tris_cam)
    front = None
    if cull_backfaces:
        front = front_faces(P, face_normals(P))
    zb = zbuffer(P, np.asarray(K, dtype=np.float64), width, height, near=near, far=far, front=front)
    return zb.face(), zb.depth()


def front_faces(P: NDArray[np.float64], n: NDArray[np.float64]) -> NDArray[np.bool_]:
    """(F,) bool: faces seen from the front, their normal ``n`` (3, F) pointing back at the camera."""
    return n[0] * P[0, 0] + n[1] * P[0, 1] + n[2] * P[0, 2] < 0.0
