"""``ejsgen run --watch`` served in this process to raw viser websocket clients: a save
reloads the open tab in place (same session token, values the author did not change kept,
still playing), a broken save shows the error (escaped) instead of the lab, also to a tab
that connects meanwhile, and the next good save brings every lab back."""

from __future__ import annotations

import html
import io
import re
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ejsgen._watch import Rebuilder, Watcher
from ejsrl.app._reload import LiveLab
from testkit.guard_client import CAMERA, Client, gui_update, run_async

SPEC = """\
ejs: 1
title: Live spring
model:
  variables:
    t: 0.0
    dt: 0.01
    x: {{value: 1.0, unit: m}}
    v: 0.0
    k: {{value: 4.0, unit: N/m}}
    p: {{value: 0.0, doc: grows at 1 per second while playing}}
    s: {s}
  evolution:
    - ode:
        equations:
          x: v
          v: -k*x
          p: 1.0
view:
  - slider: {{bind: k, min: 0.5, max: {kmax}, label: Stiffness}}
  - label: {{text: "{word}: p={{p:.2f}} s={{s:.2f}}"}}
  - plot: {{title: Position, x: t, series: [{{y: x, label: x}}], window: 10}}
  - scene:
      - sphere: {{position: [x, 0, 0], radius: 0.1}}
simulation:
  fps: 30
"""

BROKEN = SPEC.replace("v: -k*x", "v: -k*xx  # <img src=x onerror=alert(1)>")


def validate_text(spec: Path) -> str:
    from ejsgen.cli import load_plan
    from ejsgen.errors import EjsError

    with pytest.raises(EjsError) as info:
        load_plan(spec)
    return str(info.value)


def shown_texts(client: Client) -> list[str]:
    """The Markdown and HTML of the client's panel as they read now (created, then updated), unescaped."""
    current: dict[str, str] = {}
    for m in client.received:
        if m.get("type") in ("GuiMarkdownMessage", "GuiHtmlMessage"):
            props = m.get("props", {})
            current[m["uuid"]] = str(props.get("_markdown", props.get("content", "")))
        elif m.get("type") == "GuiUpdateMessage" and m.get("uuid") in current:
            for key in ("_markdown", "content"):
                if key in m["updates"]:
                    current[m["uuid"]] = str(m["updates"][key])
    return [html.unescape(t) for t in current.values()]


def last_uuid(client: Client, kind: str, label: str) -> str:
    """The uuid of the newest control of ``kind`` labelled ``label`` (a reload makes new ones)."""
    found = [m["uuid"] for m in client.received if m.get("type") == kind and m.get("props", {}).get("label") == label]
    assert found, f"no {kind} labelled {label!r}"
    return found[-1]


def token_of(client: Client) -> str:
    for text in client.texts():
        match = re.search(r"s/([A-Za-z0-9_-]{8,64})/'", text)
        if match:
            return match.group(1)
    raise AssertionError("no session address was sent")


@pytest.fixture
def live(tmp_path: Path):
    spec = tmp_path / "live.ejs.yaml"
    spec.write_text(SPEC.format(s=0.5, kmax=20, word="Before"))
    rebuilder = Rebuilder(spec, tmp_path / "builds", [])
    first = rebuilder.rebuild()
    assert first.build is not None, first.error
    lab = LiveLab(max_sessions=4, grace=30.0)
    out, err = io.StringIO(), io.StringIO()
    watcher = Watcher(rebuilder, lab, first, log=out, err=err)
    server = lab.start("127.0.0.1", 0)
    watcher.start(first)
    yield spec, lab, watcher, server, out, err
    lab.stop()


def save(spec: Path, text: str) -> None:
    spec.write_text(text)


def poll_until(watcher: Watcher, want: str, timeout: float = 10.0) -> None:
    """Let the watcher look at the files until a look gives ``want``."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if watcher.poll_once() == want:
            return
        time.sleep(0.05)
    raise AssertionError(f"the watcher never reported {want!r}")


async def open_tab(server: Any, path: str = "") -> Client:
    client = await Client.open(server.get_port(), server=server, path=path)
    await client.until(lambda: any("history.replaceState" in t or "does not build" in t for t in client.texts()),
                       "the panel", timeout=30)
    return client


def test_a_save_reloads_the_tab_in_place_keeping_what_the_author_did_not_change(live) -> None:
    spec, lab, watcher, server, out, _err = live

    async def scenario() -> None:
        tab = await open_tab(server)
        token = token_of(tab)
        session = lab.classroom.sessions[token]
        await tab.send(gui_update(last_uuid(tab, "GuiSliderMessage", "Stiffness"), value=7.0))
        await tab.until(lambda: abs(session.app.model.k - 7.0) < 0.2, "the user's stiffness")  # on the slider's steps
        k_user = session.app.model.k
        await tab.send(gui_update(last_uuid(tab, "GuiButtonMessage", "Play"), value=True))
        await tab.until(lambda: session.app.model.p > 0.5, "p to grow while playing")
        old_app = session.app
        # the user turned the 3D view: the reload keeps it there (a new view would frame the scene)
        await tab.send(dict(CAMERA, position=[4.0, -2.0, 1.5], look_at=[0.5, 0.0, 0.2]))
        camera = server.get_clients()[session.client_id].camera
        await tab.until(lambda: np.allclose(camera.position, [4.0, -2.0, 1.5]), "the user's camera")

        save(spec, SPEC.format(s=2.5, kmax=50, word="After"))
        p_saved, t_saved = old_app.model.p, old_app.model.t
        poll_until(watcher, "rebuilt")
        new_app = session.app
        assert new_app is not old_app and lab.classroom.sessions[token] is session  # the same session, a new model
        assert not old_app.is_playing() and new_app.is_playing()  # still playing
        assert new_app.model.s == 2.5  # its initial value changed: the new one
        assert new_app.model.k == k_user  # set by the user, declaration unchanged: kept
        await tab.until(lambda: new_app.model.p > p_saved + 0.3, "p to go on from where it was")
        assert new_app.model.t >= p_saved  # the independent variable kept too
        # the tab was sent the new panel: the new label, the slider's new range
        await tab.until(lambda: any(t.startswith("After: p=") for t in shown_texts(tab)), "the new label")
        sliders = [m for m in tab.received if m.get("type") == "GuiSliderMessage"
                   and m.get("props", {}).get("label") == "Stiffness"]
        assert sliders[-1]["props"]["max"] == 50 and sliders[0]["props"]["max"] == 20
        assert sliders[-1]["value"] == k_user  # the new slider shows the kept value
        assert token_of(tab) == token and len(lab.classroom.sessions) == 1
        # the strip chart (its expressions unchanged) kept the points from before the save
        x_points = session.view.panel.plots[0].buffer.data()[0]
        assert x_points[0] < t_saved - 0.3 and x_points[-1] > t_saved
        assert np.allclose(camera.position, [4.0, -2.0, 1.5]) and np.allclose(camera.look_at, [0.5, 0.0, 0.2])
        moved = [m for m in tab.received if m.get("type") == "SetCameraPositionMessage"]
        assert moved and np.allclose(moved[-1]["position"], [4.0, -2.0, 1.5])  # what the tab was told last
        line = out.getvalue().strip().splitlines()[-1]
        assert "1 tab reloaded" in line and "new initial values: s" in line, line
        outcome, report, since_save = watcher.last_report
        assert outcome.seconds + report.seconds < 1.0, line  # the rebuild: spec to the new model running
        await tab.close()

    run_async(scenario())


def test_a_broken_save_shows_the_error_instead_of_the_lab_until_a_good_one(live) -> None:
    spec, lab, watcher, server, out, err = live

    async def scenario() -> None:
        tab = await open_tab(server)
        token = token_of(tab)
        session = lab.classroom.sessions[token]
        await tab.send(gui_update(last_uuid(tab, "GuiButtonMessage", "Play"), value=True))
        await tab.until(lambda: session.app.model.p > 0.3, "playing")

        save(spec, BROKEN.format(s=0.5, kmax=20, word="Before"))
        poll_until(watcher, "error")
        await tab.until(lambda: any("does not build" in t for t in tab.texts()), "the error page")
        page = [t for t in tab.texts() if "does not build" in t][-1]
        validate = validate_text(spec)  # what `ejsgen validate` prints
        assert re.fullmatch(rf"{re.escape(str(spec))}:\d+:\d+: error: unknown name 'xx'; did you mean 'x'\?", validate)
        assert html.escape(validate, quote=True) in page
        assert "v: -k*xx  # &lt;img src=x onerror=alert(1)&gt;" in page  # the offending line, as text
        assert "<img src=x" not in page
        assert validate in err.getvalue()  # the terminal prints it too
        p_paused = session.app.model.p
        assert not session.app.is_playing()

        # a tab opened meanwhile gets the error too, then a lab of its own
        late = await open_tab(server)
        await late.until(lambda: any("does not build" in t for t in late.texts()), "the late tab's error page")
        assert len(lab.classroom.sessions) == 1

        save(spec, SPEC.format(s=0.5, kmax=20, word="Fixed"))
        poll_until(watcher, "rebuilt")
        await tab.until(lambda: any(t.startswith("Fixed: p=") for t in shown_texts(tab)), "the lab back")
        await late.until(lambda: any(t.startswith("Fixed: p=") for t in shown_texts(late)), "the late tab's lab")
        assert token_of(tab) == token and len(lab.classroom.sessions) == 2
        app = lab.classroom.sessions[token].app
        assert app.is_playing() and app.model.p >= p_paused  # it plays on from where it was
        await tab.close()
        await late.close()

    run_async(scenario())


def test_half_a_save_is_not_reported(live, monkeypatch) -> None:
    """An editor that writes the file in two steps: the first half fails to build, the
    second lands before the error would be shown; the tab never sees an error."""
    spec, lab, watcher, server, _out, err = live
    text = SPEC.format(s=0.5, kmax=20, word="Whole")
    cut = text.index("  evolution:")
    shown: list[str] = []
    monkeypatch.setattr(lab, "show_error", lambda report: shown.append(report) or 0)

    def sleep(seconds: float) -> None:
        if seconds >= 0.2 and spec.read_text() != text:  # the wait before an error is shown
            spec.write_text(text)
        time.sleep(0.01)

    watcher.sleep = sleep
    spec.write_text(text[:cut] + "  evol")
    assert watcher.poll_once() == "again"
    assert shown == [] and err.getvalue() == ""
    poll_until(watcher, "rebuilt")
    assert shown == [] and lab.error is None


def test_a_spec_broken_from_the_start_shows_its_error_then_its_lab(tmp_path: Path) -> None:
    spec = tmp_path / "live.ejs.yaml"
    spec.write_text(BROKEN.format(s=0.5, kmax=20, word="Before"))
    rebuilder = Rebuilder(spec, tmp_path / "builds", [])
    first = rebuilder.rebuild()
    assert first.build is None and "unknown name 'xx'" in (first.error or "")
    lab = LiveLab(max_sessions=4)
    watcher = Watcher(rebuilder, lab, first, log=io.StringIO(), err=io.StringIO())
    server = lab.start("127.0.0.1", 0)
    watcher.start(first)
    try:
        async def scenario() -> None:
            tab = await open_tab(server)
            await tab.until(lambda: any("does not build" in t for t in tab.texts()), "the error page")
            assert not lab.classroom.sessions
            save(spec, SPEC.format(s=0.5, kmax=20, word="Good"))
            poll_until(watcher, "rebuilt")
            await tab.until(lambda: any(t.startswith("Good: p=") for t in shown_texts(tab)), "the lab")
            assert len(lab.classroom.sessions) == 1
            await tab.close()

        run_async(scenario())
    finally:
        lab.stop()
