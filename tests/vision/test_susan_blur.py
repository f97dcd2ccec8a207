"""SUSAN on blurred pictures (issue #28): the blur read from the image, and the widened mask's
recall against the scenes' ground truth and against GFTT + cornerSubPix at the same count
(the scenes of bench/susan_recall.py --suite blur)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from ejsrl.vision import susan_corners
from ejsrl.vision._susan_scale import BLUR_LIMIT, estimate_blur
from testkit import bench_module

bench = bench_module("susan_recall")


def _recall(scenes, det) -> tuple[float, float]:
    rows = np.array([bench.score(np.asarray(det(img)).reshape(-1, 2), v) + (len(v),) for img, v in scenes], float)
    return float(np.sum(rows[:, 0] * rows[:, 3]) / rows[:, 3].sum()), float(np.nanmean(rows[:, 1]))


@pytest.mark.parametrize("blur,lo,hi", [(0.0, 0.5, 0.85), (1.0, 1.0, 1.3), (1.5, 1.35, 1.65)])
def test_the_blur_is_read_from_a_checkerboard(blur: float, lo: float, hi: float) -> None:
    rng = np.random.default_rng(4)
    for _ in range(2):
        img, _ = bench.checkerboard(rng, blur, 2.0)
        assert lo <= estimate_blur(img) <= hi


def test_blurred_polygons_are_found_as_gftt_finds_them() -> None:
    rng = np.random.default_rng(21)
    scenes = [bench.blurred_polygons(rng, 1.5, 4.0) for _ in range(4)]
    plain, _ = _recall(scenes, susan_corners)
    auto, prec = _recall(scenes, lambda i: susan_corners(i, blur="auto"))
    gftt, gprec = _recall(scenes, lambda i: bench.gftt_refined(i, max(1, len(susan_corners(i, blur="auto")))))
    assert plain < 0.65 and auto >= 0.8 and prec >= 0.8
    assert auto >= gftt - 0.05 and prec >= gprec - 0.05  # within 5 points of GFTT at the same count
    # the camera's own blur, given (a wider mask than the blur read on these small shapes: 0.79 measured)
    given, _ = _recall(scenes, lambda i: susan_corners(i, blur=1.5))
    assert given >= 0.75


def _errors(scenes, det) -> float:
    """The median distance (px) of the corners found within 1.5 px of a true one."""
    d = [bench.score(np.asarray(det(img)).reshape(-1, 2), v)[2] for img, v in scenes]
    return float(np.nanmedian(d))


@pytest.mark.parametrize("noise", [1.0, 3.0])
@pytest.mark.parametrize("blur", [0.8, 1.0, 1.25, 1.5])
def test_blurred_noisy_checkerboards_are_found_as_gftt_and_cornersubpix_find_them(blur: float, noise: float) -> None:
    """Boards of 24-36 px squares turned by up to 0.5 rad (a seed the bench never used), blurred
    and noisy: SUSAN with blur='auto' finds their inner corners within 5 points of GFTT +
    cornerSubPix asked for as many corners (the same precision, within 5 points), each within
    0.3 px at the median."""
    rng = np.random.default_rng(7)
    scenes = [bench.checkerboard(rng, blur, noise) for _ in range(3)]
    auto, prec = _recall(scenes, lambda i: susan_corners(i, blur="auto"))
    gftt, gprec = _recall(scenes, lambda i: bench.gftt_refined(i, max(1, len(susan_corners(i, blur="auto")))))
    assert auto >= gftt - 0.05 and prec >= gprec - 0.05, (auto, gftt, prec, gprec)
    assert _errors(scenes, lambda i: susan_corners(i, blur="auto")) <= 0.3
    if blur >= 1.25:  # the paper's mask alone loses most of them
        assert _recall(scenes, susan_corners)[0] < auto - 0.3


def test_sharp_pictures_are_searched_as_before() -> None:
    rng = np.random.default_rng(3)
    img, _ = bench.blurred_polygons(rng, 0.0, 4.0)
    assert estimate_blur(img) <= BLUR_LIMIT
    np.testing.assert_array_equal(susan_corners(img, blur="auto"), susan_corners(img))
    pts, resp = susan_corners(bench.checkerboard(rng, 1.5, 2.0)[0], blur="auto", return_response=True)
    assert resp.shape == (480, 640) and len(pts) > 20


def test_a_bad_blur_says_what_it_takes() -> None:
    img = np.zeros((50, 50), np.uint8)
    with pytest.raises(ValueError, match="blur is a number of pixels, 'auto' or None"):
        susan_corners(img, blur="yes")
    with pytest.raises(ValueError, match=r"blur is the image's blur in pixels \(>= 0\)"):
        susan_corners(img, blur=-1)
    # a blur so large that next to nothing is left to search is said, not an empty answer (the trial's blur=50)
    big = np.zeros((480, 640), np.uint8)
    big[100:300, 200:400] = 200
    with pytest.raises(ValueError, match=r"a blur of 50 px widens the mask 85 times, which leaves 8 x 6 pixels"):
        susan_corners(big, blur=50)
    assert len(susan_corners(big, blur=10)) == 4  # 17x: 38 x 28 pixels, the square's four corners
    # a blur read from a small image goes as far as the image allows
    small = cv2.GaussianBlur(big[::8, ::8].copy(), (0, 0), 3.0)
    susan_corners(small, blur="auto")
    with pytest.raises(ValueError, match=r"in \(0, 255\].*above 255 every pixel is as similar"):
        susan_corners(big, 300)


@pytest.mark.parametrize("blur", [1.0, 1.5])
def test_rendered_boxes_with_the_cameras_blur_are_found_as_gftt_finds_them(blur: float) -> None:
    """Boxes rendered by the virtual camera (anti-aliased, its blur and noise 2): every visible
    vertex (the scene's ground truth) found within 5 points of GFTT + cornerSubPix at the same
    count and precision, 0.3 px at the median (a seed the bench never used)."""
    from ejsrl.world.rendering import Realism

    rng = np.random.default_rng(7)
    scenes = [bench.cubes(rng, Realism(antialias=3, blur=blur, noise=2.0)) for _ in range(3)]
    auto, prec = _recall(scenes, lambda i: susan_corners(i, blur="auto"))
    gftt, gprec = _recall(scenes, lambda i: bench.gftt_refined(i, max(1, len(susan_corners(i, blur="auto")))))
    assert auto >= gftt - 0.05 and prec >= gprec - 0.05, (auto, gftt, prec, gprec)
    assert _errors(scenes, lambda i: susan_corners(i, blur="auto")) <= 0.3
