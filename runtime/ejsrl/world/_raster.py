"""A z-buffer triangle rasterizer in NumPy (the CPU back end of ``ejsrl.world.render``).

How it works, all vectorised over triangles, rows and fragments (no Python loop over them):

1. clip the camera-frame triangles against the near plane (a triangle that crosses it
   becomes one or two triangles), drop back faces and those outside the image;
2. project them with K; ``1/Z`` is an affine function of the pixel coordinates over a
   triangle, so each triangle gets its plane ``1/Z = p u + q v + r``;
3. cut every triangle into one horizontal span per pixel row it covers, from its three
   edge functions (a pixel centre (u, v) with integer u, v is inside when all three edge
   functions are >= 0, with a tiny tolerance so that shared edges leave no pinholes);
4. expand the spans into fragments (pixel index, triangle index) with ``np.repeat``;
5. z-test with one ``np.minimum.at`` over a 64-bit key: the float32 depth's bits (which
   order like the depths, the depths being positive) in the high word and the triangle
   index in the low word, so the nearest fragment wins and ties go to the lower index:
   the output is deterministic.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["clip_near", "rasterize"]

_EDGE_EPS = 1e-7


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


def _empty(H: int, W: int) -> tuple[NDArray[np.int64], NDArray[np.float32]]:
    return np.full((H, W), -1, dtype=np.int64), np.full((H, W), np.inf, dtype=np.float32)


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
    W, H = int(width), int(height)
    npix = W * H
    far32 = np.float32(far if np.isfinite(far) else np.finfo(np.float32).max)
    tris_cam = np.asarray(tris_cam, dtype=np.float64).reshape(-1, 3, 3)

    if cull_backfaces and len(tris_cam):
        # a face is seen from the front when its normal points back towards the camera
        n = np.cross(tris_cam[:, 1] - tris_cam[:, 0], tris_cam[:, 2] - tris_cam[:, 0])
        front = np.einsum("ij,ij->i", n, tris_cam[:, 0]) < 0.0
        ids0 = np.nonzero(front)[0]
        tris_cam = tris_cam[ids0]
    else:
        ids0 = np.arange(len(tris_cam))
    # drop triangles wholly beyond the far plane before clipping
    if np.isfinite(far) and len(tris_cam):
        near_enough = tris_cam[:, :, 2].min(axis=1) <= far
        tris_cam, ids0 = tris_cam[near_enough], ids0[near_enough]
    tris, src = clip_near(tris_cam, near)
    ids = ids0[src]

    # project: u = (K @ P)_x / Z ...
    X, Y, Z = tris[:, :, 0], tris[:, :, 1], tris[:, :, 2]
    w = 1.0 / Z
    u = (K[0, 0] * X + K[0, 1] * Y) * w + K[0, 2]
    v = (K[1, 1] * Y) * w + K[1, 2]
    u0, u1, u2 = u[:, 0], u[:, 1], u[:, 2]
    v0, v1, v2 = v[:, 0], v[:, 1], v[:, 2]
    area2 = (u1 - u0) * (v2 - v0) - (u2 - u0) * (v1 - v0)

    # bounding boxes in whole pixels, clipped to the image
    xmin = np.maximum(np.ceil(u.min(axis=1) - _EDGE_EPS), 0)
    xmax = np.minimum(np.floor(u.max(axis=1) + _EDGE_EPS), W - 1)
    ymin = np.maximum(np.ceil(v.min(axis=1) - _EDGE_EPS), 0)
    ymax = np.minimum(np.floor(v.max(axis=1) + _EDGE_EPS), H - 1)
    ok = (np.abs(area2) > 1e-12) & (xmin <= xmax) & (ymin <= ymax)
    if not ok.all():
        sel = np.nonzero(ok)[0]
        u0, u1, u2, v0, v1, v2 = u0[sel], u1[sel], u2[sel], v0[sel], v1[sel], v2[sel]
        w = w[sel]
        area2, xmin, xmax, ymin, ymax, ids = area2[sel], xmin[sel], xmax[sel], ymin[sel], ymax[sel], ids[sel]
    F = len(area2)
    if F == 0:
        return _empty(H, W)

    # the plane 1/Z = p u + q v + r of each triangle
    w0, w1, w2 = w[:, 0], w[:, 1], w[:, 2]
    inv_a = 1.0 / area2
    p = ((w1 - w0) * (v2 - v0) - (w2 - w0) * (v1 - v0)) * inv_a
    q = ((u1 - u0) * (w2 - w0) - (u2 - u0) * (w1 - w0)) * inv_a
    r = w0 - p * u0 - q * v0

    # edge functions E = A u + B v + C, >= 0 inside for a positively oriented triangle
    sgn = np.sign(area2)
    A = np.stack([v0 - v1, v1 - v2, v2 - v0]) * sgn
    B = np.stack([u1 - u0, u2 - u1, u0 - u2]) * sgn
    C = np.stack([u0 * (v1 - v0) - v0 * (u1 - u0), u1 * (v2 - v1) - v1 * (u2 - u1), u2 * (v0 - v2) - v2 * (u0 - u2)]) * sgn

    # one span per (triangle, row)
    nrows = (ymax - ymin + 1).astype(np.int64)
    S = int(nrows.sum())
    tri_of_span = np.repeat(np.arange(F), nrows)
    first = np.cumsum(nrows) - nrows
    ys = ymin[tri_of_span] + (np.arange(S) - np.repeat(first, nrows))
    lo = xmin[tri_of_span].copy()
    hi = xmax[tri_of_span].copy()
    with np.errstate(divide="ignore", invalid="ignore"):
        for e in range(3):
            Ae, Be, Ce = A[e][tri_of_span], B[e][tri_of_span], C[e][tri_of_span]
            rhs = Be * ys + Ce  # E = Ae u + rhs
            t = -rhs / Ae
            pos = Ae > 0
            neg = Ae < 0
            lo = np.where(pos, np.maximum(lo, np.ceil(t - _EDGE_EPS)), lo)
            hi = np.where(neg, np.minimum(hi, np.floor(t + _EDGE_EPS)), hi)
            hi = np.where((Ae == 0) & (rhs < -_EDGE_EPS), -1.0, hi)
    count = (hi - lo + 1).astype(np.int64)
    has = count > 0
    if not has.all():
        sel = np.nonzero(has)[0]
        count, lo, ys, tri_of_span = count[sel], lo[sel], ys[sel], tri_of_span[sel]
    N = int(count.sum())
    if N == 0:
        return _empty(H, W)
    start = np.cumsum(count) - count

    # fragments: 32-bit indices and float32 depths (half the memory traffic of 64-bit)
    k = np.arange(N, dtype=np.int32)
    start32 = start.astype(np.int32)
    ys_i = ys.astype(np.int32)
    lo_i = lo.astype(np.int32)
    frag_pix = np.repeat(ys_i * np.int32(W) + lo_i - start32, count) + k
    frag_tri = np.repeat(tri_of_span.astype(np.int32), count)
    x_local = (k - np.repeat(start32, count)).astype(np.float32)
    # 1/Z along the span: its value at the first pixel plus p per pixel to the right
    inv0 = (q[tri_of_span] * ys + r[tri_of_span] + p[tri_of_span] * lo).astype(np.float32)
    inv_z = np.repeat(inv0, count)
    inv_z += np.repeat(p[tri_of_span].astype(np.float32), count) * x_local
    z32 = np.reciprocal(inv_z)
    np.maximum(z32, np.float32(0.0), out=z32)  # rounding guard: keys must order like depths
    key = (z32.view(np.int32).astype(np.int64) << 32) | frag_tri
    # an empty pixel keeps the key (far, F): it decodes to face -1 and then depth inf
    empty_key = (np.int64(far32.view(np.int32)) << 32) | np.int64(F)
    zbuf = np.full(npix, empty_key, dtype=np.int64)
    np.minimum.at(zbuf, frag_pix, key)
    ids_ext = np.append(ids, -1)
    face = ids_ext[zbuf & 0xFFFFFFFF]
    depth = (zbuf >> 32).astype(np.int32).view(np.float32)
    depth[face < 0] = np.inf
    return face.reshape(H, W), depth.reshape(H, W)
