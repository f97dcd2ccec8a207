"""Point clouds from depth images, and their alignment (ICP).

``depth_to_points(capture_depth("cam"), camera)`` gives the camera-frame cloud (N, 3) in
metres (x right, y down, z forward, as the camera model); with ``T_world_camera`` the same
points in the world, ready for a scene's ``points`` element. ``icp(source, target)`` finds
the rigid transform that carries ``source`` onto ``target``: nearest neighbours by a k-d
tree, then point-to-plane steps (Chen and Medioni; normals of the target from its
neighbours, the default: it slides along planes such as a floor to the right place) or
point-to-point steps (the best rotation by SVD, Arun/Kabsch without scale).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["estimate_normals", "depth_to_points", "transform_points", "best_rigid_transform", "icp", "IcpResult", "voxel_downsample"]

Array = NDArray[np.float64]


def _cloud(P: ArrayLike, name: str) -> Array:
    A = np.asarray(P, dtype=np.float64)
    if A.ndim != 2 or A.shape[1] != 3:
        raise ValueError(f"{name} must be an (N, 3) array of points, got shape {A.shape}")
    if not np.all(np.isfinite(A)):
        raise ValueError(f"{name} has non-finite points (drop them first: P[np.isfinite(P).all(axis=1)])")
    return A


def depth_to_points(
    depth: ArrayLike,
    camera: object,
    T_world_camera: ArrayLike | None = None,
    *,
    stride: int = 1,
    max_depth: float = np.inf,
    rgb: ArrayLike | None = None,
) -> Array | tuple[Array, NDArray[np.uint8]]:
    """The points (N, 3) a depth image (H, W) sees: metres, camera frame, or world frame when
    ``T_world_camera`` (4, 4) is given.

    ``camera``: a ``CameraModel`` of the image's size (its K; a distorted camera's pixels
    are undistorted first). Pixels with depth inf, NaN, <= 0 or > ``max_depth`` are left
    out; ``stride`` keeps every stride-th row and column (a lighter cloud). With ``rgb``
    (H, W, 3) returns ``(points, colours (N, 3) uint8)``. Rows run top to bottom of the image.
    """
    D = np.asarray(depth)
    if D.dtype.kind not in "biuf":
        raise ValueError(f"depth must be real numbers (metres; inf or NaN where nothing is seen), got dtype {D.dtype}")
    D = D.astype(np.float64, copy=False)
    if D.ndim != 2 or D.size == 0:
        raise ValueError(f"depth must be a non-empty (H, W) image, got shape {D.shape}")
    W, H = int(getattr(camera, "width")), int(getattr(camera, "height"))
    if D.shape != (H, W):
        raise ValueError(f"depth is {D.shape[1]}x{D.shape[0]} but the camera is {W}x{H}")
    stride = int(stride)
    if stride < 1:
        raise ValueError(f"stride must be a whole number >= 1, got {stride}")
    vv, uu = np.mgrid[0:H:stride, 0:W:stride]
    d = D[::stride, ::stride]
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(d) & (d > 0) & (d <= max_depth)
    px = np.column_stack([uu[ok], vv[ok]]).astype(np.float64)
    P = camera.backproject(px, d[ok], T_world_camera)  # type: ignore[attr-defined]
    if rgb is None:
        return P
    C = np.asarray(rgb)
    if C.shape[:2] != (H, W):
        raise ValueError(f"rgb must be the depth's size {W}x{H}, got shape {C.shape}")
    return P, np.ascontiguousarray(C[::stride, ::stride][ok][:, :3]).astype(np.uint8)


def transform_points(T: ArrayLike, P: ArrayLike) -> Array:
    """``T`` (4, 4) applied to points (N, 3): ``R p + t`` for each."""
    M = np.asarray(T, dtype=np.float64).reshape(4, 4)
    A = np.asarray(P, dtype=np.float64).reshape(-1, 3)
    return A @ M[:3, :3].T + M[:3, 3]


def voxel_downsample(P: ArrayLike, voxel: float) -> Array:
    """One point (the mean) per cube of side ``voxel`` metres that holds any: (M, 3)."""
    A = _cloud(P, "P")
    if not (voxel > 0):
        raise ValueError(f"voxel must be a length > 0 in metres, got {voxel!r}")
    if not len(A):
        return A
    keys = np.floor(A / voxel).astype(np.int64)
    _, inv = np.unique(keys, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    n = inv.max() + 1
    out = np.zeros((n, 3))
    np.add.at(out, inv, A)
    return out / np.bincount(inv, minlength=n)[:, None]


def best_rigid_transform(src: ArrayLike, dst: ArrayLike, weights: ArrayLike | None = None) -> Array:
    """The (4, 4) rigid transform T minimising sum w |T src_i - dst_i|^2 (pairs given; Kabsch with
    the reflection fix). ``src``, ``dst``: (N, 3), N >= 3 not all on a line."""
    A, B = _cloud(src, "src"), _cloud(dst, "dst")
    if A.shape != B.shape:
        raise ValueError(f"src and dst must pair up: shapes {A.shape} and {B.shape}")
    if len(A) < 3:
        raise ValueError(f"a rigid transform needs at least 3 pairs, got {len(A)}")
    w = np.ones(len(A)) if weights is None else np.asarray(weights, dtype=np.float64).reshape(-1)
    w = w / w.sum()
    ca, cb = w @ A, w @ B
    Hm = (A - ca).T @ ((B - cb) * w[:, None])
    U, _, Vt = np.linalg.svd(Hm)
    S = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0])
    R = Vt.T @ S @ U.T
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = cb - R @ ca
    return T


def estimate_normals(P: ArrayLike, k: int = 12) -> Array:
    """Unit normals (N, 3) of a cloud: the least-variance direction of each point's ``k`` nearest
    neighbours (its sign is arbitrary; point-to-plane steps do not care)."""
    from scipy.spatial import cKDTree

    A = _cloud(P, "P")
    k = int(min(max(3, k), len(A)))
    _, idx = cKDTree(A).query(A, k=k)
    nb = A[idx]  # (N, k, 3)
    C = nb - nb.mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", C, C)
    _, vecs = np.linalg.eigh(cov)
    return vecs[:, :, 0]


def _rot(w: Array) -> Array:
    th = float(np.linalg.norm(w))
    if th < 1e-15:
        return np.eye(3)
    k = w / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * (K @ K)


def _plane_step(p: Array, q: Array, n: Array) -> Array:
    """The (4, 4) step minimising sum ((R p + t - q) . n)^2, linearised in the rotation."""
    A = np.column_stack([np.cross(p, n), n])  # residual r = (p - q).n + w.(p x n) + t.n
    b = -np.einsum("ij,ij->i", p - q, n)
    x, *_ = np.linalg.lstsq(A, b, rcond=None)
    T = np.eye(4)
    T[:3, :3] = _rot(x[:3])
    T[:3, 3] = x[3:]
    return T


@dataclass(frozen=True)
class IcpResult:
    """What ``icp`` found: ``T`` (4, 4) carries the source onto the target; ``rms`` (m) the
    root-mean-square distance of the matched pairs at the end; ``fitness`` the share of
    source points matched (within ``max_distance``); ``iterations`` run; ``converged``."""

    T: Array
    rms: float
    fitness: float
    iterations: int
    converged: bool


def icp(
    source: ArrayLike,
    target: ArrayLike,
    init: ArrayLike | None = None,
    *,
    max_iterations: int = 50,
    tolerance: float = 1e-7,
    max_distance: float = np.inf,
    trim: float = 1.0,
    method: str = "point_to_plane",
) -> IcpResult:
    """ICP: the rigid T with ``T @ source`` on ``target`` (both (N, 3), metres).

    Each iteration matches every moved source point to its nearest target point (SciPy's
    cKDTree), keeps pairs closer than ``max_distance`` and the ``trim`` share (0..1] of the
    closest (trimmed ICP: for clouds that overlap only in part), and takes the step that
    best fits the pairs kept: ``method`` "point_to_plane" (the distances along the target's
    normals, ``estimate_normals``) or "point_to_point" (the distances themselves). The rms
    is of the point-to-point distances either way. It stops when the rms changes by less than
    ``tolerance`` (metres), or comes back to within it of one of the last iterations' (the
    pairs flipping between a few sets, the pose with them: it keeps the one with the least
    rms), both ``converged``, or after ``max_iterations`` (not converged: still moving). ``init`` (4, 4): a first guess (ICP
    finds the nearest local minimum: start it within ~30 degrees and a fraction of the
    clouds' size).
    """
    from scipy.spatial import cKDTree

    S, D = _cloud(source, "source"), _cloud(target, "target")
    if len(S) < 3 or len(D) < 3:
        raise ValueError(f"icp needs at least 3 points in each cloud, got {len(S)} and {len(D)}")
    if method not in ("point_to_plane", "point_to_point"):
        raise ValueError(f"method is 'point_to_plane' or 'point_to_point', got {method!r}")
    if not 0.0 < trim <= 1.0:
        raise ValueError(f"trim is the share of pairs kept, in (0, 1], got {trim}")
    T = np.eye(4) if init is None else np.asarray(init, dtype=np.float64).reshape(4, 4).copy()
    tree = cKDTree(D)
    normals = estimate_normals(D) if method == "point_to_plane" else None
    prev = np.inf
    rms, fitness, converged, it = np.inf, 0.0, False, 0
    seen: list[tuple[float, np.ndarray, float]] = []  # the last iterations' (rms, pose, fitness)
    for it in range(1, int(max_iterations) + 1):
        moved = transform_points(T, S)
        dist, idx = tree.query(moved)
        keep = np.flatnonzero(dist <= max_distance)
        if trim < 1.0 and len(keep):
            keep = keep[np.argsort(dist[keep])[: max(3, int(round(trim * len(keep))))]]
        if len(keep) < 3:
            raise ValueError(
                f"icp: only {len(keep)} source points lie within max_distance={max_distance} of the target; "
                "give a closer init or a larger max_distance"
            )
        fitness = len(keep) / len(S)
        if normals is None:
            step = best_rigid_transform(moved[keep], D[idx[keep]])
        else:
            step = _plane_step(moved[keep], D[idx[keep]], normals[idx[keep]])
        rms = float(np.sqrt(np.mean(dist[keep] ** 2)))
        if any(abs(r - rms) < tolerance for r, _T, _f in seen[:-1]):
            # a cycle: the pairs flip between two (or a few) sets and the pose with them, a few
            # micrometres apart (trimmed pairs, points sampled apart): settled, at the best of them
            rms, T, fitness = min([*seen, (rms, T, fitness)], key=lambda e: e[0])
            converged = True
            break
        seen = [*seen[-3:], (rms, T, fitness)]
        T = step @ T
        if abs(prev - rms) < tolerance:
            converged = True
            break
        prev = rms
    return IcpResult(T, rms, fitness, it, converged)
