"""A robotics trajectory lab built with ``--web`` (examples/paper/path_planning_434): its page
shows the served panel and its 3D robot, and computes the native app's numbers to 1e-12."""

from __future__ import annotations

import csv
import io
import subprocess
import sys

import pytest

pytestmark = pytest.mark.browser


def test_path_planning_page_runs_the_native_numbers(page, web_lab) -> None:
    _site, url, app_dir = web_lab("paper/path_planning_434")
    page.goto(url)
    page.get_by_role("button", name="Play").wait_for(state="visible", timeout=120_000)
    assert page.evaluate("ejsWeb.failed") is None
    state = page.evaluate("ejsWeb.call('state')")
    assert state["error"] is None, state["error"]
    got = page.evaluate("ejsWeb.call('headless', {duration: 2})")
    assert got["status"] == 0
    out = app_dir / "native.csv"
    subprocess.run([sys.executable, str(app_dir / "app.py"), "--headless", "--duration", "2", "--csv", str(out)],
                   check=True, capture_output=True)
    web = list(csv.reader(io.StringIO(got["csv"])))
    native = list(csv.reader(io.StringIO(out.read_text())))
    assert web[0] == native[0] and len(web) == len(native) > 10
    for w, n in zip(web[1:], native[1:]):
        for a, b in zip(w, n):
            try:
                fa, fb = float(a), float(b)
            except ValueError:
                assert a == b
                continue
            assert fa == pytest.approx(fb, rel=1e-12, abs=1e-12)
