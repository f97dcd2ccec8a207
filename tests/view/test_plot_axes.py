"""The axes a plot's panel is sent: the x window of a strip chart, a flat y that looks flat.

What the 2D panel receives (the frame's ``bounds``, ``[xmin, xmax, ymin, ymax]``) decides
what the user sees: the client draws the plot area over exactly those bounds. The expected
ranges are worked out here by hand from the points.
"""

from __future__ import annotations

import math

import pytest

from ejsrl.view._plot_frame import PAD
from ejsrl.view._plots import PlotBinding
from ejsrl.view.elements import Dynamic, Plot, Series


def _binding(served, *, window: float | None = None, y_range: tuple[float, float] | None = None, n: int = 1) -> PlotBinding:
    series = [Series(Dynamic(lambda m: 0.0, f"y{i}"), f"y{i}") for i in range(n)]
    plot = Plot("p", Dynamic(lambda m: m.t, "t"), series, window=window, y_range=y_range)
    return PlotBinding(served.server.gui, plot, x_label="t", clock=served.clock)


def _play(binding: PlotBinding, t0: float, t1: float, dt: float, f) -> None:
    """Append a point every ``dt`` from t0 to t1 (inclusive) and push, as the view does each frame."""
    for i in range(int(round((t1 - t0) / dt)) + 1):
        t = t0 + i * dt
        binding.append(t, [f(t)])
        binding.push(force=True)


def _sent(binding: PlotBinding) -> dict:
    """The frame the panel last sent to the browser (as the client parses it)."""
    frame = binding.handle.last_frame
    assert frame is not None, "no frame was sent"
    return frame


def _x_range(binding: PlotBinding) -> tuple[float, float]:
    return tuple(_sent(binding)["bounds"][:2])


def _y_range(binding: PlotBinding) -> tuple[float, float]:
    return tuple(_sent(binding)["bounds"][2:])


def _auto_scaled(binding: PlotBinding, ys: list[float]) -> bool:
    """Whether the y axis is the values' extent with the usual margin (not a range pinned around flat values)."""
    lo, hi = min(ys), max(ys)
    pad = PAD * (hi - lo)
    return _y_range(binding) == pytest.approx((lo - pad, hi + pad), rel=1e-6, abs=1e-12)


def test_a_window_longer_than_the_data_shows_the_data_at_the_left_of_the_window(served):
    b = _binding(served, window=6.0)
    _play(b, 0.0, 2.0, 0.02, math.sin)
    assert _x_range(b) == pytest.approx((0.0, 6.0))


def test_once_the_data_is_longer_than_the_window_the_x_axis_is_the_last_window(served):
    # the PID lab: window 6, at t = 12 s the axis ran from about 5 to 63 s
    b = _binding(served, window=6.0)
    _play(b, 0.0, 12.0, 0.02, math.sin)
    lo, hi = _x_range(b)
    assert (lo, hi) == pytest.approx((6.0, 12.0))
    x = b.buffer.data()[0]
    assert x[-1] == pytest.approx(12.0) and x[0] >= lo - 1e-9  # every point kept is on the axis


def test_the_x_window_follows_the_data_after_a_reset(served):
    b = _binding(served, window=8.0)
    _play(b, 0.0, 20.0, 0.05, math.sin)
    b.clear()
    _play(b, 0.0, 9.5, 0.05, math.sin)
    assert _x_range(b) == pytest.approx((1.5, 9.5))


def test_a_plot_without_a_window_spans_its_data(served):
    b = _binding(served)
    _play(b, 2.0, 5.0, 0.1, math.cos)
    assert _x_range(b) == pytest.approx((2.0, 5.0))


def test_a_flat_quantity_gets_a_y_range_where_round_off_looks_flat(served):
    # the tutorial's energy: 0.196 J/kg, RK4 round-off of 7.6e-10 over the run
    b = _binding(served, window=10.0)
    _play(b, 0.0, 9.0, 0.01, lambda t: 0.196 - 7.6e-10 * t / 9.0)
    lo, hi = _y_range(b)
    assert hi - lo > 1e-6, f"a flat line is auto-scaled onto its round-off: {(lo, hi)}"
    assert lo < 0.196 - 7.6e-10 and hi > 0.196
    assert hi - lo >= 1e-3 * 0.196  # the round-off is < 1e-5 of the axis: a flat line
    assert (lo + hi) / 2 == pytest.approx(0.196, rel=1e-4)  # the line in the middle


def test_zero_plotted_with_round_off_is_flat_too(served):
    b = _binding(served)
    _play(b, 0.0, 1.0, 0.01, lambda t: 1e-17 * math.sin(40 * t))
    lo, hi = _y_range(b)
    assert lo < 0.0 < hi and hi - lo >= 1e-12


def test_a_quantity_that_varies_is_auto_scaled(served):
    b = _binding(served, window=10.0)
    _play(b, 0.0, 3.0, 0.01, lambda t: 0.2 * math.sin(3 * t))
    assert _auto_scaled(b, [0.2 * math.sin(3 * 0.01 * i) for i in range(301)])


def test_a_flat_start_that_then_varies_goes_back_to_auto_scaling(served):
    b = _binding(served)
    _play(b, 0.0, 1.0, 0.01, lambda t: 1.0)
    assert _y_range(b) == pytest.approx((0.99, 1.01))  # pinned around the flat line: +-1 %
    _play(b, 1.01, 2.0, 0.01, lambda t: 1.0 + (t - 1.0))
    assert _auto_scaled(b, [1.0, 2.0])


def test_a_flat_line_does_not_resend_its_y_range_at_every_frame(served):
    b = _binding(served)
    _play(b, 0.0, 0.5, 0.01, lambda t: 0.196)
    first = _y_range(b)
    sent = b.handle.sent
    _play(b, 0.51, 5.0, 0.01, lambda t: 0.196 + 1e-9 * t)
    assert _y_range(b) == first
    assert b.handle.sent > sent  # frames were sent (the line grew), with the same y axis


def test_a_y_range_in_the_spec_wins_over_the_flat_range(served):
    b = _binding(served, y_range=(0.0, 0.5))
    _play(b, 0.0, 2.0, 0.01, lambda t: 0.196)
    assert _y_range(b) == (0.0, 0.5)


def test_the_tutorials_energy_plot_is_flat_and_its_angle_plot_shows_the_last_10_s(tmp_path):
    # the lab the user tried: tutorial step 2 (RK4 pendulum, window 10), played 12 s
    from ejsgen.cli import build
    from ejsrl.app import load_app
    from ejsrl.view.viser_view import ViserView, make_server
    from testkit import EXAMPLES

    app = load_app(build(EXAMPLES / "tutorial" / "step2_plot.ejs.yaml", tmp_path / "app"))
    server, _url = make_server("127.0.0.1", 0)
    try:
        view = ViserView(app, server)
        angle, energy = view.panel.plots
        energies = []
        while app.model.t < 12.0:
            for _ in range(5):
                app.step_once()
            energies.append(app.model.E)
            view.on_frame()
        t = app.model.t
        assert _x_range(angle) == pytest.approx((t - 10.0, t))
        assert _x_range(energy) == pytest.approx((t - 10.0, t))
        lo, hi = _y_range(energy)
        drift = max(energies) - min(energies)
        assert 0 < drift < 1e-6 * (hi - lo)  # RK4's drift is there, and invisible on the axis
        assert lo < min(energies) and max(energies) < hi
        theta = angle.buffer.data()[1]
        omega = angle.buffer.data()[2]
        assert _auto_scaled(angle, [*theta, *omega])  # the angle swings: auto-scaled
    finally:
        server.stop()
