"""A slow ``init:`` is said in the page of the tab whose simulation it holds up, with its spec line.

Before, a served lab whose ``init:`` ran long (a new tab's simulation, or Restart after a
student set a value that makes it loop) showed an empty or frozen page with no word of why;
only the terminal named the line. Now the tab shows a notification that names the spec line
while the code runs, and it goes away when the code ends.
"""

from __future__ import annotations

import re
import time
from pathlib import Path

import pytest
from testkit.browser import wait_until

SPEC = """\
ejs: 1
title: Slow start
imports:
  - import time
model:
  variables:
    t: 0.0
    dt: 0.1
    x: 1.0
    wait_s: 0.0
    until: 0.0
    n: 0
  init: |
    until = time.monotonic() + wait_s
    n = 0
    while time.monotonic() < until:
        n = n + 1
  evolution:
    - ode:
        equations:
          x: -x
view:
  - slider: {bind: wait_s, min: 0, max: 20, label: "Start-up time (s)"}
  - button: {label: Restart, action: initialize()}
"""
WAIT_S = 8.0  # each init: of the test's lab; the page is told after 1 s
TITLE = "The simulation is still starting"


@pytest.fixture
def slow_lab(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    from ejsrl.app import _slow, load_app

    from ejsgen.cli import build

    monkeypatch.setattr(_slow, "SLOW_SECONDS", 1.0)
    spec = tmp_path / "slow_start.ejs.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    app = load_app(build(spec, tmp_path / "app"), overrides={"wait_s": WAIT_S})  # as --set wait_s=8 serves it
    server = app.serve("127.0.0.1", 0, block=False, per_client=True, max_sessions=4)
    yield app, f"http://127.0.0.1:{server.get_port()}", spec
    app.stop()
    server.stop()


def _notice(page):
    return page.locator(".mantine-Notification-root", has_text=TITLE)


def _check_text(text: str, spec: Path) -> None:
    found = re.search(r"is at (\S+):(\d+):(\d+) now", text)
    assert found, text
    assert found.group(1) == spec.name
    assert SPEC.splitlines()[int(found.group(2)) - 1].strip() in ("while time.monotonic() < until:", "n = n + 1"), text
    assert "init: has been running for 1 s" in text and "Ctrl+C in the terminal that serves the lab stops it" in text


@pytest.mark.browser
def test_a_slow_init_is_named_in_the_tab_while_it_runs_and_the_note_goes_when_it_ends(slow_lab, page) -> None:
    app, url, spec = slow_lab
    # a new tab: its simulation's init: runs for 8 s before the panel can show
    page.goto(url)
    notice = _notice(page)
    notice.wait_for(state="visible", timeout=60_000)
    _check_text(notice.inner_text(), spec)
    page.get_by_role("button", name="Restart").wait_for(timeout=60_000)  # the init: ended: the panel is there
    notice.wait_for(state="detached")  # and the note went with it

    # Restart runs init: again (with the student's 8 s): the same note, gone when it ends
    sessions = app.classroom.connected()
    assert len(sessions) == 1
    model = sessions[0].app.model
    n_before = model.n
    page.get_by_role("button", name="Restart").click()
    notice.wait_for(state="visible")
    _check_text(notice.inner_text(), spec)
    t0 = time.monotonic()
    notice.wait_for(state="detached", timeout=60_000)
    wait_until(lambda: model.n != n_before, what="the restarted init: to have counted its own laps")
    assert time.monotonic() - t0 < 60
