"""Classroom serving through real viser websocket clients: a simulation per client, its
lifecycle (reload within the grace period, freeing, the full lab), idle sessions that cost
nothing, and a client that falls behind."""

from __future__ import annotations

import logging
import re

import pytest

from ejsrl.app import _sessions
from testkit.browser_lab import make_app
from testkit.guard_client import Client, gui_update, run_async


@pytest.fixture
def classroom(request):
    """The browser lab served with a simulation per client; ``request.param``: serve's options."""
    options = dict(max_sessions=3, grace=30.0)
    options.update(getattr(request, "param", {}))
    app = make_app()
    server = app.serve("127.0.0.1", 0, block=False, per_client=True, **options)
    yield app, server
    app.stop()
    server.stop()


def token_of(client: Client) -> str:
    """The session token the server wrote into the client's address (its panel's script)."""
    for text in client.texts():
        match = re.search(r"s/([A-Za-z0-9_-]{8,64})/'", text)
        if match:
            return match.group(1)
    raise AssertionError("no session address was sent")


async def connect(server, path: str = "") -> Client:
    client = await Client.open(server.get_port(), server=server, path=path)
    await client.until(lambda: any("history.replaceState" in t for t in client.texts()) or
                       any("lab is full" in t for t in client.texts()), "the panel", timeout=30)
    return client


def test_each_client_gets_and_drives_its_own_simulation(classroom):
    app, server = classroom

    async def scenario():
        a, b = await connect(server), await connect(server)
        sa, sb = app.classroom.sessions[token_of(a)], app.classroom.sessions[token_of(b)]
        assert sa is not sb and sa.app.model is not sb.app.model
        # each client was sent a panel of its own: its controls have their own uuids
        assert a.uuid_of("GuiSliderMessage", "Length") != b.uuid_of("GuiSliderMessage", "Length")
        assert b.uuid_of("GuiSliderMessage", "Length") not in {m.get("uuid") for m in a.received}

        await a.send(gui_update(a.uuid_of("GuiSliderMessage", "Length"), value=1.7))
        await a.until(lambda: sa.app.model.L == 1.7, "A's length")
        await a.send(gui_update(a.uuid_of("GuiButtonMessage", "Play"), value=True))
        await a.until(lambda: sa.app.model.t > 0.3, "A to play")
        assert sb.app.model.L == 1.0 and sb.app.model.t == 0.0 and not sb.app.is_playing()
        # B's client never heard of A's slider value
        assert 1.7 not in b.values_of(b.uuid_of("GuiSliderMessage", "Length"))

        # a user-code error in B pauses B alone and is shown to B alone
        await b.send(gui_update(b.uuid_of("GuiButtonMessage", "Break it"), value=True))
        await b.until(lambda: any("Error at pendulum.ejs.yaml:27:7" in n for n in b.notifications()), "B's error")
        t = sa.app.model.t
        await a.until(lambda: sa.app.model.t > t + 0.2, "A to keep playing")
        assert sa.app.error is None and sb.app.error is not None
        assert not any("Error" in n for n in a.notifications())
        await a.close()
        await b.close()

    run_async(scenario())


def test_a_paused_session_costs_nothing_and_a_playing_one_runs_at_its_frame_rate(classroom):
    app, server = classroom

    async def scenario():
        a, b = await connect(server), await connect(server)
        sa, sb = app.classroom.sessions[token_of(a)], app.classroom.sessions[token_of(b)]
        await a.send(gui_update(a.uuid_of("GuiButtonMessage", "Play"), value=True))
        await a.settle(_sessions.IDLE_TAIL_SECONDS + 0.5)  # B's refresh after connecting is over
        frames_a, _ = app.classroom.scheduler.stats(sa)
        frames_b, _ = app.classroom.scheduler.stats(sb)
        await a.settle(2.0)
        ran_a = app.classroom.scheduler.stats(sa)[0] - frames_a
        ran_b = app.classroom.scheduler.stats(sb)[0] - frames_b
        assert ran_b == 0, f"a paused session ran {ran_b} frames"
        assert ran_a >= 20, f"a playing session ran {ran_a} frames in 2 s (30 fps asked)"
        await a.close()
        await b.close()

    run_async(scenario())


@pytest.mark.parametrize("classroom", [dict(max_sessions=2, grace=1.0)], indirect=True)
def test_a_reconnect_within_the_grace_period_finds_its_session_then_it_is_freed(classroom):
    app, server = classroom

    async def scenario():
        a = await connect(server)
        token = token_of(a)
        session = app.classroom.sessions[token]
        await a.send(gui_update(a.uuid_of("GuiSliderMessage", "Length"), value=1.5))
        await a.until(lambda: session.app.model.L == 1.5, "the length")
        await a.close()
        await a.until(lambda: session.client_id is None, "the session to be left")

        again = await connect(server, f"/s/{token}")
        await again.until(lambda: session.client_id is not None, "the session to be taken back")
        assert token_of(again) == token and app.classroom.sessions[token] is session
        # its new panel shows the state it had
        assert again.shown("GuiSliderMessage", "Length") == 1.5
        await again.close()
        await again.until(lambda: token not in app.classroom.sessions, "the session to be freed after the grace period",
                          timeout=10)
        assert session.app is None  # its model is let go

        # an unknown or expired token gets a new session
        late = await connect(server, f"/s/{token}")
        assert token_of(late) != token
        await late.close()

    run_async(scenario())


@pytest.mark.parametrize("classroom", [dict(max_sessions=1)], indirect=True)
def test_the_client_after_the_last_place_is_told_the_lab_is_full(classroom):
    app, server = classroom

    async def scenario():
        a = await connect(server)
        full = await connect(server)
        assert any("This lab is full" in t and "Try again later" in t for t in full.texts())
        assert any("The one place is taken" in t for t in full.texts())  # (not "All 1 places")
        assert not full.seen("GuiSliderMessage")  # no panel, no simulation
        assert len(app.classroom.sessions) == 1
        await full.close()
        await a.close()
        await a.until(lambda: not app.classroom.connected(), "A to leave")
        b = await connect(server)  # a place is free again
        assert b.shown("GuiSliderMessage", "Length") == 1.0 and not any("lab is full" in t for t in b.texts())
        await b.close()

    run_async(scenario())


def test_a_client_that_falls_behind_stalls_nobody_and_is_disconnected(classroom, monkeypatch, caplog):
    app, server = classroom
    monkeypatch.setattr(_sessions, "DROP_AFTER_SECONDS", 1.0)
    slow_ids: set[int] = set()
    real_backlog = app.classroom.backlog
    # a client that reads nothing: as if its messages piled up (what viser's buffer would hold)
    monkeypatch.setattr(app.classroom, "backlog",
                        lambda cid: 10 * _sessions.DROP_BACKLOG if cid in slow_ids else real_backlog(cid))

    async def scenario():
        a, b = await connect(server), await connect(server)
        sa, sb = app.classroom.sessions[token_of(a)], app.classroom.sessions[token_of(b)]
        slow_ids.add(sa.client_id)
        for c in (a, b):
            await c.send(gui_update(c.uuid_of("GuiButtonMessage", "Play"), value=True))
        sent_a = sa.view.frames
        await b.until(lambda: sb.app.model.t > 0.5, "B to play on")
        assert sa.view.frames <= sent_a + 1 and sa.view.skipped > 0  # A's frames are skipped ...
        assert sa.app.model.t > 0.2  # ... not its simulation
        assert len(sa.view.panel.plots[0].buffer) > 10  # nor its plot's points
        with caplog.at_level(logging.WARNING, logger="ejsrl.serve"):
            await a.until(lambda: a.closed is not None, "the slow client to be disconnected", timeout=15)
        assert any("stayed behind" in r.getMessage() for r in caplog.records)
        assert b.closed is None and sb.app.is_playing()
        await b.close()

    run_async(scenario())


def test_serving_a_class_hands_the_gil_over_often(classroom):
    """The stepper threads and viser's event loop share the GIL: at Python's 5 ms hand-over
    a frame ready to be sent waits for the loop, and 35 pendulum sessions held full rate
    where 45 do at 1 ms (bench/classroom.py)."""
    import sys

    assert sys.getswitchinterval() <= _sessions.SWITCH_INTERVAL


def test_a_session_whose_last_frame_is_unsent_skips_drawing_the_next(classroom, monkeypatch):
    """On a busy server the event loop may not have sent a tab's last frame when the next is
    due: that session's model steps on but its view is not refreshed until the frame before
    has gone out (drawing it would only take time from the sender)."""
    app, server = classroom
    waiting: dict[int, int] = {}
    real_backlog = app.classroom.backlog
    monkeypatch.setattr(app.classroom, "backlog", lambda cid: waiting.get(cid, real_backlog(cid)))

    async def scenario():
        a = await connect(server)
        sa = app.classroom.sessions[token_of(a)]
        await a.send(gui_update(a.uuid_of("GuiButtonMessage", "Play"), value=True))
        await a.until(lambda: sa.view.frames > 5, "A to play")
        waiting[sa.client_id] = 1  # one message of the last frame still waits
        await a.settle(0.1)
        frames, skipped, t = sa.view.frames, sa.view.skipped, sa.app.model.t
        await a.until(lambda: sa.view.skipped > skipped + 5, "frames to be skipped")
        assert sa.view.frames <= frames + 1 and sa.app.model.t > t  # not drawn, still stepping
        del waiting[sa.client_id]  # sent
        await a.until(lambda: sa.view.frames > frames + 5, "A to be drawn again")
        await a.close()

    run_async(scenario())


def test_a_tab_closing_mid_frame_puts_no_warning_in_the_teachers_terminal(classroom):
    """viser warns once per closed connection that a frame drawn for it "will never be
    delivered": a tab closing while its session draws is ordinary in a class, so a served
    class does not show it (other warnings still do)."""
    import threading
    import warnings

    caught: list[str] = []

    def draw_for_a_closed_tab() -> None:
        with warnings.catch_warnings(record=True) as w:
            warnings.warn("Queued a GuiUpdateMessage on a closed connection (e.g. via a handle owned by a "
                          "disconnected client); it will never be delivered.", UserWarning)
            warnings.warn("something else", UserWarning)
            caught.extend(str(x.message) for x in w)

    thread = threading.Thread(target=draw_for_a_closed_tab)
    thread.start()
    thread.join()
    assert caught == ["something else"]
