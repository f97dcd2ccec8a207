"""A windowed strip chart after the student reloads the tab (Debian's Chromium).

A lab with a 10 s plot window (a small strip-chart lab; examples/pendulum, whose heavier
page showed the fault every time) plays for 3 s; the student reloads the page (their
simulation is kept, and goes on playing). The plot must come back with its points and axes
within a second or two: x ticks within [first, first + 10] (the window not full yet) and y
ticks, as drawn on its canvas (recorded by wrapping ``fillText``).
"""

from __future__ import annotations


import pytest

from ejsrl.app import App, AppMeta, SimConfig
from ejsrl.view.elements import Dynamic, Plot, Series
from testkit.charts import RECORD_TEXT, Strip, plots, tick_labels, tick_number
from testkit.browser import ARTIFACTS, wait_until

SPEC = Strip.SPEC
WINDOW = 10.0
TOL = 0.05


VIEW = [Plot("Signal", Dynamic(lambda m: m.t, "t"), [Series(Dynamic(lambda m: m.y, "y"), "y", "blue")], window=WINDOW)]

def _chart(page) -> dict | None:
    """The first plot: its x range, y range, number of points, x data's ends, drawn text."""
    from ejsrl.view._plot_frame import decode_xy

    found = plots(page)
    if not found or not found[0]["bounds"]:
        return None
    p = found[0]
    lines = [it for it in p["items"] if it["t"] == "polyline"]
    x = decode_xy(lines[0]["xy"], 2)[:, 0] if lines else []
    return {"min": p["bounds"][0], "max": p["bounds"][1], "ymin": p["bounds"][2], "ymax": p["bounds"][3], "n": len(x),
            "first": float(x[0]) if len(x) else None, "last": float(x[-1]) if len(x) else None, "texts": p["texts"], "drawn": p["drawn"]}


@pytest.mark.browser
@pytest.mark.parametrize("lab", ["strip", "pendulum"])
def test_a_reloaded_tab_shows_its_strip_chart_with_axes(lab, built, page):
    if lab == "strip":
        app = App(Strip, VIEW, sim=SimConfig(fps=30.0), meta=AppMeta(title="Strip chart", description="", author="Tests", spec=SPEC))
    else:
        from ejsrl.app import load_app

        app = load_app(built("pendulum"))  # its 'Angle' plot has a 10 s window too
    server = app.serve("127.0.0.1", 0, block=False, per_client=True)
    try:
        page.add_init_script(RECORD_TEXT)
        page.goto(f"http://127.0.0.1:{server.get_port()}")
        page.get_by_role("button", name="Play").first.wait_for(timeout=45_000)
        wait_until(lambda: app.classroom is not None and len(app.classroom.sessions) == 1, what="the tab's session")
        session = next(iter(app.classroom.sessions.values()))
        page.get_by_role("button", name="Play").first.click()
        wait_until(lambda: session.app.model.t > 3.0, timeout=60, what="t to pass 3 s")
        page.reload()
        page.get_by_role("button", name="Pause").first.wait_for(timeout=45_000)

        def drawn() -> bool:
            c = _chart(page)
            return bool(c) and c["n"] > 100 and bool(c["texts"])

        wait_until(drawn, what="the reloaded chart to hold the kept data")
        n0 = _chart(page)["n"]
        wait_until(lambda: _chart(page)["n"] > n0 + 10, what="a few more points: it keeps playing")  # the window not full yet
        c = _chart(page)
        assert session.app.is_playing() and c["last"] < WINDOW - 2.0, c["last"]
        ARTIFACTS.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / f"polish_plot_reload_{lab}.png"))
        # the window is not full yet: the data from the left, the axis [first, first + window]
        lo, hi = c["first"], c["first"] + WINDOW
        assert c["min"] == pytest.approx(lo, abs=TOL) and c["max"] == pytest.approx(hi, abs=TOL), (c["min"], c["max"], lo)
        x_ticks, y_ticks = tick_labels(c["texts"])
        assert len(x_ticks) >= 2 and all(lo - TOL <= tick_number(v) <= hi + TOL for v in x_ticks), (x_ticks, lo, hi, c)
        assert len(y_ticks) >= 3, (y_ticks, c["texts"])
    finally:
        app.stop()
        server.stop()
