"""Camera calibration from views of a chessboard (Zhang's method, as OpenCV and MVTB do it).

Conventions: a chessboard ``pattern`` is ``(columns, rows)`` of *inner* corners (OpenCV's
``patternSize``: a board of 9 x 6 squares has pattern (8, 5)). Its corners lie in the
board's own frame on the plane z = 0, at ``(i * square, j * square, 0)`` for column ``i``
and row ``j``, listed row by row (``chessboard_points``), the order in which
``find_chessboard`` returns them. Pixels are ``(x, y)`` = (column, row) with pixel centres
at integers. Distortion coefficients are ``(k1, k2, p1, p2, k3)`` (OpenCV's order, see
:mod:`ejsrl.vision.camera`). The reprojection error is in pixels: the root mean square,
over every corner of every view, of the distance between where a corner was found and
where the calibrated camera projects it (OpenCV's ``calibrateCamera`` return value).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_gray
from ejsrl.vision.camera import CameraModel, Intrinsics, pose_from_rvec

__all__ = ["Calibration", "chessboard_points", "find_chessboard", "draw_chessboard", "calibrate_camera", "calibrate_chessboard"]

Array = NDArray[np.float64]

#: the smallest side (px) of an image OpenCV's chessboard detector can threshold: its adaptive
#: threshold's block is round(0.1 * side) | 1 pixels and must be 3 or more. A board in a smaller
#: image could not be found anyway (its squares need a few pixels each), so such an image has none.
MIN_CHESSBOARD_SIDE = 15


@dataclass(frozen=True)
class Calibration(Intrinsics):
    """The result of a calibration.

    ``K`` (3, 3) intrinsics; ``distortion`` (5,) ``(k1, k2, p1, p2, k3)``; ``rms``: the
    reprojection error (pixels, RMS over all points); ``per_view`` (M,): the RMS error of
    each view; ``poses``: ``T_camera_board`` (4, 4) of each view; ``image_size`` (w, h).
    """

    K: Array
    distortion: Array
    rms: float
    per_view: Array
    poses: list[Array] = field(repr=False)
    image_size: tuple[int, int]

    @property
    def camera(self) -> CameraModel:
        """The calibrated camera as a :class:`CameraModel`."""
        w, h = self.image_size
        return CameraModel(w, h, K=self.K, distortion=self.distortion)


def _pattern(pattern: Sequence[int]) -> tuple[int, int]:
    try:
        cols, rows = (int(v) for v in pattern)
    except (TypeError, ValueError):
        raise ValueError(f"pattern must be (columns, rows) of inner corners, got {pattern!r}") from None
    if cols < 2 or rows < 2:
        raise ValueError(f"pattern needs at least 2 x 2 inner corners, got {cols} x {rows}")
    return cols, rows


def chessboard_points(pattern: Sequence[int], square: float) -> Array:
    """The inner corners (N, 3) of a chessboard in its own frame (z = 0), row by row; ``square`` in metres."""
    cols, rows = _pattern(pattern)
    if not square > 0:
        raise ValueError(f"square must be a positive length, got {square}")
    j, i = np.mgrid[0:rows, 0:cols]
    return np.column_stack([i.ravel() * square, j.ravel() * square, np.zeros(cols * rows)]).astype(np.float64)


def find_chessboard(img: ArrayLike, pattern: Sequence[int], *, refine: bool = True) -> Array | None:
    """The inner corners (N, 2) (x, y) of a chessboard in an image, row by row, or None if not all are found.

    ``refine``: sub-pixel refinement (``cornerSubPix``, 11 x 11 window clipped to the
    square size). Needs a white margin around the board, as OpenCV's detector does. Tries
    OpenCV's default flags, then without histogram normalisation, then plain thresholds.
    An image too small to show a board (under ``MIN_CHESSBOARD_SIDE`` = 15 px on a side)
    gives None like any image without one; an invalid image (empty, NaN, wrong dtype) is a
    ValueError, and so is a ``pattern`` under 3 x 3 inner corners (OpenCV's detector needs 3).
    """
    cols, rows = _pattern(pattern)
    if cols < 3 or rows < 3:
        raise ValueError(f"find_chessboard needs a pattern of at least 3 x 3 inner corners (OpenCV's detector), got {cols} x {rows}")
    gray = as_gray(img)
    if min(gray.shape) < MIN_CHESSBOARD_SIDE:
        return None  # too small to hold a board; OpenCV's adaptive threshold would refuse it
    ok, corners = False, None
    # OpenCV's default flags first; histogram normalisation fails on some images (dark borders)
    for flags in (cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE, cv2.CALIB_CB_ADAPTIVE_THRESH, 0):
        ok, corners = cv2.findChessboardCorners(gray, (cols, rows), flags=flags)
        if ok and corners is not None:
            break
    if not ok or corners is None:
        return None
    if refine:
        pts = corners.reshape(-1, 2)
        # the window must stay inside one square: half the smallest corner spacing
        grid = pts.reshape(rows, cols, 2)
        spacing = min(np.linalg.norm(np.diff(grid, axis=1), axis=2).min(), np.linalg.norm(np.diff(grid, axis=0), axis=2).min())
        win = int(max(2, min(5, spacing / 2 - 1)))
        criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 100, 1e-4)
        corners = cv2.cornerSubPix(gray, corners, (win, win), (-1, -1), criteria)
    return corners.reshape(-1, 2).astype(np.float64)


def draw_chessboard(img: ArrayLike, pattern: Sequence[int], corners: ArrayLike | None) -> NDArray[np.uint8]:
    """A copy of ``img`` as RGB with the corners (N, 2) found by :func:`find_chessboard` drawn
    (OpenCV's coloured rows joined by lines); unchanged if ``corners`` is None."""
    from ejsrl.vision._util import as_rgb

    cols, rows = _pattern(pattern)
    out = as_rgb(img).copy()
    if corners is None:
        return out
    pts = np.asarray(corners, dtype=np.float32).reshape(-1, 1, 2)
    if len(pts) != cols * rows:
        raise ValueError(f"pattern {cols} x {rows} has {cols * rows} corners, got {len(pts)}")
    return cv2.drawChessboardCorners(out, (cols, rows), pts, True)


def calibrate_camera(
    object_points: Sequence[ArrayLike],
    image_points: Sequence[ArrayLike],
    image_size: Sequence[int],
    *,
    K_guess: ArrayLike | None = None,
    fix_k3: bool = False,
    zero_tangential: bool = False,
    fix_aspect: bool = False,
) -> Calibration:
    """Intrinsics, distortion and the pose of every view from 3 or more views of a planar target.

    ``object_points``: per view, the target's points (N, 3) in its own frame (z = 0, e.g.
    :func:`chessboard_points`); ``image_points``: per view, where they were seen (N, 2);
    ``image_size``: (width, height). Options: ``K_guess`` starts from these intrinsics,
    ``fix_k3`` keeps k3 = 0 (advisable with few or fronto-parallel views),
    ``zero_tangential`` keeps p1 = p2 = 0, ``fix_aspect`` keeps fx / fy as in ``K_guess``.
    Raises ValueError with fewer than 3 views or mismatched point lists.
    """
    if len(object_points) != len(image_points):
        raise ValueError(f"{len(object_points)} views of object points but {len(image_points)} of image points")
    if len(object_points) < 3:
        raise ValueError(f"calibration needs at least 3 views of the target, got {len(object_points)}")
    try:
        w, h = (int(v) for v in image_size)
    except (TypeError, ValueError):
        raise ValueError(f"image_size must be (width, height), got {image_size!r}") from None
    if w <= 0 or h <= 0:
        raise ValueError(f"image_size must be positive, got {w} x {h}")
    obj, img = [], []
    for k, (P, p) in enumerate(zip(object_points, image_points)):
        P = np.asarray(P, dtype=np.float64)
        p = np.asarray(p, dtype=np.float64)
        if P.ndim != 2 or P.shape[1] != 3 or p.ndim != 2 or p.shape[1] != 2 or len(P) != len(p):
            raise ValueError(f"view {k}: object points must be (N, 3) and image points (N, 2), got {P.shape} and {p.shape}")
        if len(P) < 4:
            raise ValueError(f"view {k}: needs at least 4 points, got {len(P)}")
        if not (np.all(np.isfinite(P)) and np.all(np.isfinite(p))):
            raise ValueError(f"view {k}: points must be finite")
        obj.append(P.astype(np.float32))
        img.append(p.astype(np.float32).reshape(-1, 1, 2))
    flags = 0
    K0 = None
    if K_guess is not None:
        K0 = np.asarray(K_guess, dtype=np.float64).reshape(3, 3).copy()
        flags |= cv2.CALIB_USE_INTRINSIC_GUESS
    if fix_k3:
        flags |= cv2.CALIB_FIX_K3
    if zero_tangential:
        flags |= cv2.CALIB_ZERO_TANGENT_DIST
    if fix_aspect:
        flags |= cv2.CALIB_FIX_ASPECT_RATIO
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)
    rms, K, dist, rvecs, tvecs = cv2.calibrateCamera(obj, img, (w, h), K0, None, flags=flags, criteria=criteria)
    dist = np.asarray(dist, dtype=np.float64).reshape(-1)[:5]
    dist = np.concatenate([dist, np.zeros(5 - len(dist))])
    poses = [pose_from_rvec(r, t) for r, t in zip(rvecs, tvecs)]
    per_view = []
    for P, p, r, t in zip(obj, img, rvecs, tvecs):
        proj, _ = cv2.projectPoints(P.astype(np.float64), r, t, K, dist)
        per_view.append(float(np.sqrt(np.mean(np.sum((proj.reshape(-1, 2) - p.reshape(-1, 2)) ** 2, axis=1)))))
    return Calibration(np.asarray(K, dtype=np.float64), dist, float(rms), np.array(per_view), poses, (w, h))


def calibrate_chessboard(images: Sequence[ArrayLike], pattern: Sequence[int], square: float, **options) -> Calibration:
    """Calibrate from images of a chessboard: find its corners in each, then :func:`calibrate_camera`.

    Images where the board is not found are skipped; ``options`` go to
    :func:`calibrate_camera`. Raises ValueError if fewer than 3 show the whole board.
    """
    if len(images) == 0:
        raise ValueError("no images given")
    board = chessboard_points(pattern, square)
    found = [c for c in (find_chessboard(im, pattern) for im in images) if c is not None]
    if len(found) < 3:
        raise ValueError(f"the chessboard {tuple(pattern)} was found in {len(found)} of {len(images)} images; calibration needs 3")
    h, w = np.asarray(images[0]).shape[:2]
    return calibrate_camera([board] * len(found), found, (w, h), **options)
