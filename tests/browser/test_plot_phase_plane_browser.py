"""The phase-plane example in Chromium: the damped orbit spirals through all four quadrants
around the rest point, the separatrix and the nullcline are drawn from their arrays, the
energy's logarithmic axis is ticked at powers of ten, and the histogram's bars count the
angles the pendulum went through (as ``numpy.histogram`` counts the same values)."""

from __future__ import annotations

import numpy as np
import pytest

from testkit.browser import close_notifications, save_shot, serving, settled, wait_until
from testkit.charts import RECORD_TEXT, near_color, plot, plot_pixels, tick_labels, tick_number, to_px

ROYALBLUE = (65, 105, 225)
GREY = (153, 153, 153)


@pytest.mark.browser
def test_the_phase_plane_lab_draws_its_orbit_curves_energy_and_histogram(built, page):
    from ejsrl.view._plot_frame import decode_xy

    page.add_init_script(RECORD_TEXT)
    with serving(built("phase_plane")) as (app, url):
        page.goto(url)
        wait_until(lambda: app.model.t > 6.0, timeout=90, what="the pendulum to spiral for 6 s")
        app.pause()
        wait_until(lambda: all(plot(page, title).get("drawn") for title in ("Phase plane", "Energy", "Time spent at each angle")),
                   timeout=30, what="the three plots drawn")
        settled(lambda: [{k: v for k, v in plot(page, title).items() if k != "drawn"} for title in ("Phase plane", "Energy")],
                what="the paused frame to reach the page")
        close_notifications(page)

        phase = plot(page, "Phase plane")
        img = plot_pixels(page, phase)
        blue = near_color(img, ROYALBLUE, tol=90)
        cx, cy = to_px(page, phase, 0.0, 0.0)
        right, up = blue[:, 0] > cx, blue[:, 1] < cy
        counts = [int((right & up).sum()), int((right & ~up).sum()), int((~right & up).sum()), int((~right & ~up).sum())]
        assert min(counts) > 20, f"orbit pixels by quadrant around (0, 0): {counts}"
        grey = near_color(img, GREY, tol=40)
        top = to_px(page, phase, 0.0, 2 * np.sqrt(app.model.g / app.model.L))  # the separatrix' highest point
        assert np.hypot(grey[:, 0] - top[0], grey[:, 1] - top[1]).min() <= 3.0

        energy = plot(page, "Energy")
        assert energy["y"]["log"]
        _, y_ticks = tick_labels(energy["texts"])
        assert len(y_ticks) >= 2 and len(set(y_ticks)) == len(y_ticks), y_ticks
        values = sorted(tick_number(s) for s in y_ticks)
        lo, hi = energy["bounds"][2:]
        assert all(lo <= v <= hi for v in values), (y_ticks, lo, hi)
        # the log axis' labels never touch: 11 px text at least 12 px apart on the canvas
        rows = sorted(t[2] for t in energy["texts"] if t[0] in y_ticks)
        assert min(b - a for a, b in zip(rows, rows[1:])) >= 12, (y_ticks, rows)
        # and one sits near each end of the axis (within 30 % of its decades)
        span = np.log10(hi / lo)
        assert np.log10(values[0] / lo) <= 0.3 * span and np.log10(hi / values[-1]) <= 0.3 * span, (y_ticks, lo, hi)

        hist = plot(page, "Time spent at each angle")
        bars = decode_xy([it for it in hist["items"] if it["t"] == "rects"][0]["xy"], 4)
        assert len(bars) == 30 and bars[:, 3].sum() > 100
        thetas = app.views[0].panel.plots[2].traces[0].data()[:, 0]  # the angles the histogram holds
        assert len(thetas) == bars[:, 3].sum()
        assert bars[:, 3].tolist() == np.histogram(thetas, bins=30)[0].tolist()
        save_shot(page, "phase_plane")
