"""SUSAN at its defaults against ground truth and OpenCV: the vertices of anti-aliased polygons at
several noise levels, sub-pixel X-junctions, and scikit-image's real images.

The polygons are drawn 8x supersampled and averaged down (anti-aliased, as a camera sees
them), with Gaussian noise added; their vertices are known exactly. OpenCV's Shi-Tomasi
corners refined by ``cornerSubPix`` are the reference that shows the images are fair.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from skimage import data

from ejsrl.vision import susan_corners


pytestmark = pytest.mark.usefixtures("susan_path")  # each test on both SUSAN paths (conftest.py)

TOL = 1.5  # px: a vertex is found when a corner lies this close
MAX_ANGLE = 150.0  # degrees: vertices sharper than this must be found


def _polygon(rng: np.random.Generator, cx: float, cy: float, rmax: float) -> tuple[np.ndarray, np.ndarray]:
    """A random star-shaped polygon (M, 2) and the visible angle of each vertex (degrees)."""
    while True:
        n = int(rng.integers(3, 8))
        ang = np.sort(rng.uniform(0, 2 * np.pi, n))
        if np.min(np.diff(np.r_[ang, ang[0] + 2 * np.pi])) < 0.35:
            continue
        r = rng.uniform(0.45, 1.0, n) * rmax
        P = np.column_stack([cx + r * np.cos(ang), cy + r * np.sin(ang)])
        prev, nxt = np.roll(P, 1, 0), np.roll(P, -1, 0)
        if np.min(np.linalg.norm(P - nxt, axis=1)) < 14:
            continue
        a, b = prev - P, nxt - P
        cos = (a * b).sum(1) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1)
        angle = np.degrees(np.arccos(np.clip(cos, -1, 1)))  # the angle between the two edges
        if angle.min() < 30:
            continue
        return P, angle


def polygons_image(seed: int, sigma: float, W: int = 640, H: int = 480, ss: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Twelve anti-aliased grey polygons on a dark background, noise ``sigma``; (image, vertices, angles)."""
    rng = np.random.default_rng(seed)
    big = np.full((H * ss, W * ss), int(rng.uniform(30, 90)), np.uint8)
    verts, angles = [], []
    for ty in range(3):
        for tx in range(4):
            P, a = _polygon(rng, 80 + 160 * tx + rng.uniform(-8, 8), 80 + 160 * ty + rng.uniform(-8, 8), 62)
            pts = np.rint((P + 0.5) * ss * 16 - 8).astype(np.int32)  # pixel centres at integer (x, y)
            cv2.fillPoly(big, [pts], int(rng.uniform(140, 230)), lineType=cv2.LINE_8, shift=4)
            verts.append(P)
            angles.append(a)
    img = cv2.resize(big, (W, H), interpolation=cv2.INTER_AREA).astype(np.float64)
    img += rng.normal(0, sigma, img.shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8), np.concatenate(verts), np.concatenate(angles)


def recall_precision(found: np.ndarray, verts: np.ndarray, angles: np.ndarray) -> tuple[float, float, float]:
    """Share of the sharp vertices found, share of the corners that are a vertex, median error (px)."""
    d = np.linalg.norm(found[:, None] - verts[None], axis=2)
    sharp = angles < MAX_ANGLE
    hit = (d[:, sharp] <= TOL).any(axis=0)
    true_corner = (d <= TOL).any(axis=1)  # a corner on a blunter vertex is not a false one
    err = d[:, sharp].min(axis=0)[hit]
    return float(hit.mean()), float(true_corner.mean()), float(np.median(err))


def opencv_corners(img: np.ndarray, n: int = 300) -> np.ndarray:
    pts = cv2.goodFeaturesToTrack(img, n, 0.01, 5)
    return cv2.cornerSubPix(img, pts, (3, 3), (-1, -1), (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 30, 0.01)).reshape(-1, 2)


@pytest.mark.parametrize("sigma", [0.0, 2.0, 4.0])
def test_susan_finds_the_vertices_of_anti_aliased_polygons_in_noise(sigma):
    rec, prec, err, rec_cv = [], [], [], []
    for seed in range(4):
        img, verts, angles = polygons_image(seed, sigma)
        r, p, e = recall_precision(susan_corners(img), verts, angles)
        rec.append(r), prec.append(p), err.append(e)
        rec_cv.append(recall_precision(opencv_corners(img), verts, angles)[0])
    assert np.mean(rec_cv) >= 0.95  # the reference finds them: the images are fair
    assert np.mean(rec) >= 0.95, rec
    assert np.mean(prec) >= 0.90, prec
    assert np.median(err) < 0.3  # sub-pixel, like the reference


def _x_junction(cx: float, cy: float, angle: float, size: int = 64, ss: int = 16) -> np.ndarray:
    """A checkerboard corner (grey 40 and 200) at (cx, cy), its edges turned by ``angle``, anti-aliased."""
    y, x = np.mgrid[0 : size * ss, 0 : size * ss]
    xs, ys = (x + 0.5) / ss - 0.5 - cx, (y + 0.5) / ss - 0.5 - cy
    u = np.cos(angle) * xs + np.sin(angle) * ys
    v = -np.sin(angle) * xs + np.cos(angle) * ys
    big = np.where((u > 0) ^ (v > 0), 200, 40).astype(np.float32)
    return np.rint(cv2.resize(big, (size, size), interpolation=cv2.INTER_AREA)).astype(np.uint8)


@pytest.mark.parametrize("sigma", [0.0, 4.0])
def test_x_junctions_are_found_to_a_third_of_a_pixel(sigma):
    rng = np.random.default_rng(3)
    errors, pixel_errors = [], []
    for _ in range(30):
        cx, cy = 31.5 + rng.uniform(-0.5, 0.5), 31.5 + rng.uniform(-0.5, 0.5)
        img = _x_junction(cx, cy, rng.uniform(0, np.pi / 2))
        if sigma:
            img = np.clip(np.rint(img + rng.normal(0, sigma, img.shape)), 0, 255).astype(np.uint8)
        pts = susan_corners(img)
        assert len(pts) >= 1
        errors.append(np.linalg.norm(pts - (cx, cy), axis=1).min())
        coarse = susan_corners(img, subpixel=False)
        pixel_errors.append(np.linalg.norm(coarse - (cx, cy), axis=1).min())
    assert max(errors) <= 0.3, max(errors)
    assert np.median(pixel_errors) > 0.3  # the pixel grid alone could not do it


def test_the_inner_corners_of_scikit_images_checkerboard():
    img = data.checkerboard()  # 200 x 200, squares of 25 px, sharp edges
    truth = np.array([[x, y] for y in range(1, 8) for x in range(1, 8)], float) * 25 - 0.5
    pts = susan_corners(img)
    d = np.linalg.norm(pts[:, None] - truth[None], axis=2)
    assert (d.min(axis=0) <= 0.3).all()  # all 49, sub-pixel
    assert (d.min(axis=1) <= 1.5).all()  # and nothing else
    # as a camera would see it: slightly defocused, with sensor noise
    seen = cv2.GaussianBlur(img, (0, 0), 0.7) + np.random.default_rng(0).normal(0, 4, img.shape)
    pts = susan_corners(np.clip(np.rint(seen), 0, 255).astype(np.uint8))
    d = np.linalg.norm(pts[:, None] - truth[None], axis=2)
    assert (d.min(axis=0) <= 0.3).sum() >= 46  # measured 48 of 49
    assert (d.min(axis=1) <= 1.5).all()


def test_on_a_real_photograph_susan_agrees_with_opencv_and_turns_with_the_image():
    img = cv2.resize(data.camera(), (640, 480), interpolation=cv2.INTER_AREA)
    strongest = susan_corners(img, max_corners=50)
    assert len(strongest) == 50
    ref = opencv_corners(img, 1000)
    near = np.linalg.norm(strongest[:, None] - ref[None], axis=2).min(axis=1) <= 2.0
    assert near.mean() >= 0.7  # most of SUSAN's strongest corners are Shi-Tomasi corners too
    # a quarter turn of the image turns the corners with it (the detector has no preferred axis)
    turned = susan_corners(np.ascontiguousarray(np.rot90(img)))
    W = img.shape[1]
    back = np.column_stack([W - 1 - turned[:, 1], turned[:, 0]])  # (x, y) in the turned image -> original
    full = susan_corners(img)
    d = np.linalg.norm(full[:, None] - back[None], axis=2).min(axis=1)
    assert np.mean(d <= 0.5) >= 0.9


def test_the_obtuse_corners_of_small_faint_polygons_are_found():
    """The new-user trial's scenes (bench/susan_recall.py): 3-6 sided polygons of radius 20-32 px,
    a contrast of 50-130 grey levels, noise 4. SUSAN at its defaults finds the vertices sharper
    than 150 degrees (at least 95 %, the obtuse ones of 120-150 degrees at least 90 %) at over
    90 % precision; it missed a quarter of the obtuse ones while its side test asked an
    in-between pixel's three pixels towards the centroid for 2.9 of 3 (noise widens the
    range their shares are taken from). goodFeaturesToTrack finds them all: the scenes are fair."""
    from testkit import bench_module

    B = bench_module("susan_recall")
    rng = np.random.default_rng(7)
    hits = {"all": [], "obtuse": [], "gftt": []}
    precision = []
    for _ in range(6):
        polys, greys = B.scene(rng)
        img = np.clip(B.render(polys, greys, 100) + rng.normal(0, 4.0, (240, 320)), 0, 255).round().astype(np.uint8)
        pts = np.asarray(susan_corners(img)).reshape(-1, 2)
        ref = opencv_corners(img, 200)
        verts = np.concatenate(polys)
        precision.append((np.linalg.norm(pts[:, None] - verts[None], axis=2).min(axis=1) <= TOL).mean())
        for P in polys:
            for v, a in zip(P, B.interior_angles(P)):
                if a < MAX_ANGLE:
                    hits["all"].append(np.linalg.norm(pts - v, axis=1).min() <= TOL)
                    hits["gftt"].append(np.linalg.norm(ref - v, axis=1).min() <= TOL)
                    if a >= 120:
                        hits["obtuse"].append(hits["all"][-1])
    assert np.mean(hits["gftt"]) >= 0.95
    assert len(hits["obtuse"]) >= 30
    assert np.mean(hits["all"]) >= 0.95, np.mean(hits["all"])
    assert np.mean(hits["obtuse"]) >= 0.90, np.mean(hits["obtuse"])
    assert np.mean(precision) >= 0.90, np.mean(precision)
