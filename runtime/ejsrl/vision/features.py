"""Point features, Hough transforms, regions, template matching and tracking.

Every point is ``(x, y)`` = (column, row) in pixels, as in OpenCV; point sets are (N, 2)
float64 arrays. Images are grey or RGB (uint8, or another type read as
the ``ejsrl.vision`` module docstring says: bool masks, uint16, floats in [0, 1]); a "binary" image counts
every non-zero pixel. Bad input (empty, NaN, wrong shape or type, an unknown option) is a
``ValueError``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_gray, as_points, as_rgb, choice, image_function, to_uint8

__all__ = [
    "harris_response",
    "harris_corners",
    "shi_tomasi_corners",
    "fast_corners",
    "orb_features",
    "hough_lines",
    "hough_segments",
    "hough_circles",
    "connected_components",
    "Region",
    "find_contours",
    "moments",
    "centroid",
    "blobs",
    "color_mask",
    "color_segment",
    "match_template",
    "lk_track",
]

Points = NDArray[np.float64]


def _mask_u8(img: ArrayLike, name: str = "img") -> NDArray[np.uint8]:
    return as_gray(img, name)


@image_function
def harris_response(img: ArrayLike, block_size: int = 2, ksize: int = 3, k: float = 0.04) -> NDArray[np.float64]:
    """Harris corner response ``det(M) - k trace(M)^2`` (H, W) float64 of the grey image."""
    return cv2.cornerHarris(as_gray(img).astype(np.float32), int(block_size), int(ksize), float(k)).astype(np.float64)


@image_function
def harris_corners(
    img: ArrayLike, max_corners: int = 100, quality: float = 0.01, min_distance: float = 5.0, *, k: float = 0.04
) -> Points:
    """Harris corners (N, 2) (x, y), strongest first: maxima of the response above ``quality`` x the best."""
    pts = cv2.goodFeaturesToTrack(
        as_gray(img), int(max_corners), float(quality), float(min_distance), useHarrisDetector=True, k=float(k)
    )
    return np.zeros((0, 2)) if pts is None else pts.reshape(-1, 2).astype(np.float64)


@image_function
def shi_tomasi_corners(img: ArrayLike, max_corners: int = 100, quality: float = 0.01, min_distance: float = 5.0) -> Points:
    """Shi-Tomasi ("good features to track") corners (N, 2) (x, y): the smaller eigenvalue of the structure tensor."""
    pts = cv2.goodFeaturesToTrack(as_gray(img), int(max_corners), float(quality), float(min_distance))
    return np.zeros((0, 2)) if pts is None else pts.reshape(-1, 2).astype(np.float64)


@image_function
def fast_corners(img: ArrayLike, threshold: int = 20, *, nonmax: bool = True) -> Points:
    """FAST corners (N, 2) (x, y): pixels with a contiguous arc of 9 of 16 circle pixels brighter or darker by ``threshold``."""
    det = cv2.FastFeatureDetector_create(threshold=int(threshold), nonmaxSuppression=bool(nonmax))
    kps = det.detect(as_gray(img), None)
    return np.array([kp.pt for kp in kps], dtype=np.float64).reshape(-1, 2)


@image_function
def orb_features(img: ArrayLike, n_features: int = 500) -> tuple[Points, NDArray[np.uint8]]:
    """ORB keypoints (N, 2) (x, y) and their binary descriptors (N, 32) uint8."""
    orb = cv2.ORB_create(nfeatures=int(n_features))
    kps, desc = orb.detectAndCompute(as_gray(img), None)
    pts = np.array([kp.pt for kp in kps], dtype=np.float64).reshape(-1, 2)
    return pts, (np.zeros((0, 32), np.uint8) if desc is None else desc)


@image_function
def hough_lines(edges: ArrayLike, threshold: int = 100, *, rho: float = 1.0, theta: float = np.pi / 180) -> NDArray[np.float64]:
    """Straight lines in a binary edge image, as (N, 2) ``(rho, theta)``: ``x cos(theta) + y sin(theta) = rho``.

    ``threshold``: minimum votes; ``rho`` (pixels) and ``theta`` (radians): accumulator steps.
    """
    lines = cv2.HoughLines(_mask_u8(edges, "edges"), float(rho), float(theta), int(threshold))
    return np.zeros((0, 2)) if lines is None else lines.reshape(-1, 2).astype(np.float64)


@image_function
def hough_segments(
    edges: ArrayLike, threshold: int = 50, *, min_length: float = 20.0, max_gap: float = 5.0
) -> NDArray[np.float64]:
    """Line segments (N, 4) ``(x1, y1, x2, y2)`` by the probabilistic Hough transform of an edge image."""
    segs = cv2.HoughLinesP(_mask_u8(edges, "edges"), 1.0, np.pi / 180, int(threshold), minLineLength=float(min_length), maxLineGap=float(max_gap))
    return np.zeros((0, 4)) if segs is None else segs.reshape(-1, 4).astype(np.float64)


@image_function
def hough_circles(
    img: ArrayLike,
    min_radius: int = 0,
    max_radius: int = 0,
    *,
    min_dist: float = 20.0,
    canny_high: float = 100.0,
    votes: float = 30.0,
    dp: float = 1.0,
) -> NDArray[np.float64]:
    """Circles (N, 3) ``(x, y, radius)`` in a grey image by the Hough gradient method.

    ``min_dist``: between centres; ``canny_high``: edge threshold; ``votes``: accumulator
    threshold (lower finds more, and more false, circles).
    """
    c = cv2.HoughCircles(
        as_gray(img), cv2.HOUGH_GRADIENT, float(dp), float(min_dist), param1=float(canny_high), param2=float(votes),
        minRadius=int(min_radius), maxRadius=int(max_radius),
    )
    return np.zeros((0, 3)) if c is None else c.reshape(-1, 3).astype(np.float64)


@dataclass(frozen=True)
class Region:
    """One connected region: ``label``, ``area`` (pixels), ``bbox`` (x, y, width, height), ``centroid`` (x, y)."""

    label: int
    area: int
    bbox: tuple[int, int, int, int]
    centroid: tuple[float, float]


@image_function
def connected_components(binary: ArrayLike, connectivity: int = 8, *, min_area: int = 0) -> tuple[NDArray[np.int32], list[Region]]:
    """Label the connected non-zero regions of a binary image.

    Returns ``labels`` (H, W) int32 (0 = background, 1.. regions) and the regions with at
    least ``min_area`` pixels, in label order.
    """
    if int(connectivity) not in (4, 8):
        raise ValueError(f"connected_components: connectivity must be 4 or 8, got {connectivity}")
    n, labels, stats, cents = cv2.connectedComponentsWithStats(_mask_u8(binary, "binary"), connectivity=int(connectivity))
    regions = [
        Region(i, int(stats[i, cv2.CC_STAT_AREA]), tuple(int(v) for v in stats[i, :4]), (float(cents[i, 0]), float(cents[i, 1])))  # type: ignore[arg-type]
        for i in range(1, n)
        if stats[i, cv2.CC_STAT_AREA] >= min_area
    ]
    return labels.astype(np.int32), regions


@image_function
def find_contours(binary: ArrayLike, *, external_only: bool = True, min_area: float = 0.0) -> list[Points]:
    """Outlines of the non-zero regions of a binary image, each an (M, 2) array of (x, y) points.

    ``external_only``: outer outlines only (no holes); ``min_area``: drop smaller contours.
    """
    mode = cv2.RETR_EXTERNAL if external_only else cv2.RETR_LIST
    contours, _ = cv2.findContours(_mask_u8(binary, "binary"), mode, cv2.CHAIN_APPROX_NONE)
    return [c.reshape(-1, 2).astype(np.float64) for c in contours if cv2.contourArea(c) >= min_area]


@image_function
def moments(img_or_contour: ArrayLike, *, binary: bool = False) -> dict[str, float]:
    """Image moments (m00, m10, m01, ..., central mu.., normalised nu..) of a grey image or a contour (M, 2).

    ``binary``: count every non-zero pixel as 1.
    """
    a = np.asarray(img_or_contour)
    if a.ndim == 2 and a.shape[1] == 2 and a.dtype.kind == "f":
        if len(a) == 0 or not np.isfinite(a).all():
            raise ValueError(f"moments: a contour must be a non-empty (M, 2) array of finite (x, y) points, got shape {a.shape}")
        return dict(cv2.moments(a.astype(np.float32).reshape(-1, 1, 2)))
    return dict(cv2.moments(_mask_u8(img_or_contour), binaryImage=bool(binary)))


@image_function
def centroid(img_or_contour: ArrayLike, *, binary: bool = True) -> tuple[float, float]:
    """Centroid ``(x, y) = (m10 / m00, m01 / m00)`` of a (binary by default) image or contour; nan if empty."""
    m = moments(img_or_contour, binary=binary)
    if m["m00"] == 0:
        return (float("nan"), float("nan"))
    return (m["m10"] / m["m00"], m["m01"] / m["m00"])


@image_function
def blobs(binary: ArrayLike, min_area: int = 10, connectivity: int = 8) -> Points:
    """Centroids (N, 2) (x, y) of the connected regions of at least ``min_area`` pixels, largest first."""
    _, regions = connected_components(binary, connectivity, min_area=min_area)
    regions.sort(key=lambda r: (-r.area, r.label))
    return np.array([r.centroid for r in regions], dtype=np.float64).reshape(-1, 2)


@image_function
def color_mask(img: ArrayLike, lower: ArrayLike, upper: ArrayLike, *, space: str = "hsv") -> NDArray[np.uint8]:
    """Binary mask (H, W) uint8 0/255 of pixels whose colour lies in [``lower``, ``upper``] (inclusive).

    ``space``: "hsv" (OpenCV ranges, hue 0..179; a hue range with lower > upper wraps
    through red) or "rgb".
    """
    rgb = as_rgb(img)
    lo, hi = as_points(lower, "lower", k=3), as_points(upper, "upper", k=3)
    if lo.shape != (1, 3) or hi.shape != (1, 3):
        raise ValueError(f"color_mask: lower and upper must be three numbers each, got {np.shape(lower)} and {np.shape(upper)}")
    lo, hi = lo[0], hi[0]
    if choice(space, ("hsv", "rgb"), "colour space") == "rgb":
        return cv2.inRange(rgb, lo, hi)
    hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)
    if lo[0] <= hi[0]:
        return cv2.inRange(hsv, lo, hi)
    a = cv2.inRange(hsv, lo, np.array([179, hi[1], hi[2]], dtype=np.float64))
    b = cv2.inRange(hsv, np.array([0, lo[1], lo[2]], dtype=np.float64), hi)
    return cv2.bitwise_or(a, b)


_NAMED_HUES = {"red": (170, 10), "orange": (10, 25), "yellow": (25, 35), "green": (35, 85), "cyan": (85, 100), "blue": (100, 130), "magenta": (130, 170)}


@image_function
def color_segment(img: ArrayLike, color: str, *, min_saturation: int = 80, min_value: int = 50, min_area: int = 10) -> tuple[NDArray[np.uint8], Points]:
    """Segment a named colour (red, orange, yellow, green, cyan, blue, magenta) in an RGB image.

    Returns the cleaned mask (H, W) uint8 0/255 and the centroids (N, 2) (x, y) of its
    regions of at least ``min_area`` pixels, largest first.
    """
    choice(color, sorted(_NAMED_HUES), "colour")
    h0, h1 = _NAMED_HUES[color]
    mask = color_mask(img, (h0, min_saturation, min_value), (h1, 255, 255))
    mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    return mask, blobs(mask, min_area)


@image_function
def match_template(img: ArrayLike, template: ArrayLike, *, method: str = "ccoeff_normed") -> tuple[tuple[float, float], float, NDArray[np.float32]]:
    """Find ``template`` in ``img`` (both grey or RGB).

    ``method``: "ccoeff_normed", "ccorr_normed" or "sqdiff_normed". Returns the best
    top-left corner ``(x, y)``, its score, and the score map (H - h + 1, W - w + 1).
    """
    methods = {"ccoeff_normed": cv2.TM_CCOEFF_NORMED, "ccorr_normed": cv2.TM_CCORR_NORMED, "sqdiff_normed": cv2.TM_SQDIFF_NORMED}
    m = methods[choice(method, methods, "match_template method")]
    a = np.ascontiguousarray(to_uint8(img))
    t = np.ascontiguousarray(to_uint8(template, "template"))
    if a.ndim != t.ndim:
        a, t = as_gray(a), as_gray(t)
    if t.shape[0] > a.shape[0] or t.shape[1] > a.shape[1]:
        raise ValueError(f"match_template: the template ({t.shape[1]} x {t.shape[0]}) is larger than the image ({a.shape[1]} x {a.shape[0]})")
    res = cv2.matchTemplate(a, t, m)
    mn, mx, mnl, mxl = cv2.minMaxLoc(res)
    if method == "sqdiff_normed":
        return (float(mnl[0]), float(mnl[1])), float(mn), res
    return (float(mxl[0]), float(mxl[1])), float(mx), res


@image_function
def lk_track(
    prev: ArrayLike, curr: ArrayLike, points: ArrayLike, *, win_size: int = 21, levels: int = 3
) -> tuple[Points, NDArray[np.bool_]]:
    """Track points (N, 2) (x, y) from image ``prev`` to ``curr`` with pyramidal Lucas-Kanade.

    Returns the new positions (N, 2) and which points were found (N,) bool.
    """
    g0, g1 = as_gray(prev, "prev"), as_gray(curr, "curr")
    if g0.shape != g1.shape:
        raise ValueError(f"lk_track: prev and curr must have the same size, got {g0.shape} and {g1.shape}")
    p0 = as_points(points).astype(np.float32).reshape(-1, 1, 2)
    if len(p0) == 0:
        return np.zeros((0, 2)), np.zeros(0, bool)
    p1, st, _ = cv2.calcOpticalFlowPyrLK(
        g0, g1, p0, None, winSize=(int(win_size), int(win_size)), maxLevel=int(levels),
        criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.01),
    )
    return p1.reshape(-1, 2).astype(np.float64), st.reshape(-1).astype(bool)
