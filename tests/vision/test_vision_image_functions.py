"""Each image function against OpenCV or an analytic expectation on small synthetic images."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import ejsrl.vision as V


def square_img(h=64, w=80, x0=20, y0=16, side=24, fg=200, bg=30) -> np.ndarray:
    img = np.full((h, w), bg, np.uint8)
    img[y0 : y0 + side, x0 : x0 + side] = fg
    return img


def test_at_least_fifty_documented_image_functions():
    assert len(V.IMAGE_FUNCTIONS) >= 50
    for name in V.IMAGE_FUNCTIONS:
        fn = getattr(V, name)
        doc = fn.__doc__ or ""
        assert len(doc.split()) >= 5, f"{name} needs a docstring"
    assert set(V.IMAGE_FUNCTIONS) <= set(V.__all__)


# -- conversions -----------------------------------------------------------------------------
def test_gray_is_luma_and_rgb_roundtrip():
    rgb = np.zeros((2, 3, 3), np.uint8)
    rgb[0, 0] = (255, 0, 0)
    rgb[0, 1] = (0, 255, 0)
    rgb[0, 2] = (0, 0, 255)
    rgb[1] = 100
    g = V.to_gray(rgb)
    assert g.shape == (2, 3) and g.dtype == np.uint8
    np.testing.assert_allclose(g[0], [0.299 * 255, 0.587 * 255, 0.114 * 255], atol=1)
    assert (g[1] == 100).all()
    back = V.to_rgb(g)
    assert back.shape == (2, 3, 3) and (back[..., 0] == g).all() and (back[..., 2] == g).all()


def test_hsv_of_primaries_and_roundtrip():
    rgb = np.array([[[255, 0, 0], [0, 255, 0], [0, 0, 255]]], np.uint8)
    hsv = V.rgb_to_hsv(rgb)
    assert list(hsv[0, :, 0]) == [0, 60, 120]  # degrees / 2
    assert (hsv[0, :, 1] == 255).all() and (hsv[0, :, 2] == 255).all()
    np.testing.assert_array_equal(V.hsv_to_rgb(hsv), rgb)


def test_thresholds(rng):
    img = np.arange(256, dtype=np.uint8).reshape(16, 16)
    b = V.threshold(img, 100)
    assert ((b == 255) == (img > 100)).all()
    assert ((V.threshold(img, 100, inverse=True) == 255) == (img <= 100)).all()
    bimodal = np.where(rng.random((40, 40)) < 0.5, 50, 200).astype(np.uint8)
    out, level = V.threshold_otsu(bimodal)
    assert 50 <= level < 200
    assert ((out == 255) == (bimodal == 200)).all()
    # adaptive: a dark spot on a bright gradient is found whatever the global brightness
    grad = np.tile(np.linspace(60, 250, 60), (40, 1)).astype(np.uint8)
    grad[18:22, 48:52] = 120
    ad = V.threshold_adaptive(grad, 11, 5, inverse=True)
    assert ad[20, 50] == 255 and ad[5, 5] == 0 and ad[5, 55] == 0


def test_invert_normalize_brightness_gamma():
    img = np.array([[0, 10, 255]], np.uint8)
    np.testing.assert_array_equal(V.invert(img), [[255, 245, 0]])
    f = np.array([[-1.0, 0.0, 1.0]])
    np.testing.assert_array_equal(V.normalize(f), [[0, 128, 255]])
    np.testing.assert_array_equal(V.adjust_brightness_contrast(img, 10, 2.0), [[10, 30, 255]])
    g = V.adjust_gamma(np.array([[0, 64, 255]], np.uint8), 2.0)
    assert g[0, 0] == 0 and g[0, 2] == 255 and g[0, 1] == round(255 * (64 / 255) ** 0.5)


def test_equalize_and_clahe_spread_a_narrow_histogram(rng):
    img = rng.integers(100, 120, (64, 64)).astype(np.uint8)
    eq = V.equalize_histogram(img)
    assert eq.max() == 255 and eq.min() < 20
    # equalisation keeps the order of grey levels
    order = np.argsort(img.ravel(), kind="stable")
    assert (np.diff(eq.ravel()[order].astype(int)) >= 0).all()
    cl = V.clahe(img, 4.0, (4, 4))
    assert cl.std() > img.std() * 2
    rgb = np.dstack([img, img, img])
    assert V.equalize_histogram(rgb).shape == rgb.shape


def test_histogram_counts():
    img = np.array([[0, 0, 5], [255, 5, 5]], np.uint8)
    h = V.histogram(img)
    assert h.shape == (256,) and h[0] == 2 and h[5] == 3 and h[255] == 1 and h.sum() == 6
    rgb = np.zeros((2, 2, 3), np.uint8)
    rgb[..., 1] = 7
    hh = V.histogram(rgb)
    assert hh.shape == (3, 256) and hh[1, 7] == 4 and hh[0, 0] == 4
    assert V.histogram(img, bins=2).tolist() == [5, 1]


# -- geometry ---------------------------------------------------------------------------------
def test_resize_flip_crop_rotate():
    img = square_img()
    small = V.resize(img, (40, 32), interpolation="nearest")
    assert small.shape == (32, 40)
    np.testing.assert_array_equal(small, img[::2, ::2])
    assert V.resize(img, scale=0.5).shape == (32, 40)
    np.testing.assert_array_equal(V.flip(img, "horizontal"), img[:, ::-1])
    np.testing.assert_array_equal(V.flip(img, "vertical"), img[::-1])
    np.testing.assert_array_equal(V.flip(img, "both"), img[::-1, ::-1])
    np.testing.assert_array_equal(V.crop(img, 10, 5, 30, 20), img[5:25, 10:40])
    assert V.crop(img, 70, 60, 30, 30).shape == (4, 10)  # clipped
    sq = np.zeros((41, 41), np.uint8)
    sq[10:15, 20] = 255  # a bar above the centre (20, 20)
    r = V.rotate(sq, 90)  # counter-clockwise: the bar goes to the left of the centre
    ys, xs = np.nonzero(r > 128)
    assert np.allclose(ys, 20) and xs.min() == 10 and xs.max() == 14


def test_affine_and_perspective_warps_move_points_as_their_matrices():
    img = np.zeros((60, 80), np.uint8)
    img[10, 20] = 255
    M = V.affine_matrix([[0, 0], [1, 0], [0, 1]], [[5, 7], [6, 7], [5, 8]])  # a shift by (5, 7)
    np.testing.assert_allclose(M, [[1, 0, 5], [0, 1, 7]], atol=1e-9)
    out = V.warp_affine(img, M)
    assert np.unravel_index(out.argmax(), out.shape) == (17, 25)
    src = np.array([[0, 0], [79, 0], [79, 59], [0, 59]], float)
    dst = src * 0.5 + 10
    H = V.perspective_matrix(src, dst)
    p = H @ [20, 10, 1]
    np.testing.assert_allclose(p[:2] / p[2], [20, 15])
    big = np.zeros((60, 80), np.uint8)
    big[8:13, 18:23] = 255
    w = V.warp_perspective(big, H)
    ys, xs = np.nonzero(w > 100)
    assert abs(xs.mean() - 20) < 0.6 and abs(ys.mean() - 15) < 0.6


# -- filters and noise ------------------------------------------------------------------------
def test_smoothing_filters_against_analytic_values(rng):
    img = np.zeros((9, 9), np.uint8)
    img[4, 4] = 90
    assert V.box_filter(img, 3)[4, 4] == 10 and V.box_filter(img, 3)[3, 3] == 10 and V.box_filter(img, 3)[2, 2] == 0
    g = V.gaussian_blur(np.full((9, 9), 77, np.uint8), 5, 1.0)
    assert (g == 77).all()  # a constant image stays constant
    gi = V.gaussian_blur(img.astype(np.uint8) * 2, 5, 1.0)
    assert gi[4, 4] == gi.max() and gi[4, 3] == gi[3, 4] == gi[4, 5]
    noisy = V.add_salt_pepper_noise(np.full((40, 40), 120, np.uint8), 0.05, seed=3)
    assert ((noisy == 0) | (noisy == 255)).mean() == pytest.approx(0.05, abs=0.02)
    assert (V.median_blur(noisy, 3) == 120).mean() > 0.99
    # bilateral: smooths a flat noisy region, keeps a strong step
    step = np.where(np.arange(40)[None, :] < 20, 50, 200).astype(np.uint8).repeat(40, 0)
    noisy2 = V.add_gaussian_noise(step, 5.0, seed=1)
    bf = V.bilateral_filter(noisy2, 9, 30, 30)
    assert bf[:, 2:15].std() < noisy2[:, 2:15].std()
    assert bf[:, 18].mean() < 80 and bf[:, 21].mean() > 170


def test_gaussian_noise_statistics():
    out = V.add_gaussian_noise(np.full((200, 200), 128, np.uint8), 10.0, seed=0)
    assert abs(out.mean() - 128) < 0.3 and abs(out.std() - 10) < 0.3
    np.testing.assert_array_equal(out, V.add_gaussian_noise(np.full((200, 200), 128, np.uint8), 10.0, seed=0))


def test_sharpen_and_convolve():
    img = np.zeros((7, 7), np.uint8)
    img[:, 3:] = 100
    s = V.sharpen(img, 1.0)
    assert s[3, 2] == 0 and s[3, 3] == 200 and s[3, 5] == 100  # overshoot at the step
    k = np.array([[0, 0, 0], [0, 0, 1], [0, 0, 0]], float)  # correlation: takes the right neighbour
    c = V.convolve(img, k)
    np.testing.assert_array_equal(c[:, 2], 100)
    f = V.convolve(img, [[-1, 0, 1]], output="float")
    assert f.dtype == np.float64 and f[3, 2] == 100 and f[3, 3] == 100 and f[3, 0] == 0


def test_morphology_on_a_square():
    img = square_img(fg=255, bg=0)  # 24x24 square
    area = lambda a: int((a > 0).sum())  # noqa: E731
    assert area(V.erode(img, 3)) == 22 * 22
    assert area(V.dilate(img, 3)) == 26 * 26
    specks = img.copy()
    specks[2, 2] = 255
    np.testing.assert_array_equal(V.morph_open(specks, 3), img)
    holes = img.copy()
    holes[28, 30] = 0
    np.testing.assert_array_equal(V.morph_close(holes, 3), img)
    grad = V.morph_gradient(img, 3)
    assert area(grad) == 26 * 26 - 22 * 22
    th = V.top_hat(specks, 5)
    assert th[2, 2] == 255 and area(th) == 1
    bh = V.black_hat(holes, 5)
    assert bh[28, 30] == 255 and area(bh) == 1
    assert V.structuring_element("cross", 3).tolist() == [[0, 1, 0], [1, 1, 1], [0, 1, 0]]


# -- edges ------------------------------------------------------------------------------------
def test_derivative_operators_on_a_ramp():
    ramp = np.tile(np.arange(20, dtype=np.uint8) * 3, (10, 1))  # dI/dx = 3
    gx, gy = V.sobel(ramp, "both")
    assert np.allclose(gx[2:-2, 2:-2], 8 * 3) and np.allclose(gy[2:-2, 2:-2], 0)
    assert np.allclose(V.scharr(ramp, "x")[2:-2, 2:-2], 32 * 3)
    assert np.allclose(V.prewitt(ramp, "x")[2:-2, 2:-2], 6 * 3)
    d1, d2 = V.roberts(ramp, "both")
    assert np.allclose(d1[:-1, :-1], -3) and np.allclose(d2[:-1, :-1], 3)
    np.testing.assert_allclose(V.sobel(ramp, "magnitude"), np.hypot(gx, gy))
    yy, xx = np.mgrid[0:20, 0:20].astype(float)
    quad = (xx - 10) ** 2 + (yy - 10) ** 2  # Laplacian = 4
    assert np.allclose(V.laplacian(np.clip(quad, 0, 255).astype(np.uint8))[8:12, 8:12], 4)
    gm = V.gradient_magnitude(square_img())
    assert gm.dtype == np.uint8 and gm.max() == 255 and gm[40, 5] == 0


def test_canny_outlines_the_square():
    img = square_img()
    e = V.canny(img, 50, 150)
    ys, xs = np.nonzero(e)
    assert len(xs) > 80
    # every edge pixel is within one pixel of the square's border (x 19.5..43.5, y 15.5..39.5)
    d = np.minimum.reduce([np.abs(xs - 19.5), np.abs(xs - 43.5), np.abs(ys - 15.5), np.abs(ys - 39.5)])
    assert d.max() <= 1.0
    np.testing.assert_array_equal(e, cv2.Canny(img, 50, 150))


# -- point features -----------------------------------------------------------------------------
TRUE_CORNERS = np.array([[19.5, 15.5], [43.5, 15.5], [43.5, 39.5], [19.5, 39.5]])


def _near_all_corners(pts, tol):
    d = np.linalg.norm(TRUE_CORNERS[:, None] - np.asarray(pts)[None], axis=2)
    return d.min(axis=1).max() <= tol


def test_harris_shi_tomasi_fast_find_square_corners():
    img = square_img()
    h = V.harris_corners(img, 10, 0.1)
    assert len(h) == 4 and _near_all_corners(h, 1.5)
    st = V.shi_tomasi_corners(img, 10, 0.1)
    assert len(st) == 4 and _near_all_corners(st, 1.5)
    # FAST's non-maximum suppression needs distinct scores: a slightly blurred square
    fa = V.fast_corners(V.gaussian_blur(img, 3), 20)
    assert len(fa) == 4 and _near_all_corners(fa, 2.2)  # FAST marks a pixel just inside the corner
    raw = V.fast_corners(img, 40, nonmax=False)
    assert _near_all_corners(raw, 1.5)
    resp = V.harris_response(img)
    y, x = np.unravel_index(resp.argmax(), resp.shape)
    assert np.min(np.linalg.norm(TRUE_CORNERS - [x, y], axis=1)) <= 2.2  # the peak pixel, 1.5 px in


def test_orb_features_are_on_structure(rng):
    img = V.gaussian_blur((rng.random((120, 160)) * 255).astype(np.uint8), 5)
    pts, desc = V.orb_features(img, 100)
    assert 10 < len(pts) <= 100 and desc.shape == (len(pts), 32) and desc.dtype == np.uint8
    assert (pts[:, 0] >= 0).all() and (pts[:, 0] < 160).all() and (pts[:, 1] < 120).all()
    p0, _ = V.orb_features(np.zeros((50, 50), np.uint8))
    assert len(p0) == 0


# -- Hough ------------------------------------------------------------------------------------
def test_hough_lines_and_segments_find_a_drawn_line():
    img = np.zeros((100, 100), np.uint8)
    cv2.line(img, (0, 30), (99, 30), 255, 1)  # y = 30: theta = 90 deg, rho = 30
    lines = V.hough_lines(img, 60)
    assert len(lines) >= 1
    rho, theta = lines[0]
    assert abs(rho - 30) <= 1 and abs(theta - np.pi / 2) <= np.radians(1.5)
    segs = V.hough_segments(img, 50, min_length=50)
    assert len(segs) >= 1 and np.allclose(segs[0][[1, 3]], 30) and abs(segs[0][2] - segs[0][0]) > 90


def test_hough_circles_find_a_drawn_disc():
    img = np.zeros((120, 120), np.uint8)
    cv2.circle(img, (60, 50), 25, 255, -1)
    circles = V.hough_circles(V.gaussian_blur(img, 5), 15, 40, votes=20)
    assert len(circles) >= 1
    x, y, r = circles[0]
    assert abs(x - 60) <= 2 and abs(y - 50) <= 2 and abs(r - 25) <= 3


# -- regions ----------------------------------------------------------------------------------
def test_components_contours_moments_blobs():
    img = np.zeros((50, 60), np.uint8)
    img[5:15, 5:25] = 255  # 10 x 20 = 200 px, centroid (14.5, 9.5)
    img[30:40, 40:45] = 255  # 50 px, centroid (42, 34.5)
    img[45, 2] = 255  # 1 px
    labels, regions = V.connected_components(img, min_area=2)
    assert len(regions) == 2 and labels.max() == 3
    assert regions[0].area == 200 and regions[0].bbox == (5, 5, 20, 10)
    np.testing.assert_allclose(regions[0].centroid, (14.5, 9.5))
    contours = V.find_contours(img, min_area=10)
    assert len(contours) == 2
    areas = sorted(cv2.contourArea(c.astype(np.float32)) for c in contours)
    assert areas == [4 * 9, 9 * 19]  # the outline through the border pixel centres
    np.testing.assert_allclose(V.centroid(img[:, :30][:, :]), ((14.5 * 200 + 2) / 201, (9.5 * 200 + 45) / 201))
    m = V.moments(img, binary=True)
    assert m["m00"] == 251
    b = V.blobs(img, 10)
    np.testing.assert_allclose(b, [[14.5, 9.5], [42.0, 34.5]])


def test_colour_segmentation():
    rgb = np.zeros((40, 60, 3), np.uint8)
    rgb[:] = (40, 40, 40)
    rgb[5:15, 5:15] = (220, 20, 20)  # red
    rgb[20:30, 30:50] = (20, 20, 220)  # blue
    mask, cents = V.color_segment(rgb, "red")
    assert (mask > 0).sum() == 100
    np.testing.assert_allclose(cents, [[9.5, 9.5]])
    _, cb = V.color_segment(rgb, "blue")
    np.testing.assert_allclose(cb, [[39.5, 24.5]])
    m = V.color_mask(rgb, (0, 0, 200), (60, 60, 255), space="rgb")
    assert (m > 0).sum() == 200
    with pytest.raises(ValueError, match="unknown colour"):
        V.color_segment(rgb, "purple")


# -- matching and tracking ------------------------------------------------------------------------
def test_template_matching_finds_the_patch(rng):
    img = V.gaussian_blur((rng.random((80, 100)) * 255).astype(np.uint8), 3)
    tpl = img[30:45, 50:70].copy()
    loc, score, res = V.match_template(img, tpl)
    assert loc == (50.0, 30.0) and score > 0.99 and res.shape == (80 - 15 + 1, 100 - 20 + 1)
    loc2, s2, _ = V.match_template(img, tpl, method="sqdiff_normed")
    assert loc2 == (50.0, 30.0) and s2 < 1e-3


def test_lucas_kanade_tracks_a_shift(rng):
    img = V.gaussian_blur((rng.random((100, 120)) * 255).astype(np.uint8), 7)
    M = np.float64([[1, 0, 3.0], [0, 1, -2.0]])
    moved = cv2.warpAffine(img, M, (120, 100))
    pts = V.shi_tomasi_corners(img, 20, 0.01, 8)
    pts = pts[(pts[:, 0] > 15) & (pts[:, 0] < 105) & (pts[:, 1] > 15) & (pts[:, 1] < 85)]
    new, ok = V.lk_track(img, moved, pts)
    assert ok.all() and len(pts) >= 5
    np.testing.assert_allclose(new - pts, np.tile([3.0, -2.0], (len(pts), 1)), atol=0.1)


# -- drawing ----------------------------------------------------------------------------------
def test_drawing_helpers_paint_where_asked():
    base = np.zeros((40, 50), np.uint8)
    p = V.draw_points(base, [[10, 20]], "red", size=5)
    assert p.shape == (40, 50, 3) and tuple(p[20, 10]) == (255, 0, 0) and tuple(p[20, 12]) == (255, 0, 0)
    assert tuple(p[5, 5]) == (0, 0, 0)
    ln = V.draw_lines(base, [[0, 5, 49, 5]], "green")
    assert (ln[5, :, 1] == 200).all() and ln[6, :, 1].max() == 0
    bx = V.draw_boxes(base, [[10, 10, 5, 4]], "blue")
    assert tuple(bx[10, 10]) == (0, 0, 255) and tuple(bx[13, 14]) == (0, 0, 255) and tuple(bx[11, 11]) == (0, 0, 0)
    ci = V.draw_circles(base, [[25, 20, 8]], (1, 2, 3))
    assert tuple(ci[20, 33]) == (1, 2, 3) and tuple(ci[20, 25]) == (0, 0, 0)
    co = V.draw_contours(base, [np.array([[5, 5], [15, 5], [15, 15], [5, 15]])], "white")
    assert co[5, 10, 0] == 255 and co[10, 10, 0] == 0
    tx = V.draw_text(base, "Hi", (2, 30), "white")
    assert tx[15:32, 0:25].max() > 0 and tx[0:10].max() == 0
    assert base.max() == 0  # inputs are not modified
