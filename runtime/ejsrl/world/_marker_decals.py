"""Fiducial markers for the OpenGL back end: each black cell of a marker as a decal face.

The NumPy back end paints a marker per pixel (``rendering._paint_markers``: the marker cell
under the pixel's point of the face, from perspective-correct barycentrics). The OpenGL back
end draws the same marker as geometry instead, with its shaders unchanged: every black cell
of the marker, clipped to each face that carries it, becomes a small polygon in that face's
plane, fanned into triangles, lifted ``DECAL_LIFT`` towards the camera and coloured as the
face times ``MARKER_DARK``. A pixel is black in both when its centre falls in a black cell:
the two images differ only where a cell's edge passes within rounding of a pixel centre, and
by one grey level where the face's shade times ``MARKER_DARK`` rounds differently; depth on the
black cells is ``DECAL_LIFT`` nearer (tests/vision/test_render_gl.py).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["DECAL_LIFT", "marker_decals"]

#: how far (metres) a decal lies in front of its face, towards the camera: above the GL depth
#: test's resolution (1e-5 m at 50 m), below what a camera image shows (0.1 px at 0.5 m)
DECAL_LIFT = 5e-5


def _clip(poly: list[NDArray[np.float64]], a: NDArray[np.float64], b: NDArray[np.float64], inside_sign: float) -> list[NDArray[np.float64]]:
    """Sutherland-Hodgman: the part of the convex polygon ``poly`` (2D points) on the ``inside_sign``
    side of the line through ``a`` and ``b``."""
    def side(p: NDArray[np.float64]) -> float:
        return inside_sign * ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]))

    out: list[NDArray[np.float64]] = []
    for i, p in enumerate(poly):
        q = poly[(i + 1) % len(poly)]
        sp, sq = side(p), side(q)
        if sp >= 0:
            out.append(p)
        if (sp >= 0) != (sq >= 0):
            out.append(p + (q - p) * (sp / (sp - sq)))
    return out


def marker_decals(
    P: NDArray[np.float64], n: NDArray[np.float64], cols: NDArray[np.float64], coords: NDArray[np.float64],
    bitmaps: list[NDArray[np.bool_]], faces: NDArray[np.int64], dark: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
    """The decal faces of the markers on ``faces`` (indices of front faces).

    ``P`` (3 vertices, 3, F): camera-frame faces; ``n`` (3, F) their normals; ``cols`` (F, 3)
    colours in [0, 1]; ``coords``, ``bitmaps``: ``rendering.marker_coords``'s (u, v, k + 1) per
    corner and the markers' cells (True = black, row 0 at v = 1). Returns the decals' ``P``
    (3, 3, D), normals (3, D), colours (D, 3) (the face's times ``dark``), the face each comes
    from (D,), and each decal corner's barycentrics in that face (D, 3 corners, 3).
    """
    tris: list[NDArray[np.float64]] = []
    src: list[int] = []
    bary: list[NDArray[np.float64]] = []
    for f in faces:
        k = round(coords[f, 0, 2]) - 1
        if k < 0:
            continue
        bits = bitmaps[k]
        cells = bits.shape[0]
        U = coords[f, :, :2]  # (3 corners, 2): the face in the marker's (u, v)
        M = np.column_stack([U[1] - U[0], U[2] - U[0]])
        if abs(np.linalg.det(M)) < 1e-12:
            continue
        Minv = np.linalg.inv(M)
        orient = 1.0 if np.linalg.det(M) > 0 else -1.0
        lo, hi = U.min(axis=0), U.max(axis=0)
        c0, c1 = max(int(np.floor(lo[0] * cells)), 0), min(int(np.ceil(hi[0] * cells)), cells)
        r0, r1 = max(int(np.floor((1.0 - hi[1]) * cells)), 0), min(int(np.ceil((1.0 - lo[1]) * cells)), cells)
        V = P[:, :, f]  # (3 vertices, 3)
        nf = n[:, f] / np.linalg.norm(n[:, f])
        lift = -DECAL_LIFT * nf if nf @ V[0] > 0 else DECAL_LIFT * nf  # towards the camera (at the origin)
        for r in range(r0, r1):
            for c in range(c0, c1):
                if not bits[r, c]:
                    continue
                u0, u1 = c / cells, (c + 1) / cells
                v0, v1 = 1.0 - (r + 1) / cells, 1.0 - r / cells
                poly = [np.array(p) for p in ((u0, v0), (u1, v0), (u1, v1), (u0, v1))]
                for e in range(3):
                    poly = _clip(poly, U[e], U[(e + 1) % 3], orient)
                    if len(poly) < 3:
                        break
                if len(poly) < 3:
                    continue
                b12 = (np.array(poly) - U[0]) @ Minv.T  # (m, 2): barycentrics of corners 1 and 2
                b = np.column_stack([1.0 - b12.sum(axis=1), b12])
                X = b @ V + lift
                for j in range(1, len(poly) - 1):
                    tris.append(X[[0, j, j + 1]])
                    bary.append(b[[0, j, j + 1]])
                    src.append(int(f))
    if not tris:
        return np.zeros((3, 3, 0)), np.zeros((3, 0)), np.zeros((0, 3)), np.zeros(0, np.int64), np.zeros((0, 3, 3))
    s = np.array(src, dtype=np.int64)
    Pd = np.stack(tris).transpose(1, 2, 0)  # (3 vertices, 3, D)
    return Pd, n[:, s], cols[s] * dark, s, np.stack(bary)
