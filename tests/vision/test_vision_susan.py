"""SUSAN on rendered images: the corners of a perspective-tilted square and its edges."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import corners_world, square_world

from ejsrl.robotics.transforms import r2t, rotx, roty, rotz
from ejsrl.vision import SUSAN_MASK, CameraModel, Pipeline, add_gaussian_noise, susan, susan_corners, susan_edges, to_gray, usan_area
from ejsrl.world import render

pytestmark = pytest.mark.usefixtures("susan_path")  # each test on both SUSAN paths (conftest.py)

CAM = CameraModel(320, 240, fov_deg=50)


def tilted_square_view(tilt=(0.45, -0.3, 0.35)):
    T_sq = r2t(rotx(tilt[0]) @ roty(tilt[1]) @ rotz(tilt[2]))
    T_cam = np.eye(4)
    T_cam[:3, :3] = rotx(np.pi)  # looking down the world -z axis at the square
    T_cam[:3, 3] = (0.02, -0.01, 0.55)
    w = square_world(T_sq, backing=False)
    rgb, depth = render(w, CAM, T_cam, background=(0.1, 0.1, 0.12))
    truth = CAM.project(corners_world(T_sq), T_cam)
    return rgb, truth


def test_mask_is_the_37_pixel_disc():
    assert len(SUSAN_MASK) == 37
    assert (np.hypot(SUSAN_MASK[:, 0], SUSAN_MASK[:, 1]) <= 3.4).all()
    assert sorted(np.bincount(SUSAN_MASK[:, 1] + 3).tolist()) == [3, 3, 5, 5, 7, 7, 7]


def test_usan_area_flat_and_straight_edge():
    flat = np.full((20, 20), 90, np.uint8)
    assert np.allclose(usan_area(flat), 37)
    step = np.full((20, 20), 40, np.uint8)
    step[:, 10:] = 200
    n = usan_area(step, t=20)
    # beside a straight vertical edge the USAN is the nucleus column plus three to one side: 7 + 7 + 5 + 3
    assert n[10, 9] == pytest.approx(22) and n[10, 10] == pytest.approx(22)
    assert n[10, 6] == pytest.approx(37) and n[10, 5] == pytest.approx(37)
    # the smooth brightness test: a difference of t counts exp(-1)
    half = np.full((20, 20), 100, np.uint8)
    half[10, 10] = 120
    assert usan_area(half, t=20)[10, 10] == pytest.approx(1 + 36 * round(100 * np.exp(-1)) / 100)


@pytest.mark.parametrize("noise", [0.0, 6.0])
def test_susan_finds_the_four_corners_of_a_tilted_square(noise):
    rgb, truth = tilted_square_view()
    img = to_gray(rgb)
    if noise:
        img = add_gaussian_noise(img, noise, seed=7)
    pts = susan_corners(img, t=25)
    assert len(pts) >= 4
    best4 = pts[:4]  # strongest first
    d = np.linalg.norm(truth[:, None] - best4[None], axis=2)
    assert d.min(axis=1).max() < 1.5, d.min(axis=1)
    # each true corner has its own detection
    assert len(set(d.argmin(axis=1).tolist())) == 4
    if not noise:
        assert len(pts) == 4


def test_susan_without_subpixel_is_the_pixel_inside_the_corner():
    rgb, truth = tilted_square_view()
    pts = susan_corners(rgb, t=25, subpixel=False)
    assert len(pts) == 4 and np.allclose(pts, np.rint(pts))
    d = np.linalg.norm(truth[:, None] - pts[None], axis=2).min(axis=1)
    assert d.max() < 2.0


def test_susan_edges_lie_on_the_square_sides():
    rgb, truth = tilted_square_view()
    edges, pts = susan_edges(to_gray(rgb), t=25)
    assert edges.dtype == np.uint8 and set(np.unique(edges)) <= {0, 255}
    # distance of each edge point to the nearest side of the projected square
    a = truth
    b = np.roll(truth, -1, axis=0)
    ab = b - a
    tpar = np.clip(((pts[:, None] - a[None]) * ab[None]).sum(-1) / (ab * ab).sum(-1)[None], 0, 1)
    closest = a[None] + tpar[..., None] * ab[None]
    dist = np.linalg.norm(pts[:, None] - closest, axis=2).min(axis=1)
    assert len(pts) > 0.8 * np.linalg.norm(ab, axis=1).sum()  # the outline is (nearly) complete
    assert np.mean(dist < 1.5) > 0.97
    assert dist.max() < 3.0
    # thin: mostly one pixel across (per side, about one point per unit of length)
    assert len(pts) < 1.6 * np.linalg.norm(ab, axis=1).sum()


def test_susan_alias_and_pipeline_give_the_same_corners():
    rgb, _ = tilted_square_view()
    direct = susan_corners(to_gray(rgb), t=25)
    np.testing.assert_array_equal(susan(rgb, 25), direct)
    res = Pipeline("gray", ("susan", {"t": 25})).run(rgb)
    np.testing.assert_array_equal(res.points, direct)
    np.testing.assert_array_equal(res.image, to_gray(rgb))
    img, pts = Pipeline(to_gray, lambda g: susan_corners(g, t=25))(rgb)
    np.testing.assert_array_equal(pts, direct)
    e = Pipeline("gray", ("susan_edges", {"t": 25}))(rgb)
    assert e.image.max() == 255 and len(e.features["susan_edges"]) > 100
    with pytest.raises(ValueError, match="did you mean 'susan'"):
        Pipeline("gray", "susna")
    with pytest.raises(ValueError, match="unknown SUSAN kind"):
        susan(rgb, kind="blobs")


def test_susan_is_deterministic_and_shape_safe():
    rgb, _ = tilted_square_view()
    a = susan_corners(rgb, t=25)
    b = susan_corners(rgb.copy(), t=25)
    np.testing.assert_array_equal(a, b)
    assert susan_corners(np.zeros((5, 5), np.uint8)).shape == (0, 2)
    assert susan_corners(np.full((50, 50), 128, np.uint8)).shape == (0, 2)
