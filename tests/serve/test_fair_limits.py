"""The limits a served app puts on one client (issue #30), through raw viser websocket
clients: connections per address, a deadline to register, messages paced with only the
latest value per control, sessions bound to their browser, and the note a tab gets when
its address's session is gone."""

from __future__ import annotations

import asyncio
import re
import time

import pytest
from websockets.exceptions import InvalidStatus

from ejsrl.view import _fair
from testkit.classroom import join, served_classroom, token_of
from testkit.guard_client import CAMERA, Client, gui_update, run_async


@pytest.fixture
def classroom(request):
    options = dict(max_sessions=6, grace=30.0)
    options.update(getattr(request, "param", {}))
    with served_classroom(**options) as served:
        yield served


async def tab(server, path: str = "", cookie: str | None = None) -> Client:
    return await join(server.get_port(), path, cookie)


def test_connections_from_one_address_are_capped_and_the_refusal_logged_once(monkeypatch, caplog):
    monkeypatch.setattr(_fair, "MAX_PER_ADDRESS", 3)

    async def scenario(server) -> None:
        port = server.get_port()
        mine = [await Client.open(port, camera=False) for _ in range(3)]
        for _ in range(5):
            with pytest.raises(InvalidStatus) as refused:
                await Client.open(port, camera=False)
            assert refused.value.response.status_code == 429
            assert b"Too many connections" in refused.value.response.body
        # another address is not affected (127.0.0.2 is loopback too)
        other = await Client.open(port, source="127.0.0.2", server=server)
        await other.until(lambda: token_of(other) is not None, "the other address's panel", timeout=30)
        # a closed connection gives its place back
        await mine[0].close()
        again = None
        deadline = time.monotonic() + 10
        while again is None:
            try:
                again = await Client.open(port, camera=False)
            except InvalidStatus:
                assert time.monotonic() < deadline, "the closed connection's place was never given back"
                await asyncio.sleep(0.1)
        for c in [*mine[1:], other, again]:
            await c.close()

    with served_classroom(max_sessions=4) as (_app, server), caplog.at_level("WARNING", logger="ejsrl.serve"):
        run_async(scenario(server))
    lines = [r.getMessage() for r in caplog.records if "refused websockets from" in r.getMessage()]
    assert lines == ["ejsrl: refused websockets from 127.0.0.1: it has 3 open (the most from one address)"]


def test_a_websocket_that_never_registers_is_closed(monkeypatch):
    monkeypatch.setattr(_fair, "REGISTER_SECONDS", 1.0)

    async def scenario(server) -> float:
        idle = await Client.open(server.get_port(), camera=False)
        page = await Client.open(server.get_port(), server=server)  # registers at once: stays
        t = time.monotonic()
        await idle.until(lambda: idle.closed is not None, "the idle websocket to be closed", timeout=10)
        waited = time.monotonic() - t
        await asyncio.sleep(1.5)
        assert page.closed is None
        await page.close()
        return waited

    with served_classroom(max_sessions=2) as (_app, server):
        waited = run_async(scenario(server))
    assert 0.5 <= waited <= 3.0


def test_a_flood_of_values_is_paced_and_only_the_latest_counts(classroom):
    """5,000 values sent at once: the model ends on the last one, and most were replaced by a
    newer one before viser saw them."""
    import msgspec

    from ejsrl.view._guard import guard_of

    app, server = classroom
    guard = guard_of(server)

    async def scenario() -> None:
        evil = await tab(server)
        session = app.classroom.sessions[token_of(evil)]
        length = evil.uuid_of("GuiSliderMessage", "Length")
        for i in range(5000):
            await evil.ws.send(msgspec.msgpack.encode(gui_update(length, value=0.5 + (i % 15) / 10)))
        await evil.send(gui_update(length, value=1.3))
        await Client.until(lambda: abs(session.app.model.L - 1.3) < 1e-9, "the last value to reach the model",
                           timeout=30)
        await evil.settle(0.5)
        assert abs(session.app.model.L - 1.3) < 1e-9  # no older value arrived after it
        await evil.close()

    run_async(scenario())
    assert guard.dropped.get("replaced by a newer value", 0) >= 4000, guard.dropped


def test_a_session_resumes_only_in_the_browser_that_created_it(classroom):
    app, server = classroom

    async def scenario() -> None:
        mine = await tab(server, cookie="a" * 24)
        token = token_of(mine)
        length = mine.uuid_of("GuiSliderMessage", "Length")
        await mine.send(gui_update(length, value=1.7))
        await Client.until(lambda: app.classroom.sessions[token].app.model.L == 1.7, "the student's value")
        await mine.close()
        await Client.until(lambda: app.classroom.sessions[token].client_id is None, "the tab to be gone")
        # a projector (another browser) opening the address within the grace period: a lab of its own
        other = await tab(server, f"/s/{token}", cookie="b" * 24)
        assert token_of(other) != token
        await Client.until(lambda: any("another browser" in n for n in other.notifications()), "the note", timeout=10)
        assert app.classroom.sessions[token_of(other)].app.model.L == 1.0
        # ... and so does a script with no cookie
        script = await tab(server, f"/s/{token}")
        assert token_of(script) not in (token, token_of(other))
        # the student's own browser finds its simulation again
        back = await tab(server, f"/s/{token}", cookie="a" * 24)
        assert token_of(back) == token and app.classroom.sessions[token].app.model.L == 1.7
        assert back.notifications() == []
        for c in (other, script, back):
            await c.close()

    run_async(scenario(), timeout=120)


@pytest.mark.parametrize("classroom", [dict(grace=0.5)], indirect=True)
def test_a_tab_whose_session_is_gone_is_told_why(classroom):
    app, server = classroom

    async def scenario() -> None:
        first = await tab(server, cookie="c" * 24)
        token = token_of(first)
        await first.close()
        await Client.until(lambda: token not in app.classroom.sessions, "the session to be freed", timeout=10)
        late = await tab(server, f"/s/{token}", cookie="c" * 24)
        assert token_of(late) != token
        # the note follows the panel (a window of viser's later): waited for, not raced
        await Client.until(lambda: any("Your earlier simulation ended" in n and "closed for more than" in n
                                       for n in late.notifications()), "the note", timeout=10)
        # an address this server never gave (its process was restarted since): told the lab was restarted
        restarted = await tab(server, "/s/NeverGivenToken1234/", cookie="d" * 24)
        await Client.until(lambda: any("This lab was restarted" in n for n in restarted.notifications()), "the note", timeout=10)
        for c in (late, restarted):
            await c.close()

    run_async(scenario(), timeout=60)


def test_a_reload_waiting_for_its_old_connection_holds_no_thread(classroom):
    """Forty copies of a live address (same browser) wait for it without parking viser's
    thread pool: a new tab meanwhile gets its panel at once."""
    app, server = classroom

    async def scenario() -> float:
        owner = await tab(server, cookie="e" * 24)
        token = token_of(owner)
        copies = []
        for _ in range(40):
            c = await Client.open(server.get_port(), path=f"/s/{token}", cookie="e" * 24, camera=False)
            await c.send(CAMERA)
            copies.append(c)
        await asyncio.sleep(0.2)
        assert len(app.classroom._waiting.get(token, [])) >= 30
        t = time.monotonic()
        newcomer = await tab(server, cookie="f" * 24)
        took = time.monotonic() - t
        assert token_of(newcomer) is not None
        # the owner's tab closes: the first copy takes the session over, at once
        await owner.close()
        await Client.until(lambda: any(token_of(c) == token for c in copies), "a copy to resume the session",
                           timeout=10)
        for c in [*copies, newcomer]:
            await c.close()
        return took

    took = run_async(scenario(), timeout=120)
    assert took < 1.5, took


def test_a_tab_shown_few_frames_is_told_so(classroom, monkeypatch):
    """A tab whose frames are held (its connection cannot take them) at 2 of 5 frames shown
    reads about 12 frames/s in its time readout; a tab shown every frame reads nothing of it."""
    app, server = classroom
    slow_ids: set[int] = set()
    ticks: dict[int, int] = {}
    original = type(app.classroom).backlog

    def backlog(self, client_id):
        if client_id in slow_ids:
            ticks[client_id] = ticks.get(client_id, 0) + 1
            return 0 if ticks[client_id] % 5 == 0 else 10
        return original(self, client_id)

    monkeypatch.setattr(type(app.classroom), "backlog", backlog)

    def readouts(client: Client) -> list[str]:
        out = []
        for m in client.received:
            if m.get("type") in ("GuiUpdateMessage", "GuiMarkdownMessage"):
                text = str(m.get("updates", m.get("props", {})).get("_markdown", ""))
                if text.startswith("**t** ="):
                    out.append(text)
        return out

    async def scenario() -> None:
        slow, quick = await tab(server), await tab(server)
        slow_ids.add(app.classroom.sessions[token_of(slow)].client_id)
        for c in (slow, quick):
            await c.send(gui_update(c.uuid_of("GuiButtonMessage", "Play"), value=True))
        await slow.until(lambda: any("frames/s" in t for t in readouts(slow)), "the slow tab's note", timeout=20)
        note = next(t for t in readouts(slow) if "frames/s" in t)
        shown = float(re.search(r"showing (\d+) frames/s \(the server is busy\)", note).group(1))
        assert 8 <= shown <= 16, note
        assert not any("frames/s" in t for t in readouts(quick))
        for c in (slow, quick):
            await c.close()

    run_async(scenario(), timeout=60)


def test_a_tab_always_behind_is_not_starved(classroom, monkeypatch):
    """A tab whose connection is always a little behind (an overloaded server) still gets a
    frame every 0.2 s, and its readout says how few; before, it could get 0.5 frames/s."""
    from ejsrl.app import _sessions

    app, server = classroom
    behind: set[int] = set()
    original = type(app.classroom).backlog
    monkeypatch.setattr(type(app.classroom), "backlog",
                        lambda self, cid: 10 if cid in behind else original(self, cid))

    def times(client: Client) -> list[str]:
        """The texts of the time readout the client was sent (with the note on frames, if any)."""
        out = []
        for m in client.received:
            text = str(m.get("updates", m.get("props", {})).get("_markdown", "")) \
                if m.get("type") in ("GuiUpdateMessage", "GuiMarkdownMessage") else ""
            if re.match(r"\*\*t\*\* = ([-+0-9.eE]+)", text):
                out.append(text)
        return out

    async def scenario() -> None:
        slow = await tab(server)
        behind.add(app.classroom.sessions[token_of(slow)].client_id)
        await slow.send(gui_update(slow.uuid_of("GuiButtonMessage", "Play"), value=True))
        await asyncio.sleep(1.0)
        before = len(times(slow))
        await asyncio.sleep(3.0)
        got = len(times(slow)) - before
        assert 3 * 3 <= got <= 3 * 1.2 / _sessions.MAX_HOLD_SECONDS + 3, got  # about 5 a second, not 0.5
        await slow.until(lambda: any("showing 5 frames/s" in t or "showing 4 frames/s" in t or
                                     "showing 6 frames/s" in t for t in times(slow)), "the note", timeout=10)
        await slow.close()

    run_async(scenario(), timeout=60)


def test_a_link_from_another_site_keeps_the_browsers_name(classroom):
    """A page reached from another site (a course page's link) is sent without the
    SameSite=Strict cookie: it is given no new one (which would replace the browser's own),
    and a browser's websocket without a name is named on the handshake's response."""
    import http.client

    app, server = classroom
    port = server.get_port()

    def page(headers: dict[str, str]):
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
        conn.request("GET", "/", headers={"Host": f"127.0.0.1:{port}", **headers})
        r = conn.getresponse()
        r.read()
        conn.close()
        return r.headers.get("Set-Cookie")

    assert page({"Sec-Fetch-Site": "cross-site"}) is None
    assert "ejsrl_browser=" in page({"Sec-Fetch-Site": "none"})
    assert page({"Cookie": "ejsrl_browser=" + "g" * 24}) is None

    async def scenario() -> None:
        origin = f"http://127.0.0.1:{port}"
        first = await Client.open(port, origin=origin)
        cookie_line = first.ws.response.headers.get("Set-Cookie", "")
        name = re.match(r"ejsrl_browser=([A-Za-z0-9_-]+); Path=/; HttpOnly; SameSite=Strict", cookie_line).group(1)
        await first.until(lambda: token_of(first) is not None, "the panel", timeout=30)
        token = token_of(first)
        assert app.classroom.sessions[token].browser == name
        await first.close()
        await Client.until(lambda: app.classroom.sessions[token].client_id is None, "the tab to be gone")
        # the browser comes back with the name it was given: its session
        back = await Client.open(port, origin=origin, path=f"/s/{token}", cookie=name)
        assert "Set-Cookie" not in back.ws.response.headers
        await back.until(lambda: token_of(back) is not None, "the panel", timeout=30)
        assert token_of(back) == token
        await back.close()

    run_async(scenario(), timeout=60)
