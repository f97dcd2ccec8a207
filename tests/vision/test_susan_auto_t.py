"""``susan_corners(t="auto")`` (issue #28, session 11's trial): the brightness threshold read from
the image, half the step of its weaker edges, between the noise's floor and the paper's 25.

References: Gaussian noise of known sigma added to a picture with edges (the noise estimate);
the true vertices of rendered boxes on a floor, dimly lit (their faces 5-20 grey levels apart,
where t = 25 missed most three-face vertices), found within 1.5 px, against GFTT +
cornerSubPix asked for as many corners (equal precision); and checkerboards and polygons,
whose high contrast keeps t at 25 (the same corners as the default). Seeds the bench
(bench/susan_recall.py --suite blur) never used.
"""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.vision import susan_corners
from ejsrl.vision._susan_scale import T_MAX, T_MIN, auto_threshold, estimate_noise
from ejsrl.world.rendering import Realism
from testkit import bench_module

bench = bench_module("susan_recall")


def _recall(scenes, det) -> tuple[float, float]:
    rows = np.array([bench.score(np.asarray(det(img)).reshape(-1, 2), v) + (len(v),) for img, v in scenes], float)
    return float(np.sum(rows[:, 0] * rows[:, 3]) / rows[:, 3].sum()), float(np.nanmean(rows[:, 1]))


@pytest.mark.parametrize("sigma", [0.5, 1.0, 2.0, 4.0, 8.0])
def test_the_noise_is_read_past_the_edges(sigma: float) -> None:
    rng = np.random.default_rng(11)
    y, x = np.mgrid[0:480, 0:640]
    base = 110 + 50 * np.sin(x / 37.0) * np.cos(y / 23.0)
    base[120:330, 180:430] += 70  # a box with hard edges: the mask answers to them, not to noise
    img = np.clip(base + rng.normal(0, sigma, base.shape), 0, 255).round().astype(np.uint8)
    assert abs(estimate_noise(img) - sigma) <= 0.1 * sigma + 0.1


def test_high_contrast_pictures_keep_the_papers_threshold() -> None:
    rng = np.random.default_rng(5)
    for blur, noise in ((0.7, 1.0), (1.5, 2.0)):
        img, _ = bench.checkerboard(rng, blur, noise)
        assert auto_threshold(img) == T_MAX
        assert np.array_equal(susan_corners(img, "auto", blur="auto"), susan_corners(img, T_MAX, blur="auto"))


@pytest.mark.parametrize("blur,noise", [(0.0, 0.0), (1.0, 2.0), (1.5, 2.0)])
def test_dim_boxes_on_a_floor_are_found_as_gftt_finds_them(blur: float, noise: float) -> None:
    """Their vertices: with t = 25 most are missed (a box's faces are closer than 25 grey levels);
    with t = "auto" at least 0.6 of them, within 5 points of GFTT + cornerSubPix at the same
    count and at its precision or better."""
    rng = np.random.default_rng(301)
    scenes = [bench.floor_boxes(rng, Realism(antialias=3, blur=blur, noise=noise)) for _ in range(6)]
    for img, _ in scenes:
        assert T_MIN <= auto_threshold(img) < 20
    fixed, _ = _recall(scenes, lambda i: susan_corners(i, blur="auto"))
    auto, prec = _recall(scenes, lambda i: susan_corners(i, "auto", blur="auto"))
    gftt, gprec = _recall(scenes, lambda i: bench.gftt_refined(i, max(1, len(susan_corners(i, "auto", blur="auto")))))
    assert auto >= 0.6 and auto >= fixed + 0.2, (auto, fixed)
    assert auto >= gftt - 0.05 and prec >= gprec - 0.05, (auto, gftt, prec, gprec)


def test_a_threshold_that_is_neither_a_number_nor_auto_is_refused() -> None:
    img = np.zeros((40, 40), np.uint8)
    for bad in ("autp", 0, -3.0, None, [25], True):
        with pytest.raises(ValueError, match="'auto'"):
            susan_corners(img, bad)
