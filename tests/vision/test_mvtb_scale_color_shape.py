"""Colour spaces (against scikit-image, OpenCV and published values), pyramids, LoG / DoG
(against SciPy and the scale-space theory of blob size) and Hu moments (against the
formulas written out here and their invariances)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from scipy import ndimage as ndi

from ejsrl.vision import (
    collapse_laplacian_pyramid,
    delta_e,
    dog_filter,
    ellipse_from_moments,
    gaussian_pyramid,
    hu_moments,
    lab_to_rgb,
    laplacian_pyramid,
    log_blobs,
    log_filter,
    rgb_to_lab,
    rgb_to_xyz,
    xyz_to_rgb,
)


def _rgb(seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, (40, 50, 3), dtype=np.uint8)


# -- colour -------------------------------------------------------------------------------------
def test_xyz_and_lab_match_scikit_image():
    from skimage import color

    img = _rgb()
    np.testing.assert_allclose(rgb_to_xyz(img), color.rgb2xyz(img), atol=1e-9)
    # scikit-image rounds the CIE constants (0.008856, 7.787); ours are exact (216/24389, 841/108)
    np.testing.assert_allclose(rgb_to_lab(img), color.rgb2lab(img), atol=5e-4)
    lab = rgb_to_lab(img)
    np.testing.assert_allclose(lab_to_rgb(lab), img / 255.0, atol=1e-9)  # round trip
    np.testing.assert_allclose(xyz_to_rgb(rgb_to_xyz(img)), img / 255.0, atol=1e-9)


def test_lab_matches_opencv_and_published_values():
    img = _rgb(1)
    ref = cv2.cvtColor(img.astype(np.float32) / 255.0, cv2.COLOR_RGB2Lab)
    # OpenCV's float conversion uses tabulated approximations: about 0.1 off on average
    diff = np.abs(rgb_to_lab(img) - ref)
    assert diff.max() < 0.4 and diff.mean() < 0.15
    # sRGB primaries and white (D65): published L*a*b* values
    prim = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]], np.uint8)
    expected = [[53.24, 80.09, 67.20], [87.73, -86.18, 83.18], [32.30, 79.19, -107.86], [100.0, 0.0, 0.0]]
    np.testing.assert_allclose(rgb_to_lab(prim), expected, atol=0.02)
    np.testing.assert_allclose(rgb_to_xyz(np.array([255, 255, 255], np.uint8)), [0.9505, 1.0, 1.0888], atol=2e-4)
    assert delta_e(rgb_to_lab(prim[0]), rgb_to_lab(prim[0])) == 0.0


def test_colour_input_validation():
    with pytest.raises(ValueError, match="3 channels"):
        rgb_to_lab(np.zeros((4, 4)))
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        rgb_to_lab(np.full((2, 2, 3), 200.0))
    with pytest.raises(ValueError, match="uint8"):
        rgb_to_xyz(np.zeros((2, 2, 3), np.int64))


# -- pyramids -----------------------------------------------------------------------------------
def test_gaussian_pyramid_is_the_binomial_filter_then_decimation():
    img = _rgb()[..., 0].astype(np.uint8)
    img = cv2.resize(img, (101, 77))
    pyr = gaussian_pyramid(img, 4)
    assert [p.shape for p in pyr] == [(77, 101), (39, 51), (20, 26), (10, 13)]
    w = np.array([1, 4, 6, 4, 1]) / 16.0
    ref = ndi.correlate(ndi.correlate(img.astype(float), w[None, :], mode="mirror"), w[:, None], mode="mirror")[::2, ::2]
    assert np.abs(pyr[1].astype(float) - ref).max() <= 0.5 + 1e-9  # rounded to uint8


def test_laplacian_pyramid_collapses_to_the_image():
    img = cv2.resize(_rgb()[..., 1], (97, 63))
    lap = laplacian_pyramid(img, 4)
    assert len(lap) == 4 and lap[0].shape == img.shape
    np.testing.assert_allclose(collapse_laplacian_pyramid(lap), img, atol=1e-9)
    with pytest.raises(ValueError, match="levels"):
        gaussian_pyramid(img, 0)


# -- LoG and DoG --------------------------------------------------------------------------------
def test_log_matches_scipy():
    img = cv2.GaussianBlur(_rgb(2)[..., 0], (0, 0), 1.0)
    for sigma in (1.5, 3.0):
        ours = log_filter(img, sigma, normalized=False)
        ref = ndi.gaussian_laplace(img.astype(float), sigma, mode="mirror", truncate=4.0)
        inner = (slice(12, -12), slice(12, -12))
        assert np.abs(ours[inner] - ref[inner]).max() < 0.02 * np.abs(ref[inner]).max()


def test_normalised_log_picks_a_discs_size():
    """A disc of radius r responds most at sigma = r / sqrt(2) (Lindeberg)."""
    img = np.full((121, 121), 255, np.uint8)
    r = 12.0
    cv2.circle(img, (60, 60), int(r), 0, -1, cv2.LINE_AA)
    sigmas = np.linspace(4, 14, 41)
    resp = [log_filter(img, s)[60, 60] for s in sigmas]
    best = sigmas[int(np.argmax(resp))]
    assert abs(best - r / np.sqrt(2)) < 0.6
    blobs = log_blobs(img, dark=True, threshold=50)
    x, y, radius = blobs[0]
    assert (x, y) == (60, 60) and abs(radius - r) < 0.2 * r


def test_dog_approximates_the_scaled_log():
    img = cv2.GaussianBlur(cv2.resize(_rgb(3)[..., 2], (200, 160), interpolation=cv2.INTER_NEAREST), (0, 0), 2.0)
    sigma, k = 3.0, 1.1
    dog = dog_filter(img, sigma, k)
    approx = (k - 1) * log_filter(img, sigma)  # sigma^2 LoG times (k - 1)
    inner = (slice(20, -20), slice(20, -20))
    corr = np.corrcoef(dog[inner].ravel(), approx[inner].ravel())[0, 1]
    assert corr > 0.99
    with pytest.raises(ValueError, match="k must"):
        dog_filter(img, 2.0, 0.9)


# -- Hu moments ---------------------------------------------------------------------------------
def _hu_by_formula(img: np.ndarray) -> np.ndarray:
    """Hu's invariants written out from the normalised central moments."""
    ys, xs = np.nonzero(img)
    w = img[ys, xs].astype(float)
    m00 = w.sum()
    xc, yc = (w * xs).sum() / m00, (w * ys).sum() / m00

    def eta(p, q):
        return (w * (xs - xc) ** p * (ys - yc) ** q).sum() / m00 ** (1 + (p + q) / 2)

    n20, n02, n11, n30, n03, n21, n12 = eta(2, 0), eta(0, 2), eta(1, 1), eta(3, 0), eta(0, 3), eta(2, 1), eta(1, 2)
    return np.array([
        n20 + n02,
        (n20 - n02) ** 2 + 4 * n11**2,
        (n30 - 3 * n12) ** 2 + (3 * n21 - n03) ** 2,
        (n30 + n12) ** 2 + (n21 + n03) ** 2,
        (n30 - 3 * n12) * (n30 + n12) * ((n30 + n12) ** 2 - 3 * (n21 + n03) ** 2)
        + (3 * n21 - n03) * (n21 + n03) * (3 * (n30 + n12) ** 2 - (n21 + n03) ** 2),
        (n20 - n02) * ((n30 + n12) ** 2 - (n21 + n03) ** 2) + 4 * n11 * (n30 + n12) * (n21 + n03),
        (3 * n21 - n03) * (n30 + n12) * ((n30 + n12) ** 2 - 3 * (n21 + n03) ** 2)
        - (n30 - 3 * n12) * (n21 + n03) * (3 * (n30 + n12) ** 2 - (n21 + n03) ** 2),
    ])


def _shape(scale: float = 1.0, angle: float = 0.0, shift=(0, 0)) -> np.ndarray:
    pts = np.array([[0, 0], [40, 0], [40, 10], [15, 10], [15, 35], [0, 35]], float) * scale  # an L
    c, s = np.cos(angle), np.sin(angle)
    pts = pts @ np.array([[c, -s], [s, c]]).T + np.array([100, 100]) + shift
    img = np.zeros((220, 220), np.uint8)
    cv2.fillPoly(img, [np.round(pts * 16).astype(np.int32)], 1, cv2.LINE_8, shift=4)
    return img


def test_hu_moments_match_the_formulas_and_are_invariant():
    img = _shape()
    np.testing.assert_allclose(hu_moments(img, binary=True), _hu_by_formula(img), rtol=1e-6, atol=1e-14)
    ref = hu_moments(img, binary=True, log=True)
    for other in (_shape(angle=np.radians(90)), _shape(scale=1.7), _shape(angle=0.6, shift=(-20, 10)), _shape(scale=0.8, angle=2.0)):
        # the first four to a few per cent (log10 0.05 = 12 %); h5-h7 are products of small third-order terms,
        # which pixel sampling changes more
        assert np.abs(hu_moments(other, binary=True, log=True)[:4] - ref[:4]).max() < 0.05
    mirrored = _shape()[:, ::-1]
    h, hm = hu_moments(img, binary=True), hu_moments(mirrored, binary=True)
    assert np.sign(h[6]) == -np.sign(hm[6])  # h7 tells a shape from its mirror image
    with pytest.raises(ValueError, match="zero area"):
        hu_moments(np.zeros((10, 10), np.uint8))


def test_equivalent_ellipse_of_a_drawn_ellipse():
    img = np.zeros((200, 200), np.uint8)
    cv2.ellipse(img, (100, 90), (60, 25), 30, 0, 360, 255, -1)
    x, y, a, b, theta = ellipse_from_moments(img)
    assert abs(x - 100) < 0.2 and abs(y - 90) < 0.2
    assert abs(a - 60) < 1.0 and abs(b - 25) < 1.0
    assert abs(np.degrees(theta) - 30) < 0.5
