"""Plot buffers, a plot's frame on the 2D panel, image preparation and the server helper."""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.view._plots import PlotBinding, PlotBuffer, prepare_image
from ejsrl.view.elements import Dynamic, Plot, Series
from ejsrl.view.viser_view import make_server


def test_the_buffer_keeps_the_window_span():
    b = PlotBuffer(1, window=1.0)
    for i in range(50):
        b.append(i * 0.1, [i])
    x, y = b.data()
    assert x[0] == pytest.approx(3.9) and x[-1] == pytest.approx(4.9)
    assert y.tolist() == list(range(39, 50))


def test_the_buffer_keeps_at_most_max_points_over_many_appends():
    b = PlotBuffer(2, max_points=10)
    for i in range(1000):
        b.append(float(i), [i, -i])
    x, y1, y2 = b.data()
    assert x.tolist() == [float(i) for i in range(990, 1000)]
    assert (y2 == -x).all()


def test_the_same_instant_replaces_the_last_point_and_going_back_starts_over():
    b = PlotBuffer(1)
    b.append(0.0, [1.0])
    b.append(1.0, [2.0])
    b.append(1.0, [5.0])  # paused, a slider moved
    assert b.data()[1].tolist() == [1.0, 5.0]
    b.append(0.5, [3.0])  # t went back
    assert b.data()[0].tolist() == [0.5]


def test_non_finite_points_are_skipped():
    b = PlotBuffer(1)
    assert not b.append(0.0, [float("nan")])
    assert not b.append(float("inf"), [0.0])
    assert len(b) == 0


def test_fixed_y_range_and_numeric_x_axis(served):
    plot = Plot("p", Dynamic(lambda m: m.t, "t"), [Series(Dynamic(lambda m: m.x), "x", "#00ff00")], y_range=(-2, 3))
    binding = PlotBinding(served.server.gui, plot, x_label="t")
    binding.append(10.0, [50.0])  # outside the fixed range: the range stays
    binding.append(20.0, [-40.0])
    binding.push(force=True)
    frame = binding.handle.last_frame
    assert frame["bounds"] == [10.0, 20.0, -2.0, 3.0]
    assert frame["axes"]["x"]["title"] == "t" and [v for v, _ in frame["axes"]["x"]["ticks"]] == [10.0, 12.0, 14.0, 16.0, 18.0, 20.0]
    assert [it["stroke"] for it in frame["items"]] == ["rgb(0, 255, 0)"]


def test_images_become_rgb_uint8_with_markers():
    gray = np.zeros((40, 50), dtype=np.uint8)
    out = prepare_image(gray, np.array([[10.0, 20.0]]))
    assert out.shape == (40, 50, 3) and out.dtype == np.uint8
    assert out[:, :, 0].max() > 200 and gray.max() == 0  # drawn on a copy
    assert prepare_image(np.ones((4, 4, 3)) * 0.5)[0, 0].tolist() == [127, 127, 127]
    assert prepare_image(np.zeros((3,))) is None and prepare_image(None) is None


def test_image_points_are_rings_drawn_with_numpy_at_their_sub_pixel_places(monkeypatch):
    """An image's ``points`` are drawn without OpenCV (a web page's Python has none): a red ring of
    radius min(H, W) / 80 around each point, centred on the point to a tenth of a pixel (the
    centroid of the red drawn), a black ring just outside it, the picture untouched elsewhere;
    NaN and far-away points are left out."""
    import sys

    monkeypatch.setitem(sys.modules, "cv2", None)  # import cv2 fails, as in a page
    grey = np.full((400, 480), 128, np.uint8)
    pts = np.array([[100.3, 200.7], [300.0, 50.5], [np.nan, 10.0], [5000.0, 3.0]])
    out = prepare_image(grey, pts)
    r = 5  # 400 / 80
    y, x = np.mgrid[0:400, 0:480]
    red = (out[:, :, 0].astype(int) - out[:, :, 1]).clip(0)  # how red each pixel is
    for px, py in pts[:2]:
        d = np.hypot(x - px, y - py)
        ring = np.abs(d - r) < 0.5
        assert (out[ring][:, 0] > 200).all() and (out[ring][:, 1] < 90).all()  # red on the ring
        outside = np.abs(d - (r + 1.5)) < 0.25
        assert out[outside].max(axis=1).mean() < 60  # dark just outside it
        near = d < r + 4
        w = red * near
        assert abs((w * x).sum() / w.sum() - px) < 0.1 and abs((w * y).sum() / w.sum() - py) < 0.1
        assert (out[d < r - 1.5] == 128).all()  # the middle is the picture's
    far = np.min([np.hypot(x - px, y - py) for px, py in pts[:2]], axis=0) > r + 3
    assert (out[far] == 128).all() and (grey == 128).all()
    many = np.random.default_rng(3).random((3000, 2)) * [480, 400]
    assert (prepare_image(grey, many)[:, :, 0] > 200).mean() > 0.2  # thousands (a texture's corners) drawn


def test_make_server_takes_the_next_free_port():
    first, url1 = make_server("127.0.0.1", 0)
    try:
        second, url2 = make_server("127.0.0.1", first.get_port())
        try:
            assert second.get_port() != first.get_port()
            assert url2 == f"http://127.0.0.1:{second.get_port()}"
        finally:
            second.stop()
    finally:
        first.stop()
