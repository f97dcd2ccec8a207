"""Plots in a real browser (Debian's Chromium), read from the pixels of their canvases and the
text drawn on them: a phase orbit drawn whole, a curve of arrays where its values put it,
readable distinct tick labels for data near 1e-5, and a log-log axis."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from testkit.browser import ARTIFACTS, hide_notifications, serving, wait_until
from testkit.charts import RECORD_TEXT, near_color, plot, plot_pixels, tick_labels, tick_number, to_px

SPEC = """\
ejs: 1
title: Plot kinds
model:
  variables:
    t: 0.0
    dt: 0.02
    theta: {value: 1.0, unit: rad}
    omega: {value: 0.0, unit: rad/s}
    xs: {expr: "np.linspace(-3, 3, 121)"}
    ys: {expr: "np.sin(xs)"}
    small: 0.0
    lx: {expr: "np.logspace(-2, 2, 41)"}
  evolution:
    - ode: {method: rk4, equations: {theta: omega, omega: -sin(theta)}}
  fixed_relations: |
    small = 1e-5*sin(3*t)
    ys = np.sin(xs + t)
view:
  - button: {label: Stop, action: pause()}
  - plot: {title: Phase, series: [{x: theta, y: omega, color: "#0000ff", label: orbit}]}
  - plot: {title: Curve, series: [{x: xs, y: ys, color: "#ff0000", label: "sin(x + t)"}]}
  - plot: {title: Small, x: t, series: [{y: small, color: "#000000"}], window: 5}
  - plot: {title: Log, x_log: true, y_log: true, series: [{x: lx, y: "lx**2", color: "#00aa00"}]}
simulation: {fps: 30, steps_per_display: 5, autoplay: true}
"""

BLUE, RED, GREEN = (0, 0, 255), (255, 0, 0), (0, 170, 0)


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    from ejsgen.cli import build

    folder = tmp_path_factory.mktemp("plot_kinds")
    spec = folder / "plot_kinds.ejs.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    return build(spec, folder / "app")


@pytest.fixture(scope="module")
def shown(lab: Path, browser_context):
    """The lab played past one period of its pendulum (6.7 s), then stopped: ``(app, page)``."""
    page = browser_context.new_page()
    page.add_init_script(RECORD_TEXT)
    with serving(lab) as (app, url):
        page.goto(url)
        page.wait_for_load_state()
        hide_notifications(page)  # at the bottom-left of a lab with no scene, over the plots' pixels
        wait_until(lambda: app.model.t > 8.0, timeout=90, what="the pendulum to swing past one period")
        page.get_by_role("button", name="Stop").first.click()
        wait_until(lambda: not app.is_playing(), what="the lab to stop")
        t = app.model.t
        wait_until(lambda: all(plot(page, title).get("drawn") for title in ("Phase", "Curve", "Small", "Log")), what="four plots drawn")
        # the last frames reach the page (the curve's phase shows the time it stopped at)
        wait_until(lambda: _curve_is_at(plot(page, "Curve"), t), what="the stopped frame")
        ARTIFACTS.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "plot_kinds.png"), full_page=True)
        yield app, page
    page.close()


def _curve_is_at(p: dict, t: float) -> bool:
    """Whether the curve the page holds is sin(x + t) (the frame of the time the lab stopped at)."""
    from ejsrl.view._plot_frame import decode_xy

    if not p.get("items"):
        return False
    xy = decode_xy(p["items"][0]["xy"], 2)
    return len(xy) == 121 and bool(np.allclose(xy[:, 1], np.sin(xy[:, 0] + t), atol=1e-5))


@pytest.mark.browser
def test_a_phase_orbit_is_drawn_whole(shown):
    app, page = shown
    p = plot(page, "Phase")
    img = plot_pixels(page, p)
    blue = near_color(img, BLUE, tol=120)
    cx, cy = to_px(page, p, 0.0, 0.0)
    right, up = blue[:, 0] > cx, blue[:, 1] < cy  # rows grow downwards
    quadrants = {"theta > 0, omega > 0": int((right & up).sum()), "theta > 0, omega < 0": int((right & ~up).sum()),
                 "theta < 0, omega > 0": int((~right & up).sum()), "theta < 0, omega < 0": int((~right & ~up).sum())}
    assert all(n > 30 for n in quadrants.values()), f"blue pixels by quadrant around the origin: {quadrants}"
    # and on the orbit: a point the pendulum passes, theta = 1 at omega = 0 (energy kept by RK4)
    x, y = to_px(page, p, 1.0, 0.0)
    assert np.hypot(blue[:, 0] - x, blue[:, 1] - y).min() <= 3.0


@pytest.mark.browser
def test_a_curve_of_arrays_is_drawn_where_its_values_put_it(shown):
    app, page = shown
    p = plot(page, "Curve")
    img = plot_pixels(page, p)
    red = near_color(img, RED, tol=120)
    t = app.model.t
    for x in (-2.5, -1.0, 0.0, 1.3, 2.5):
        px, py = to_px(page, p, x, math.sin(x + t))
        d = np.hypot(red[:, 0] - px, red[:, 1] - py).min()
        assert d <= 3.0, f"no red pixel within 3 px of sin({x} + t) at ({px:.0f}, {py:.0f}): nearest {d:.1f} px"


@pytest.mark.browser
def test_tick_labels_of_data_near_1e_5_are_distinct_and_readable(shown):
    app, page = shown
    p = plot(page, "Small")
    x_ticks, y_ticks = tick_labels(p["texts"])  # as drawn on the canvas
    assert len(y_ticks) >= 3 and len(set(y_ticks)) == len(y_ticks), f"y tick labels repeat: {y_ticks}"
    values = [tick_number(s) for s in y_ticks]
    assert values == sorted(values, reverse=True) or values == sorted(values)
    assert max(abs(v) for v in values) <= 1.2e-5 and sum(v != 0 for v in values) >= 2, y_ticks
    assert all("e\u22125" in s or s == "0" for s in y_ticks), y_ticks  # in units of 1e-5, never "0 0 -0"
    lo, hi = p["bounds"][2:]
    assert lo <= -0.9e-5 and hi >= 0.9e-5  # the axis spans the values, not +-1 around them
    assert len(x_ticks) >= 2 and all(t - 5.0 - 0.2 <= tick_number(s) <= t + 0.2 for s in x_ticks for t in [app.model.t]), x_ticks


@pytest.mark.browser
def test_a_log_log_plot_draws_a_power_law_as_a_straight_line(shown):
    app, page = shown
    p = plot(page, "Log")
    img = plot_pixels(page, p)
    green = near_color(img, GREEN, tol=120)
    points = [to_px(page, p, x, x * x) for x in (0.01, 0.1, 1.0, 10.0, 100.0)]
    for px, py in points:
        assert np.hypot(green[:, 0] - px, green[:, 1] - py).min() <= 3.0, (px, py)
    xs = [q[0] for q in points]
    ys = [q[1] for q in points]
    assert np.allclose(np.diff(xs), np.diff(xs)[0], atol=1.0)  # each decade as wide as the next
    assert np.allclose(np.diff(ys), np.diff(ys)[0], atol=1.0)  # y = x^2: a straight line on log-log
    x_ticks, y_ticks = tick_labels(p["texts"])
    assert {"0.1", "1", "10"} <= set(x_ticks), x_ticks
    assert all(math.log10(tick_number(s)) == round(math.log10(tick_number(s))) for s in y_ticks), y_ticks
