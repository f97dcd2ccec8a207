"""Point features with descriptors, matching, and robust two-view geometry (RANSAC).

Conventions: points are ``(x, y)`` pixels; a match is a pair of indices ``(i, j)``: feature
``i`` of the first image and ``j`` of the second. ``H`` (3, 3) maps the first image's
pixels to the second's (``p2 ~ H p1``); the fundamental matrix satisfies ``p2^T F p1 = 0``
for homogeneous pixels, the essential matrix ``x2^T E x1 = 0`` for normalised coordinates.
:func:`recover_pose` returns ``T_2_1``, the pose of camera 1 in camera 2's frame
(``X2 = R X1 + t``), with ``|t| = 1``: two views fix the translation only up to scale.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_gray, choice, image_function

__all__ = [
    "Features",
    "feature_methods",
    "detect_features",
    "match_features",
    "find_homography",
    "find_fundamental",
    "find_essential",
    "recover_pose",
    "epipolar_distances",
]

Array = NDArray[np.float64]

#: every method ``detect_features`` knows, and the OpenCV class that does it. OpenCV 5 keeps
#: ORB and SIFT in its main package and moved AKAZE, KAZE and BRISK to opencv-contrib's
#: ``xfeatures2d``; a method works when the installed OpenCV has its class (see ``feature_methods``).
_DETECTORS = {"orb": "ORB", "sift": "SIFT", "akaze": "AKAZE", "kaze": "KAZE", "brisk": "BRISK"}
#: descriptor length and type of each method when an image gives no keypoint
_EMPTY = {"orb": (32, np.uint8), "sift": (128, np.float32), "akaze": (61, np.uint8), "kaze": (64, np.float32), "brisk": (64, np.uint8)}


def _factory(method: str):
    """The installed OpenCV's constructor for ``method`` (``cv2.ORB.create`` and the like), or None."""
    cls = _DETECTORS[method]
    for module in (cv2, getattr(cv2, "xfeatures2d", None), getattr(cv2, "features2d", None)):
        if module is None:
            continue
        make = getattr(getattr(module, cls, None), "create", None) or getattr(module, f"{cls}_create", None)
        if make is not None:
            return make
    return None


@functools.cache  # the installed OpenCV does not change
def feature_methods() -> tuple[str, ...]:
    """The ``detect_features`` methods this OpenCV has: ``("orb", "sift")`` with opencv-python 5,
    plus ``"akaze"``, ``"kaze"`` and ``"brisk"`` where opencv-contrib-python provides them."""
    return tuple(m for m in _DETECTORS if _factory(m) is not None)


@dataclass(frozen=True)
class Features:
    """Keypoints and descriptors of one image: ``points`` (N, 2) (x, y), ``descriptors`` (N, D)
    (uint8 binary for ORB/AKAZE/BRISK, float32 for SIFT/KAZE), ``sizes`` (N,) diameters in px,
    ``angles`` (N,) orientations in degrees, ``responses`` (N,), and the ``method``."""

    points: Array
    descriptors: NDArray
    sizes: Array
    angles: Array
    responses: Array
    method: str

    def __len__(self) -> int:
        return len(self.points)

    @property
    def binary(self) -> bool:
        """Whether the descriptors are binary strings (compared by Hamming distance)."""
        return self.descriptors.dtype == np.uint8


@image_function
def detect_features(img: ArrayLike, method: str = "orb", *, max_features: int = 1000) -> Features:
    """Detect keypoints and describe them: ``"orb"`` (default) or ``"sift"``; ``"akaze"``,
    ``"kaze"`` and ``"brisk"`` only where the installed OpenCV has them (OpenCV 5 moved them
    to opencv-contrib-python; ``feature_methods()`` lists what works here, and any other
    method is a ValueError naming those).

    ``max_features`` keeps the strongest (ORB and SIFT take it as their own limit). An image
    one pixel wide or high has no features.
    """
    here = feature_methods()
    if method in _DETECTORS and method not in here:
        raise ValueError(
            f"this OpenCV ({cv2.__version__}) has no {method.upper()} detector (OpenCV 5 moved it to "
            f"opencv-contrib-python); use one of {', '.join(repr(m) for m in here)}"
        )
    method = choice(method, here, "feature method")
    if max_features < 1:
        raise ValueError(f"max_features must be positive, got {max_features}")
    gray = as_gray(img)
    if min(gray.shape) < 2:  # OpenCV's ORB pyramid fails on a one-pixel-wide image; it has no features
        width, dtype = _EMPTY[method]
        return Features(np.zeros((0, 2)), np.zeros((0, width), dtype), np.zeros(0), np.zeros(0), np.zeros(0), method)
    make = _factory(method)
    det = make(nfeatures=int(max_features)) if method in ("orb", "sift") else make()
    kps, desc = det.detectAndCompute(gray, None)
    if desc is None or len(kps) == 0:
        width, dtype = _EMPTY[method]
        desc = np.zeros((0, width), dtype)
        kps = []
    order = np.argsort([-k.response for k in kps], kind="stable")[: int(max_features)]
    kps = [kps[i] for i in order]
    desc = desc[order]
    return Features(
        np.array([k.pt for k in kps], dtype=np.float64).reshape(-1, 2),
        desc,
        np.array([k.size for k in kps], dtype=np.float64),
        np.array([k.angle for k in kps], dtype=np.float64),
        np.array([k.response for k in kps], dtype=np.float64),
        method,
    )


def match_features(f1: Features, f2: Features, *, ratio: float = 0.8, cross_check: bool = False) -> NDArray[np.int64]:
    """Matches (M, 2) of index pairs ``(i, j)``, best first.

    Brute force with Hamming distance for binary descriptors, L2 for SIFT. ``ratio``:
    Lowe's test, keep a match only if its distance is below ``ratio`` times the second
    best (1 turns it off); ``cross_check``: keep only mutual best matches.
    """
    if f1.binary != f2.binary:
        raise ValueError(f"cannot match {f1.method} descriptors with {f2.method} ones")
    if not 0 < ratio <= 1:
        raise ValueError(f"ratio must be in (0, 1], got {ratio}")
    if len(f1) == 0 or len(f2) == 0:
        return np.zeros((0, 2), np.int64)
    norm = cv2.NORM_HAMMING if f1.binary else cv2.NORM_L2
    bf = cv2.BFMatcher(norm)
    pairs: list[tuple[float, int, int]] = []
    for cands in bf.knnMatch(f1.descriptors, f2.descriptors, k=2):
        if not cands:
            continue
        best = cands[0]
        if len(cands) > 1 and ratio < 1 and not best.distance < ratio * cands[1].distance:
            continue
        pairs.append((best.distance, best.queryIdx, best.trainIdx))
    if cross_check and pairs:
        back = {m.queryIdx: m.trainIdx for m in bf.match(f2.descriptors, f1.descriptors)}
        pairs = [p for p in pairs if back.get(p[2]) == p[1]]
    pairs.sort()
    return np.array([(i, j) for _, i, j in pairs], dtype=np.int64).reshape(-1, 2)


def _pair(p1: ArrayLike, p2: ArrayLike, n_min: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    a = np.asarray(p1, dtype=np.float64)
    b = np.asarray(p2, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 2 or a.shape != b.shape:
        raise ValueError(f"points must be two (N, 2) arrays of the same N, got {a.shape} and {b.shape}")
    if len(a) < n_min:
        raise ValueError(f"needs at least {n_min} point pairs, got {len(a)}")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ValueError("points must be finite")
    return a, b


def _robust(name: str) -> int:
    methods = {"usac": cv2.USAC_ACCURATE, "ransac": cv2.RANSAC, "lmeds": cv2.LMEDS, "magsac": cv2.USAC_MAGSAC}
    if name not in methods:
        raise ValueError(f"method must be one of {sorted(methods)}, got {name!r}")
    return methods[name]


def find_homography(
    p1: ArrayLike, p2: ArrayLike, *, threshold: float = 3.0, method: str = "usac", confidence: float = 0.999
) -> tuple[Array, NDArray[np.bool_]]:
    """``(H, inliers)``: the homography (3, 3, ``H[2, 2] = 1``) with ``p2 ~ H p1`` and which pairs fit it.

    ``threshold``: largest reprojection error (px) of an inlier; ``method``: ``"usac"``
    (OpenCV's USAC_ACCURATE: RANSAC with local optimisation, default), ``"ransac"``,
    ``"lmeds"`` or ``"magsac"``. Needs 4 pairs; raises ValueError if no homography is found.
    """
    a, b = _pair(p1, p2, 4)
    H, mask = cv2.findHomography(a, b, _robust(method), float(threshold), confidence=float(confidence), maxIters=5000)
    if H is None:
        raise ValueError("no homography fits these points (too few inliers, or degenerate)")
    return H / H[2, 2], mask.ravel().astype(bool)


def find_fundamental(
    p1: ArrayLike, p2: ArrayLike, *, threshold: float = 1.0, method: str = "usac", confidence: float = 0.999
) -> tuple[Array, NDArray[np.bool_]]:
    """``(F, inliers)``: the fundamental matrix (3, 3, rank 2, ``|F| = 1``) with ``p2^T F p1 = 0``.

    ``threshold``: largest distance (px) of an inlier from its epipolar line; ``method`` as
    :func:`find_homography`. Needs 8 pairs.
    """
    a, b = _pair(p1, p2, 8)
    F, mask = cv2.findFundamentalMat(a, b, _robust(method), float(threshold), float(confidence), 5000)
    if F is None or F.shape != (3, 3):
        raise ValueError("no fundamental matrix fits these points (too few inliers, or a planar scene)")
    return F / np.linalg.norm(F), mask.ravel().astype(bool)


def find_essential(
    p1: ArrayLike, p2: ArrayLike, K: ArrayLike, *, threshold: float = 1.0, method: str = "usac", confidence: float = 0.999
) -> tuple[Array, NDArray[np.bool_]]:
    """``(E, inliers)``: the essential matrix (3, 3, ``|E| = 1``) of two views by one camera with intrinsics K.

    Pixels must be undistorted (``CameraModel.undistort_points``). Needs 5 pairs;
    ``threshold`` in pixels and ``method`` as :func:`find_homography`.
    """
    a, b = _pair(p1, p2, 5)
    Km = np.asarray(K, dtype=np.float64).reshape(3, 3)
    E, mask = cv2.findEssentialMat(a, b, Km, _robust(method), float(confidence), float(threshold))
    if E is None or E.shape != (3, 3):
        raise ValueError("no essential matrix fits these points")
    return E / np.linalg.norm(E), mask.ravel().astype(bool)


def recover_pose(E: ArrayLike, p1: ArrayLike, p2: ArrayLike, K: ArrayLike) -> tuple[Array, NDArray[np.bool_]]:
    """``(T_2_1, inliers)``: the relative pose from an essential matrix, the one of the four that puts
    the points in front of both cameras; ``X2 = R X1 + t`` with ``|t| = 1``."""
    a, b = _pair(p1, p2, 5)
    Em = np.asarray(E, dtype=np.float64).reshape(3, 3)
    _, R, t, mask = cv2.recoverPose(Em, a, b, np.asarray(K, dtype=np.float64).reshape(3, 3))
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t.ravel()
    return T, mask.ravel() > 0


def epipolar_distances(F: ArrayLike, p1: ArrayLike, p2: ArrayLike) -> Array:
    """Distance (N,) in pixels of each ``p2`` from the epipolar line ``F p1`` of its partner."""
    a, b = _pair(p1, p2, 1)
    Fm = np.asarray(F, dtype=np.float64).reshape(3, 3)
    lines = np.column_stack([a, np.ones(len(a))]) @ Fm.T
    return np.abs(np.sum(lines * np.column_stack([b, np.ones(len(b))]), axis=1)) / np.hypot(lines[:, 0], lines[:, 1])
