"""A more realistic virtual camera: the options and the image pipeline behind them.

``Realism`` holds what a ``camera`` element may ask for beyond the plain pinhole render
(all off by default, so a camera that asks for nothing renders bit for bit as before):

- ``antialias`` s: supersampling, every pixel the mean of s x s samples on a regular grid
  inside it (the scene is rendered s times finer, then averaged block by block);
- ``shading``: ``"flat"`` (one shade per face) or ``"smooth"`` (Gouraud: each corner gets
  the light of its vertex normal, the mean of the normals of the faces around it within
  ``CREASE_DEG`` of its own face, and colours are interpolated across the face,
  perspective-correct; a box keeps sharp edges, a sphere or cylinder side looks round);
- ``distortion`` (k1, k2, p1, p2, k3): lens distortion, applied with the camera's own
  ``CameraModel.distort`` to a pinhole render made with a margin around the frame (so
  barrel distortion pulls no black border in); depth is distorted the same way (nearest);
- ``blur``: defocus blur, a Gaussian of that standard deviation in pixels (OpenCV's
  ``GaussianBlur``, borders reflected);
- ``noise``: Gaussian sensor noise of that standard deviation in grey levels (0-255),
  independent per pixel and channel, added last, then the image is rounded and clipped.

The order is that of a real camera: optics (distortion, then blur), then the sensor
(sampling, noise). The depth image is ideal (no blur, no noise): the Z, along the optical
axis, of the surface seen through the pixel's centre.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["Realism", "CREASE_DEG", "SHADINGS", "corner_normals", "supersampled_K", "block_mean", "centre_depth"]

#: faces meeting at a vertex at more than this angle keep their own normal there (smooth shading)
CREASE_DEG: float = 40.0
#: the values of ``shading``
SHADINGS: tuple[str, ...] = ("flat", "smooth")
#: the widest margin (pixels, each side) rendered around the frame for lens distortion
_MAX_MARGIN_SHARE = 0.5


@dataclass(frozen=True)
class Realism:
    """What the virtual camera adds to a pinhole render (see the module docstring)."""

    antialias: int = 1
    shading: str = "flat"
    noise: float = 0.0
    blur: float = 0.0
    distortion: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not isinstance(self.antialias, (int, np.integer)) or isinstance(self.antialias, bool) or not 1 <= self.antialias <= 8:
            raise ValueError(f"camera antialias must be a whole number from 1 (off) to 8, got {self.antialias!r}")
        if self.shading not in SHADINGS:
            raise ValueError(f"camera shading must be one of {', '.join(map(repr, SHADINGS))}, got {self.shading!r}")
        for what, v in (("noise", self.noise), ("blur", self.blur)):
            if not (isinstance(v, (int, float, np.number)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"camera {what} must be a number >= 0 (0: off), got {v!r}")
        d = tuple(float(x) for x in self.distortion)
        if len(d) not in (2, 4, 5) or not all(math.isfinite(x) for x in d):
            raise ValueError(
                "camera distortion takes [k1, k2, p1, p2, k3] (OpenCV's order; or the first 2 or 4 of them), "
                f"finite numbers, got {list(self.distortion)}"
            )
        object.__setattr__(self, "distortion", d + (0.0,) * (5 - len(d)))

    @property
    def distorted(self) -> bool:
        return any(x != 0.0 for x in self.distortion)

    @property
    def plain(self) -> bool:
        """Nothing to add: the render is the plain pinhole one, bit for bit."""
        return self.antialias == 1 and self.shading == "flat" and self.noise == 0 and self.blur == 0 and not self.distorted

    @classmethod
    def from_props(cls, props: Mapping[str, Any]) -> Realism:
        """The options of a camera node's properties (missing ones are off)."""
        dist = props.get("distortion")
        return cls(
            antialias=int(props.get("antialias", 1) if props.get("antialias") is not None else 1),
            shading=str(props.get("shading") or "flat").strip().lower(),
            noise=float(props.get("noise") or 0.0),
            blur=float(props.get("blur") or 0.0),
            distortion=(0.0,) * 5 if dist is None else tuple(np.asarray(dist, dtype=float).reshape(-1)),
        )


def margin_for(camera: Any) -> int:
    """Pixels to render past each side of the frame so that every distorted pixel has a source."""
    if not camera.distorted:
        return 0
    W, H = camera.width, camera.height
    xs, ys = np.linspace(-0.5, W - 0.5, 33), np.linspace(-0.5, H - 0.5, 25)
    border = np.concatenate(
        [np.column_stack([xs, np.full_like(xs, -0.5)]), np.column_stack([xs, np.full_like(xs, H - 0.5)]),
         np.column_stack([np.full_like(ys, -0.5), ys]), np.column_stack([np.full_like(ys, W - 0.5), ys])]
    )
    ideal = camera.undistort_points(border)
    ideal = ideal[np.all(np.isfinite(ideal), axis=1)]
    if not len(ideal):
        return 0
    lo, hi = ideal.min(axis=0), ideal.max(axis=0)
    over = max(0.0, float(-lo[0]), float(hi[0] - (W - 1)), float(-lo[1]), float(hi[1] - (H - 1)))
    return int(min(math.ceil(over) + 2, _MAX_MARGIN_SHARE * max(W, H)))


def supersampled_K(K: NDArray[np.float64], s: int, margin: int = 0) -> NDArray[np.float64]:
    """Intrinsics of the render s times finer, with ``margin`` pixels (of the output) added each side.

    Pixel centres at integer coordinates: output pixel u covers [u - 1/2, u + 1/2], whose
    sub-pixel j (0..s-1) has its centre at fine coordinate s (u + margin) + j, at output
    coordinate u + (j + 1/2) / s - 1/2; so u_fine = s (u + margin) + (s - 1) / 2.
    """
    S = np.diag([float(s), float(s), 1.0])
    S[0, 2] = S[1, 2] = s * margin + (s - 1) / 2.0
    return S @ np.asarray(K, dtype=np.float64)


def block_mean(img: NDArray[Any], s: int) -> NDArray[np.float32]:
    """(s H, s W[, C]) -> (H, W[, C]) float32, the mean of each s x s block."""
    if s == 1:
        return np.asarray(img, dtype=np.float32)
    a = np.asarray(img)
    out = np.zeros((a.shape[0] // s, a.shape[1] // s) + a.shape[2:], dtype=np.float32)
    for j in range(s):  # s * s strided adds: much faster than a mean over reshaped axes
        for k in range(s):
            out += a[j::s, k::s]
    out *= np.float32(1.0 / (s * s))
    return out


def centre_depth(depth: NDArray[np.float32], s: int) -> NDArray[np.float32]:
    """Depth at the output pixels' centres from a render s times finer.

    Odd s: the centre sub-sample. Even s: from the four sub-samples around the centre, the
    mean of 1/Z (exact on a plane, where 1/Z is affine in the pixel coordinates) where all
    four see a surface, the nearest elsewhere.
    """
    if s == 1:
        return depth
    h = s // 2
    if s % 2:
        return np.ascontiguousarray(depth[h::s, h::s])
    c = [depth[j::s, k::s] for j in (h - 1, h) for k in (h - 1, h)]
    with np.errstate(divide="ignore"):
        inv = sum(1.0 / x for x in c) / 4.0
        finite = np.isfinite(c[0]) & np.isfinite(c[1]) & np.isfinite(c[2]) & np.isfinite(c[3])
        out = np.where(finite, 1.0 / inv, np.minimum(np.minimum(c[0], c[1]), np.minimum(c[2], c[3])))
    return out.astype(np.float32)


def corner_normals(P: NDArray[np.float64], n: NDArray[np.float64], crease_deg: float = CREASE_DEG) -> NDArray[np.float64]:
    """Unit normals (3 corners, 3, F) for smooth shading of vertex-major triangles ``P`` (3, 3, F).

    ``n`` (3, F): the faces' (unnormalised) normals. Corners at the same position share a
    vertex; a corner's normal is the area-weighted sum of the normals of the faces at its
    vertex that make less than ``crease_deg`` with its own face (its own included).
    """
    F = P.shape[2]
    if F == 0:
        return np.zeros((3, 3, 0))
    corners = P.transpose(0, 2, 1).reshape(3 * F, 3)  # corner k = v * F + f
    face_of = np.tile(np.arange(F), 3)
    # corners at the same position, grouped: sort by (x, y, z), cut where the position changes
    order = np.lexsort((corners[:, 2], corners[:, 1], corners[:, 0]))
    sc = corners[order]
    cut = np.r_[True, np.any(sc[1:] != sc[:-1], axis=1)]
    nn = np.sqrt(np.einsum("cf,cf->f", n, n))
    with np.errstate(divide="ignore", invalid="ignore"):
        unit = np.where(nn > 0, n / nn, 0.0).T  # (F, 3)
    starts = np.flatnonzero(cut)
    counts = np.diff(np.r_[starts, len(sc)])
    group_of = np.repeat(np.arange(len(starts)), counts)  # group of each sorted corner
    # every (corner, other corner of its vertex) pair, in sorted positions a, b
    m = counts[group_of]
    a = np.repeat(np.arange(len(sc)), m)
    b = np.repeat(starts[group_of] - (np.cumsum(m) - m), m) + np.arange(len(a))
    fa, fb = face_of[order[a]], face_of[order[b]]
    keep = np.einsum("ij,ij->i", unit[fa], unit[fb]) >= math.cos(math.radians(crease_deg))
    dst, src = order[a[keep]], fb[keep]
    # area-weighted (|n| is twice the area), summed per corner
    acc = np.stack([np.bincount(dst, weights=n[c, src], minlength=3 * F) for c in range(3)], axis=1)
    norm = np.sqrt(np.einsum("kc,kc->k", acc, acc))[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        acc = np.where(norm > 0, acc / norm, unit[face_of])
    return acc.reshape(3, F, 3).transpose(0, 2, 1)
