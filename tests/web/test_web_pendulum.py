"""The pendulum built with ``ejsgen build --web``, in Chromium from a plain static server: no
Python server anywhere, the lab's Python runs in the page (issue #32).

What a teacher and a student notice: the page loads within the issue's times and download
size, shows the served app's panel, Play runs at the lab's rate, a slider changes the
simulation as it does served (same validation, same clamping), and the numbers are the
native app's to 1e-12.
"""

from __future__ import annotations

import sys
import time

import pytest

from testkit.csvcompare import assert_same_csv, native_csv
from testkit.web_page import visit

pytestmark = pytest.mark.browser

#: bytes over the wire of a first visit (issue #32's limit)
FIRST_VISIT_BYTES = 30_000_000
#: seconds to a usable panel that would mean the page is broken, not slow: the issue's targets
#: (cold <= 10 s, warm <= 3 s on an idle machine) are timed by bench/web.py, since a test run
#: shares the machine with another worker's Chromium
USABLE_S = 90.0


def state(page, *names: str) -> dict:
    return page.evaluate("(names) => ejsWeb.call('state', {vars: names})", list(names))


@pytest.fixture(scope="module")
def pendulum(web_lab):
    return web_lab("pendulum")


def test_pendulum_page_loads_within_the_download_limit_cold_and_warm(browser_context, pendulum) -> None:
    site, url, _app = pendulum
    page = browser_context.new_page()
    try:
        cold, received = visit(page, url, cold=True, text="Length (m)")
        failed = page.evaluate("ejsWeb.failed")
        assert failed is None, failed
        page.goto("about:blank")
        warm, _ = visit(page, url, cold=False, text="Length (m)")
        timing = page.evaluate("ejsWeb.timing")
    finally:
        page.close()
    print(f"cold {cold:.1f} s, warm {warm:.1f} s, first visit {received / 1e6:.1f} MB over the wire "
          f"(site says {site.download_bytes / 1e6:.1f} MB); warm timing {timing}")
    assert received <= FIRST_VISIT_BYTES, f"a first visit downloaded {received / 1e6:.1f} MB"
    assert received >= 0.9 * site.download_bytes  # the count saw the worker's downloads too
    assert cold <= USABLE_S and warm <= USABLE_S, f"cold {cold:.1f} s, warm {warm:.1f} s"


def test_play_runs_at_the_lab_rate_and_the_readout_follows(page, pendulum, until) -> None:
    _site, url, _app = pendulum
    page.goto(url)
    play = page.get_by_role("button", name="Play")
    play.wait_for(state="visible", timeout=120_000)
    sim = page.evaluate("ejsWeb.sim")
    dt = state(page, "dt")["values"]["dt"]
    asked = dt * sim["steps"] * sim["fps"]  # model time per wall second the lab asks for
    play.click()
    page.get_by_role("button", name="Pause").wait_for(state="visible")
    until(page, "() => ejsWeb.call('state').then(s => s.t > 0.2)")  # playing, settled
    first, t0 = state(page), time.monotonic()
    time.sleep(3.0)
    last, t1 = state(page), time.monotonic()
    rate = (last["t"] - first["t"]) / (t1 - t0)
    print(f"model time advanced {rate:.3f} per second; the lab asks {asked:.3f}")
    if rate < 0.95 * asked:
        # a machine too busy to give the page the CPU it needs (the suite beside CPU-bound
        # processes): the lab cannot keep its rate there, and must say so in its time readout
        # with the speed it runs at, as a served lab says it of its server
        import re

        note = page.get_by_text("% speed (the browser is busy)").first
        note.wait_for(state="visible", timeout=30_000)
        said = int(re.search(r"running at (\d+)% speed", note.inner_text()).group(1)) / 100
        assert abs(said - rate / asked) <= 0.08, (said, rate / asked)
    readout = page.get_by_text("t =").first.inner_text()
    shown = float(readout.split("=")[1].split()[0])
    assert shown >= first["t"]  # the panel's time readout moves with the model


def test_a_slider_changes_the_model_as_served(page, pendulum, until) -> None:
    from ejsrl.view._validate import validate_control

    _site, url, app_dir = pendulum
    page.goto(url)
    page.get_by_role("button", name="Play").wait_for(state="visible", timeout=120_000)
    sys.path.insert(0, str(app_dir))
    try:
        import importlib

        app = importlib.import_module("app")
    finally:
        sys.path.remove(str(app_dir))
    damping = next(e for e in app.VIEW if getattr(e, "bind", None) == "b")
    box = page.get_by_role("textbox").nth(1)  # the Damping slider's number box (Length's is the first)
    # viser's client rounds a typed value to the slider's step (0.01) before sending it, served
    # as in the page: "0.537" reaches the lab as 0.53, "5" as 5, which the lab clamps to 1
    for typed, sent in (("0.537", 0.53), ("5", 5.0)):
        expected = validate_control(damping, sent)  # the served app's check: typing, clamping, step
        assert expected.ok
        box.fill(typed)
        box.press("Enter")
        box.blur()
        until(page, "(v) => ejsWeb.call('state', {vars: ['b']}).then(s => Math.abs(s.values.b - v) < 1e-12)",
              expected.value)
    energy_before = state(page, "E")["values"]["E"]
    page.get_by_role("button", name="Play").click()
    until(page, "() => ejsWeb.call('state').then(s => s.t > 1.0)")
    assert state(page, "E")["values"]["E"] < energy_before  # damped at the new rate


def test_the_page_computes_the_native_apps_numbers(page, pendulum) -> None:
    _site, url, app_dir = pendulum
    page.goto(url)
    page.get_by_role("button", name="Play").wait_for(state="visible", timeout=120_000)
    got = page.evaluate("ejsWeb.call('headless', {duration: 5})")
    assert got["status"] == 0
    assert_same_csv(got["csv"], native_csv(app_dir, 5), more_rows_than=400)
