"""Dense optical flow, distance transform, watershed and skeletons, against ground truth
(known shifts, geometric shapes) and against SciPy / scikit-image as independent references."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from scipy import ndimage as ndi

from ejsrl.vision import distance_transform, flow_magnitude, optical_flow, skeleton, split_touching, warp_by_flow, watershed


def _texture(seed: int = 0, h: int = 240, w: int = 320) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.integers(0, 256, (h, w)).astype(np.uint8), (0, 0), 2.0)


# -- optical flow -------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["farneback", "dis"])
def test_flow_of_a_known_subpixel_shift(method):
    prev = _texture()
    dx, dy = 1.6, -0.8
    nxt = cv2.warpAffine(prev, np.float32([[1, 0, dx], [0, 1, dy]]), (320, 240), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
    flow = optical_flow(prev, nxt, method)
    assert flow.shape == (240, 320, 2)
    inner = flow[30:-30, 30:-30]
    np.testing.assert_allclose(np.median(inner.reshape(-1, 2), axis=0), [dx, dy], atol=0.08)
    assert abs(np.median(flow_magnitude(flow)[30:-30, 30:-30]) - np.hypot(dx, dy)) < 0.1
    # warping the next frame back by the flow gives the first frame
    back = warp_by_flow(nxt, flow).astype(int)
    assert np.abs(back[30:-30, 30:-30] - prev[30:-30, 30:-30].astype(int)).mean() < 2.0


def test_flow_of_a_rotation_follows_the_rotation_field():
    prev = _texture(1)
    c, ang = (159.5, 119.5), 2.0
    M = cv2.getRotationMatrix2D(c, ang, 1.0)
    nxt = cv2.warpAffine(prev, M, (320, 240), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
    flow = optical_flow(prev, nxt)
    ys, xs = np.mgrid[0:240, 0:320].astype(float)
    truth = np.stack([M[0, 0] * xs + M[0, 1] * ys + M[0, 2] - xs, M[1, 0] * xs + M[1, 1] * ys + M[1, 2] - ys], axis=-1)
    err = np.linalg.norm(flow - truth, axis=-1)[40:-40, 40:-40]
    assert np.median(err) < 0.15


def test_flow_input_validation():
    with pytest.raises(ValueError, match="same size"):
        optical_flow(np.zeros((10, 10), np.uint8), np.zeros((10, 11), np.uint8))
    with pytest.raises(ValueError, match="method"):
        optical_flow(np.zeros((10, 10), np.uint8), np.zeros((10, 10), np.uint8), "horn")


# -- distance transform -------------------------------------------------------------------------
def _shapes() -> np.ndarray:
    img = np.zeros((120, 160), np.uint8)
    cv2.circle(img, (50, 60), 35, 255, -1)
    cv2.rectangle(img, (95, 20), (150, 100), 255, -1)
    img[60, 120] = 0  # a hole
    return img


@pytest.mark.parametrize(("metric", "ref"), [
    ("euclidean", lambda b: ndi.distance_transform_edt(b)),
    ("l1", lambda b: ndi.distance_transform_cdt(b, metric="taxicab")),
    ("chessboard", lambda b: ndi.distance_transform_cdt(b, metric="chessboard")),
])
def test_distance_transform_matches_scipy(metric, ref):
    img = _shapes()
    d = distance_transform(img, metric)
    np.testing.assert_allclose(d, ref(img > 0), atol=1e-3 if metric == "euclidean" else 0)


def test_distance_transform_of_a_disc_peaks_at_its_radius():
    img = np.zeros((101, 101), np.uint8)
    cv2.circle(img, (50, 50), 40, 1, -1)
    d = distance_transform(img)
    assert abs(d[50, 50] - 41) <= 1.0 and d.max() == d[50, 50]
    with pytest.raises(ValueError, match="2-D"):
        distance_transform(np.zeros((4, 4, 3)))
    with pytest.raises(ValueError, match="empty"):
        distance_transform(np.zeros((0, 0)))
    with pytest.raises(ValueError, match="metric"):
        distance_transform(img, "manhattan")


# -- watershed ----------------------------------------------------------------------------------
def _two_discs() -> tuple[np.ndarray, tuple, tuple, int]:
    img = np.zeros((120, 180), np.uint8)
    c1, c2, r = (60, 60), (118, 60), 35
    cv2.circle(img, c1, r, 255, -1)
    cv2.circle(img, c2, r, 255, -1)
    return img, c1, c2, r


def test_split_touching_separates_two_overlapping_discs_on_their_bisector():
    img, c1, c2, r = _two_discs()
    assert ndi.label(img > 0)[1] == 1  # one blob before
    labels = split_touching(img, min_distance=10)
    ids = sorted(set(np.unique(labels)) - {0})
    assert len(ids) == 2
    ys, xs = np.mgrid[0:120, 0:180]
    nearer1 = (xs - c1[0]) ** 2 + (ys - c1[1]) ** 2 < (xs - c2[0]) ** 2 + (ys - c2[1]) ** 2
    lab1 = labels[c1[1], c1[0]]
    fg = (img > 0) & (labels > 0)
    agree = np.mean((labels[fg] == lab1) == nearer1[fg])
    assert agree > 0.99
    # the dividing line lies on the bisector x = 89
    cut = np.nonzero((img[:, 89] > 0) & (labels[:, 89] == 0))[0]
    assert len(cut) > 0


def test_watershed_agrees_with_scikit_image():
    from skimage.segmentation import watershed as sk_watershed

    img, c1, c2, r = _two_discs()
    d = ndi.distance_transform_edt(img > 0)
    relief = np.uint8(255 * (1 - d / d.max()))
    markers = np.zeros(img.shape, np.int32)
    markers[c1[1], c1[0]], markers[c2[1], c2[0]] = 1, 2
    markers[img == 0] = 3  # the sure background
    ours = watershed(relief, markers)
    ref = sk_watershed(relief, markers)
    valid = ours > 0
    assert np.mean(ours[valid] == ref[valid]) > 0.99
    assert (ours == -1).any() and (ours == -1).mean() < 0.03  # thin lines where basins meet
    # the two discs' basins meet on the bisector x = 89
    line = np.nonzero((ours == -1) & (d > 3))  # not the discs' outlines
    assert np.abs(line[1] - 89).max() <= 1
    with pytest.raises(ValueError, match="shape"):
        watershed(relief, markers[:10])
    with pytest.raises(ValueError, match="integer"):
        watershed(relief, markers.astype(float))


# -- skeleton -----------------------------------------------------------------------------------
def test_skeleton_of_a_bar_is_its_centre_line():
    img = np.zeros((40, 120), np.uint8)
    img[15:24, 10:110] = 255  # 9 px thick, centre row 19
    sk = skeleton(img) > 0
    rows, cols = np.nonzero(sk)
    assert set(rows) == {19}
    assert cols.min() <= 16 and cols.max() >= 103  # nearly the whole length


def test_skeleton_is_thin_connected_and_near_scikit_images():
    from skimage.morphology import skeletonize

    rng = np.random.default_rng(0)
    img = np.zeros((200, 300), np.uint8)
    for _ in range(8):
        cv2.ellipse(img, (int(rng.integers(30, 270)), int(rng.integers(30, 170))), (int(rng.integers(5, 40)), int(rng.integers(5, 30))),
                    float(rng.uniform(0, 180)), 0, 360, 255, -1)
    cv2.circle(img, (150, 100), 20, 0, -1)  # a hole: the skeleton must go round it
    ours = skeleton(img) > 0
    ref = skeletonize(img > 0)
    eight = np.ones((3, 3))
    assert ndi.label(ours, eight)[1] == ndi.label(img > 0, eight)[1]  # one skeleton per shape
    # holes kept: as many background components as the shapes have
    assert ndi.label(~ours)[1] >= ndi.label(img == 0)[1]
    # one pixel wide: no 2 x 2 block
    assert not (ours[:-1, :-1] & ours[1:, :-1] & ours[:-1, 1:] & ours[1:, 1:]).any()
    # every pixel of ours is on or next to scikit-image's skeleton
    assert ndi.distance_transform_edt(~ref)[ours].max() <= 1.5
    assert np.all(img[ours] > 0)
