"""Plot axes as the browser draws them: a strip chart shows its last window; a flat line looks flat.

A small lab plays, is reset (its plots empty), and plays for 1.5 simulated seconds past its
plot's 1 s window. The plot's x range (the bounds of the frame the 2D panel engine holds)
must be about [t - 1, t] for the last t it holds, and the x tick labels drawn on its canvas
(recorded by wrapping ``fillText``) must lie in that range. A 10 s window not yet full shows [first, first + 10]. A second chart plots a constant up to round-off (0.196 + 1e-10 t, like the
tutorial's RK4 energy): its y tick labels must not all read the same.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from testkit.charts import RECORD_TEXT, Strip, plots, tick_labels, tick_number
from testkit.browser import wait_until
from ejsrl.app import App, AppMeta, SimConfig
from ejsrl.view.elements import Dynamic, Node3D, Plot, Scene, Series

SPEC = Strip.SPEC
WINDOW = 1.0
TOL = 0.05  # s: 2.5 frames of the lab


VIEW = [
    Plot("Signal", Dynamic(lambda m: m.t, "t"), [Series(Dynamic(lambda m: m.y, "y"), "y", "blue")], window=WINDOW),
    Plot("Energy", Dynamic(lambda m: m.t, "t"), [Series(Dynamic(lambda m: m.E, "E"), "E", "red")], window=10.0),
    Scene([
        Node3D("grid", "floor", props={"size": 4.0, "cell": 0.25}),
        Node3D("sphere", "bob", props={"radius": 0.08}, position=Dynamic(lambda m: (m.y, 0.0, 1.0), "[y, 0, 1]"), color="orange"),
    ]),
]

def _charts(page) -> list[dict]:
    """Each plot: title, x range, its x data's ends, the text last drawn on its canvas."""
    from ejsrl.view._plot_frame import decode_xy

    out = []
    for p in plots(page):
        lines = [it for it in p["items"] if it["t"] == "polyline"]
        x = decode_xy(lines[0]["xy"], 2)[:, 0] if lines else []
        out.append({"title": p["title"], "min": p["bounds"][0] if p["bounds"] else None, "max": p["bounds"][1] if p["bounds"] else None,
                    "first": float(x[0]) if len(x) else None, "last": float(x[-1]) if len(x) else None, "texts": p["texts"]})
    return out


@contextmanager
def serving_app(app: App) -> Iterator[str]:
    """Serve ``app`` on a free port: yields its URL."""
    server = app.serve("127.0.0.1", 0, block=False)
    try:
        yield f"http://127.0.0.1:{server.get_port()}"
    finally:
        app.stop()
        server.stop()


def _chart(page, title: str) -> dict:
    charts = [c for c in _charts(page) if c["title"] == title]
    return charts[0] if charts else {}


@pytest.mark.browser
def test_a_strip_chart_shows_its_last_window_and_a_flat_line_looks_flat(page):
    app = App(Strip, VIEW, sim=SimConfig(fps=30.0), meta=AppMeta(title="Strip chart", description="", author="Tests", spec=SPEC))
    with serving_app(app) as url:
        page.add_init_script(RECORD_TEXT)
        page.goto(url)
        page.get_by_role("button", name="Play").first.wait_for(timeout=45_000)
        wait_until(lambda: len(_charts(page)) == 2, what="two plots in the panel")
        # play a little, reset (the plots empty), play again: what a student does
        page.get_by_role("button", name="Play").first.click()
        wait_until(lambda: app.model.t > 0.5, what="t to advance after Play")
        page.get_by_role("button", name="Reset").first.click()
        wait_until(lambda: app.model.t < 0.5, what="the reset")
        page.get_by_role("button", name="Play").first.click()
        wait_until(lambda: app.model.t > WINDOW + 1.5, what="t to run 1.5 s past the window")

        def settled() -> bool:
            c = _chart(page, "Signal")
            return bool(c) and c["last"] is not None and c["last"] > WINDOW + 1.0 and len(tick_labels(c["texts"])[0]) >= 2

        wait_until(settled, what="the signal chart to hold data past its window")
        page.get_by_role("button", name="Pause").first.click()
        wait_until(lambda: not app.is_playing(), what="the lab to pause")
        t_end = app.model.t
        wait_until(lambda: abs((_chart(page, "Signal").get("last") or 0.0) - t_end) < 1e-5, timeout=10,
                   what="the chart to show the last point")

        signal = _chart(page, "Signal")
        t = signal["last"]
        # the x range of the frame that holds the data
        assert signal["min"] == pytest.approx(t - WINDOW, abs=TOL) and signal["max"] == pytest.approx(t, abs=TOL), (
            f"x axis [{signal['min']}, {signal['max']}] for data ending at t = {t} with a {WINDOW} s window")
        x_ticks, _ = tick_labels(signal["texts"])
        values = [tick_number(v) for v in x_ticks]
        assert len(values) >= 2 and all(t - WINDOW - TOL <= v <= t + TOL for v in values), (
            f"x tick labels {x_ticks} outside [{t - WINDOW:.2f}, {t:.2f}]")

        # a 10 s window not yet full: the data from the left, the axis [first, first + 10]
        energy = _chart(page, "Energy")
        first = energy["first"]
        assert energy["min"] == pytest.approx(first, abs=TOL) and energy["max"] == pytest.approx(first + 10.0, abs=TOL), (
            f"x axis [{energy['min']}, {energy['max']}] for data from t = {first} with a 10 s window")
        x_ticks, y_ticks = tick_labels(energy["texts"])
        assert x_ticks and all(first - TOL <= tick_number(v) <= first + 10.0 + TOL for v in x_ticks), x_ticks
        assert len(y_ticks) >= 3, f"y tick labels of the flat chart: {y_ticks} (all text: {energy['texts']})"
        assert len(set(y_ticks)) == len(y_ticks), f"y tick labels of a flat line repeat: {y_ticks}"
        values = sorted(tick_number(v) for v in y_ticks)
        assert values[-1] - values[0] >= 1e-4, f"the flat line's y axis spans only {values[-1] - values[0]:g}: {y_ticks}"
