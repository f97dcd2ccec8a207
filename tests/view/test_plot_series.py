"""What a plot's series draw, read from the frame the 2D panel is sent (as the browser parses it).

A phase orbit is kept whole; a curve of arrays is drawn as it is now; a histogram counts
what a brute-force count over the same bins counts (and what ``numpy.histogram`` counts);
values that cannot be drawn pause the app with a message naming the series.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ejsrl.view._plot_frame import decode_xy
from ejsrl.view._plots import PlotBinding
from ejsrl.view.elements import Dynamic, Plot, Series, value_of


class _Model:
    INDEPENDENT = "t"

    def __init__(self) -> None:
        self.t = 0.0
        self.theta = 1.0
        self.omega = 0.0
        self.xs = np.linspace(0.0, 1.0, 5)
        self.ys = self.xs**2

    def _ejs_time(self) -> float:
        return self.t


class _App:
    """What a plot binding needs of the app: the model, values read safely, and an error pause."""

    def __init__(self) -> None:
        self.model = _Model()
        self.error = None

    def safe_value(self, prop, where=""):
        return None if self.error is not None else value_of(prop, self.model)

    def fail(self, exc, where=""):
        self.error = exc


def _items(b: PlotBinding, kind: str) -> list[dict]:
    return [it for it in b.handle.last_frame["items"] if it["t"] == kind]


def _orbit(app: _App, b: PlotBinding, steps: int, dt: float = 0.05) -> None:
    """An undamped small-angle pendulum, exactly: theta = cos t, omega = -sin t; one frame a step."""
    for _ in range(steps):
        app.model.t += dt
        app.model.theta, app.model.omega = math.cos(app.model.t), -math.sin(app.model.t)
        b.update(app, playing=False)


@pytest.mark.parametrize("own_x", [False, True])
def test_a_phase_orbit_is_kept_whole(served, own_x):
    # the phase plot: 'x: theta, y: omega' at the plot's level (today's spec) or on the series
    app = _App()
    theta, omega = Dynamic(lambda m: m.theta, "theta"), Dynamic(lambda m: m.omega, "omega")
    series = Series(omega, "omega", x=theta) if own_x else Series(omega, "omega")
    b = PlotBinding(served.server.gui, Plot("phase", Dynamic(lambda m: m.t, "t") if own_x else theta, [series]), clock=served.clock)
    _orbit(app, b, 140)  # 7 s: more than one turn (2 pi)
    assert app.error is None
    xy = decode_xy(_items(b, "polyline")[0]["xy"], 2)
    assert len(xy) == 140  # every point, in the order they came
    quadrants = {(bool(x > 0), bool(y > 0)) for x, y in xy}
    assert quadrants == {(True, True), (True, False), (False, True), (False, False)}
    np.testing.assert_allclose(np.hypot(xy[:, 0], xy[:, 1]), 1.0, atol=1e-6)  # on the circle
    lo_x, hi_x, lo_y, hi_y = b.handle.last_frame["bounds"]
    assert lo_x < -1.0 and hi_x > 1.0 and lo_y < -1.0 and hi_y > 1.0  # the whole orbit in view


def test_an_x_y_series_keeps_its_own_number_of_points_and_follows_a_slider_while_paused(served):
    app = _App()
    theta, omega = Dynamic(lambda m: m.theta, "theta"), Dynamic(lambda m: m.omega, "omega")
    b = PlotBinding(served.server.gui, Plot("phase", Dynamic(lambda m: m.t, "t"), [Series(omega, "omega", x=theta, max_points=50)]), clock=served.clock)
    _orbit(app, b, 120)
    assert len(decode_xy(_items(b, "polyline")[0]["xy"], 2)) == 50
    app.model.theta = 0.3  # paused (the clock stands), a slider moves theta: the head follows
    b.update(app, playing=False)
    xy = decode_xy(_items(b, "polyline")[0]["xy"], 2)
    assert len(xy) == 50 and xy[-1, 0] == pytest.approx(0.3)
    app.model.t = 0.0  # a reset: the orbit starts over
    b.update(app, playing=False)
    assert len(decode_xy(_items(b, "polyline")[0]["xy"], 2)) == 1


def test_a_counter_that_goes_back_with_the_clock_standing_starts_the_chart_over(served):
    # the calibration lab: 'x: n_views'; "Clear views" sets n_views = 0 while paused
    app = _App()
    b = PlotBinding(served.server.gui, Plot("err", Dynamic(lambda m: m.theta, "n"), [Series(Dynamic(lambda m: m.omega, "rms"), "rms")]), clock=served.clock)
    for n in range(5):
        app.model.theta, app.model.omega = float(n), 1.0 / (n + 1)
        app.model.t += 1.0
        b.update(app, playing=False)
    app.model.theta = 0.0  # cleared, the clock standing
    b.update(app, playing=False)
    assert decode_xy(_items(b, "polyline")[0]["xy"], 2)[:, 0].tolist() == [0.0]


def test_a_curve_of_arrays_is_drawn_as_it_is_now(served):
    app = _App()
    b = PlotBinding(served.server.gui, Plot("f", 0.0, [Series(Dynamic(lambda m: m.ys, "xs**2"), "f", x=Dynamic(lambda m: m.xs, "xs"))]), clock=served.clock)
    b.update(app, playing=False)
    np.testing.assert_allclose(decode_xy(_items(b, "polyline")[0]["xy"], 2), np.column_stack((app.model.xs, app.model.ys)), atol=1e-7)
    app.model.xs = np.linspace(-2.0, 2.0, 101)  # a new curve, of another length: redrawn whole
    app.model.ys = np.sin(app.model.xs)
    b.update(app, playing=False)
    np.testing.assert_allclose(decode_xy(_items(b, "polyline")[0]["xy"], 2), np.column_stack((app.model.xs, app.model.ys)), atol=1e-6)
    assert app.error is None


def test_scatter_markers_are_drawn_at_the_data(served):
    app = _App()
    s = Series(Dynamic(lambda m: m.ys, "ys"), "data", "red", x=Dynamic(lambda m: m.xs, "xs"), kind="scatter", marker="square", size=5.0)
    b = PlotBinding(served.server.gui, Plot("d", 0.0, [s]), clock=served.clock)
    b.update(app, playing=False)
    assert not _items(b, "polyline")
    (m,) = _items(b, "markers")
    assert m["shape"] == "square" and m["size"] == 5.0 and m["fill"] == "rgb(255, 0, 0)"
    np.testing.assert_allclose(decode_xy(m["xy"], 2), np.column_stack((app.model.xs, app.model.ys)), atol=1e-7)


def _brute_counts(values: np.ndarray, edges: np.ndarray) -> list[int]:
    """Counts per bin [e_i, e_i+1), the last bin closed, by looking at every value."""
    counts = [0] * (len(edges) - 1)
    for v in values:
        for i in range(len(counts)):
            last = i == len(counts) - 1
            if edges[i] <= v < edges[i + 1] or (last and v == edges[i + 1]):
                counts[i] += 1
                break
    return counts


def test_a_histogram_of_an_array_counts_what_a_brute_force_count_and_numpy_count(served):
    app = _App()
    rng = np.random.default_rng(3)
    app.model.xs = rng.normal(0.0, 1.0, 500)
    b = PlotBinding(served.server.gui, Plot("h", 0.0, [Series(None, "samples", x=Dynamic(lambda m: m.xs, "xs"), kind="histogram", bins=12)]), clock=served.clock)
    b.update(app, playing=False)
    (bars,) = _items(b, "rects")
    r = decode_xy(bars["xy"], 4)  # x0 y0 x1 y1 per bar
    edges = np.linspace(app.model.xs.min(), app.model.xs.max(), 13)
    np.testing.assert_allclose(r[:, 0], edges[:-1], rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(r[:, 2], edges[1:], rtol=1e-6, atol=1e-6)
    assert r[:, 3].tolist() == _brute_counts(app.model.xs, edges)
    assert r[:, 3].tolist() == np.histogram(app.model.xs, bins=12)[0].tolist()
    assert (r[:, 1] == 0).all() and b.handle.last_frame["bounds"][2] == 0.0  # bars stand on 0
    assert b.handle.last_frame["axes"]["y"]["ticks"][0] == [0.0, "0"]


def test_a_histogram_of_a_number_counts_its_history_once_per_step(served):
    app = _App()
    s = Series(None, "theta", x=Dynamic(lambda m: m.theta, "theta"), kind="histogram", bins=4, bin_range=(-1.0, 1.0))
    b = PlotBinding(served.server.gui, Plot("h", 0.0, [s]), clock=served.clock)
    values = []
    for k in range(40):
        app.model.t += 0.1
        app.model.theta = math.cos(0.7 * k)
        values.append(app.model.theta)
        b.update(app, playing=False)
        b.update(app, playing=False)  # the same instant again (a paused frame): not counted twice
    app.model.theta = 5.0  # outside the bins: not counted
    app.model.t += 0.1
    b.update(app, playing=False)
    r = decode_xy(_items(b, "rects")[0]["xy"], 4)
    assert r[:, 3].tolist() == _brute_counts(np.array(values), np.linspace(-1.0, 1.0, 5))
    assert b.handle.last_frame["bounds"][:2] == [-1.0, 1.0]


@pytest.mark.parametrize(
    ("x", "y", "message"),
    [
        (lambda m: m.xs, lambda m: 1.0, "y is a number but its x is an array of 5 values"),
        (lambda m: m.xs, lambda m: np.zeros(4), "has 5 and y has 4"),
        (lambda m: 1.0, lambda m: m.xs, "y is an array of 5 values but its x is a number"),
        (lambda m: m.xs, lambda m: np.zeros((5, 2)), "shape (5, 2)"),
        (lambda m: m.xs, lambda m: "fast", "not 'fast'"),
    ],
)
def test_values_that_cannot_be_drawn_pause_the_app_with_a_message(served, x, y, message):
    app = _App()
    s = Series(Dynamic(y, "y"), "model", x=Dynamic(x, "x"), where="lab.ejs.yaml:12:9")
    b = PlotBinding(served.server.gui, Plot("p", 0.0, [s], where="lab.ejs.yaml:10:5"), clock=served.clock)
    b.update(app, playing=True)
    assert message in app.error.message, app.error
    assert app.error.message.startswith("the plot 'p' cannot draw series 1 (model): ") and app.error.where == "lab.ejs.yaml:12:9"


def test_an_array_against_the_plots_number_x_pauses_with_a_hint(served):
    app = _App()
    b = PlotBinding(served.server.gui, Plot("p", Dynamic(lambda m: m.t, "t"), [Series(Dynamic(lambda m: m.xs, "xs"), "xs")]), clock=served.clock)
    b.update(app, playing=True)
    assert "give the series an x of its own" in str(app.error)


def test_log_axes_show_positive_values_at_powers_of_ten(served):
    app = _App()
    app.model.xs = np.array([0.0, 1e-3, 1e-2, 1e-1, 1.0, 10.0])
    app.model.ys = app.model.xs**2
    s = Series(Dynamic(lambda m: m.ys, "ys"), "x²", x=Dynamic(lambda m: m.xs, "xs"))
    b = PlotBinding(served.server.gui, Plot("log", 0.0, [s], x_log=True, y_log=True), clock=served.clock)
    b.update(app, playing=False)
    f = b.handle.last_frame
    x0, x1, y0, y1 = f["bounds"]
    assert 0 < x0 < 1e-3 and x1 > 10 and 0 < y0 < 1e-6 and y1 > 100
    assert f["axes"]["x"]["log"] and f["axes"]["y"]["log"]
    assert [label for _v, label in f["axes"]["x"]["ticks"]] == ["0.001", "0.01", "0.1", "1", "10"]
    xy = decode_xy(_items(b, "polyline")[0]["xy"], 2)
    assert np.isnan(xy[0]).all() and np.isfinite(xy[1:]).all()  # 0 cannot be shown: the line starts at 1e-3


def test_the_legend_lists_labelled_series_with_their_kind(served):
    app = _App()
    xs = Dynamic(lambda m: m.xs, "xs")
    series = [Series(Dynamic(lambda m: m.ys, "ys"), "model", "blue", x=xs), Series(Dynamic(lambda m: m.ys, "ys"), "data", x=xs, kind="scatter"),
              Series(None, "spread", x=xs, kind="histogram")]
    b = PlotBinding(served.server.gui, Plot("p", 0.0, series, x_range=(-1.0, 2.0)), clock=served.clock)
    b.update(app, playing=False)
    f = b.handle.last_frame
    assert [(e["label"], e["kind"]) for e in f["legend"]] == [("model", "line"), ("data", "marker"), ("spread", "bar")]
    assert f["legend"][0]["color"] == "rgb(0, 0, 255)"
    assert f["bounds"][:2] == [-1.0, 2.0]  # a fixed x range
    one = PlotBinding(served.server.gui, Plot("p", 0.0, series[:1]), clock=served.clock, key="one")
    one.update(app, playing=False)
    assert one.handle.last_frame["legend"] == []  # one series: no legend unless asked


def test_a_plot_x_that_is_not_a_number_pauses_at_the_plot(served):
    app = _App()
    b = PlotBinding(served.server.gui, Plot("p", Dynamic(lambda m: "later", "label"), [Series(Dynamic(lambda m: m.t, "t"), "t")], where="lab.ejs.yaml:10:5"), clock=served.clock)
    b.update(app, playing=True)
    assert app.error.message == "the plot 'p' cannot draw: the plot's x must be a number or a 1-D array of numbers, not 'later'"
    assert app.error.where == "lab.ejs.yaml:10:5"
