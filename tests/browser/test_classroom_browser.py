"""Classroom serving in a real browser: two or three tabs on one served lab, each with its own simulation."""

from __future__ import annotations

import re

import pytest

from testkit.browser import wait_until
from testkit.browser_lab import make_app
from testkit.classroom import served_classroom
from testkit.served import Served


#: a loaded machine (several WebGL pages on software rendering) needs patience
SLOW = 120_000


@pytest.fixture
def classroom(request):
    """The browser lab served with a simulation per tab (at most 2 tabs, or ``request.param``);
    yields ``(app, url)``."""
    with served_classroom(max_sessions=getattr(request, "param", 2), grace=30.0) as (app, server):
        yield app, f"http://127.0.0.1:{server.get_port()}"


def open_tab(context, url: str):
    """A new tab on ``url``, once its panel is there and its address carries its session."""
    page = front(context.new_page())
    page.goto(url)
    page.get_by_text("Length").first.wait_for(timeout=SLOW)
    wait_until(lambda: "/s/" in address(page), what="the tab's address to carry its session")
    return page


def front(page):
    """``page`` as the tab in front (a loaded machine starves background tabs), slow actions allowed."""
    page.bring_to_front()
    page.set_default_timeout(SLOW)
    return page


def address(page) -> str:
    """What the address bar shows (``page.url`` misses ``history.replaceState``)."""
    return page.evaluate("location.href")


def session_of(app, page):
    token = re.search(r"/s/([A-Za-z0-9_-]+)/", address(page)).group(1)
    return app.classroom.sessions[token]


@pytest.mark.browser
def test_each_tab_drives_only_its_own_simulation(classroom, browser_context):
    app, url = classroom
    a = open_tab(browser_context, url)
    b = open_tab(browser_context, url)
    try:
        sa, sb = session_of(app, a), session_of(app, b)
        assert sa is not sb and sa.app.model is not sb.app.model

        # a slider moved in tab A changes A's simulation; tab B's slider and model stay
        front(a)
        slider_a = a.get_by_role("slider").first
        slider_a.focus()
        slider_a.press("End")
        wait_until(lambda: abs(sa.app.model.L - 2.0) < 1e-9, what="L == 2 in A's simulation")
        front(b)
        b.wait_for_timeout(500)
        assert sb.app.model.L == 1.0
        assert b.get_by_role("slider").first.get_attribute("aria-valuenow") == "1"

        # Play in A plays A only: B's time stays 0 and its button still says Play
        front(a)
        a.get_by_role("button", name="Play").click()
        a.get_by_role("button", name="Pause").wait_for()
        wait_until(lambda: sa.app.model.t > 0.3, what="A's time to run")
        assert sb.app.model.t == 0.0 and not sb.app.is_playing()
        front(b)
        b.get_by_role("button", name="Play").wait_for()

        # a user-code error in B pauses B and shows there; A keeps playing and shows nothing
        b.get_by_role("button", name="Break it").click()
        b.locator("b", has_text="Error at pendulum.ejs.yaml:27:7").wait_for()
        assert sb.app.error is not None and sa.app.error is None
        t_a = sa.app.model.t
        wait_until(lambda: sa.app.model.t > t_a + 0.2, what="A to keep playing after B's error")
        front(a)
        a.get_by_role("button", name="Pause").wait_for()
        assert a.locator("b", has_text="Error at").count() == 0
        assert a.locator(".mantine-Notification-title", has_text="Error at").count() == 0

        # Step in B (after Reset) moves B alone by one step
        front(b)
        b.get_by_role("button", name="Reset").click()
        wait_until(lambda: sb.app.error is None, what="B's Reset")
        b.get_by_role("button", name="Step").click()
        wait_until(lambda: abs(sb.app.model.t - 0.02) < 1e-9, what="one step in B")
    finally:
        a.close()
        b.close()


@pytest.mark.browser
def test_a_reload_within_the_grace_period_keeps_the_session(classroom, browser_context):
    app, url = classroom
    a = open_tab(browser_context, url)
    try:
        session = session_of(app, a)
        slider = a.get_by_role("slider").first
        slider.focus()
        slider.press("End")
        a.get_by_role("button", name="Play").click()
        wait_until(lambda: session.app.model.t > 0.5, what="the simulation to run")
        a.get_by_role("button", name="Pause").click()
        wait_until(lambda: not session.app.is_playing(), what="the pause")
        t = session.app.model.t
        points = len(session.view.panel.plots[0].buffer)
        assert points > 10
        before = address(a)

        a.reload()
        a.get_by_text("Length").first.wait_for(timeout=SLOW)
        wait_until(lambda: session.view is not None and session.client_id is not None, what="the session to be taken back")
        assert address(a).split("?")[0] == before.split("?")[0]  # the same session address
        assert session_of(app, a) is session and len(app.classroom.sessions) == 1
        # what the student sees: the slider where they left it, the same time, the plot's points
        wait_until(lambda: a.get_by_role("slider").first.get_attribute("aria-valuenow") == "2", what="the slider at 2")
        a.get_by_text(f"{t:.6g}", exact=False).first.wait_for()
        assert session.app.model.t == t and session.app.model.L == 2.0
        assert len(session.view.panel.plots[0].buffer) >= points
    finally:
        a.close()


@pytest.mark.browser
@pytest.mark.parametrize("classroom", [1], indirect=True)
def test_the_tab_after_the_last_place_is_told_the_lab_is_full(classroom, browser_context):
    app, url = classroom
    a = open_tab(browser_context, url)
    b = front(browser_context.new_page())
    try:
        b.goto(url)
        b.get_by_text("This lab is full").first.wait_for()
        assert b.get_by_text("Try again later", exact=False).first.is_visible()
        assert b.get_by_text("Length").count() == 0  # no panel: no simulation was made for it
        assert len(app.classroom.sessions) == 1
        # the student who has the place keeps it
        front(a).get_by_role("button", name="Play").click()
        wait_until(lambda: session_of(app, a).app.model.t > 0.2, what="A to play")
    finally:
        for p in (a, b):
            p.close()


@pytest.mark.browser
def test_shared_serving_still_shares_one_simulation(browser_context):
    app = make_app()
    server = app.serve("127.0.0.1", 0, block=False)  # what --shared serves
    url = f"http://127.0.0.1:{server.get_port()}"
    a = b = None
    try:
        a = browser_context.new_page()
        b = browser_context.new_page()
        for p in (a, b):
            front(p).goto(url)
            p.get_by_text("Length").first.wait_for(timeout=SLOW)
        slider = front(a).get_by_role("slider").first
        slider.focus()
        slider.press("End")
        wait_until(lambda: abs(app.model.L - 2.0) < 1e-9, what="L == 2")
        front(b)
        wait_until(lambda: b.get_by_role("slider").first.get_attribute("aria-valuenow") == "2", what="B's slider to follow A's")
        front(a).get_by_role("button", name="Play").click()
        front(b).get_by_role("button", name="Pause").wait_for()
        assert "/s/" not in address(a)
    finally:
        for p in (a, b):
            if p is not None:
                p.close()
        app.stop()
        server.stop()


def shown_time(page) -> float:
    """The simulated time the tab's panel shows (its time readout)."""
    text = page.evaluate("Array.from(document.querySelectorAll('p')).map(p=>p.textContent)"
                         ".filter(t=>/^t = [-0-9.e]+/.test(t))[0]||''")
    return float(text.split("=")[1].split()[0]) if "=" in text else float("nan")


@pytest.mark.browser
def test_tabs_served_from_two_processes_each_run_their_own_simulation(built, tmp_path, browser_context):
    """``python app.py`` as a teacher runs it, from two processes: a tab in each, through the front."""
    server = Served(built("pendulum"), tmp_path, "--processes", "2", "--max-sessions", "4", "--grace", "30")
    url = f"http://127.0.0.1:{server.port}"
    a = b = None
    try:
        a, b = open_tab(browser_context, url), open_tab(browser_context, url)
        token = lambda page: re.search(r"/s/([A-Za-z0-9_-]+)/", address(page)).group(1)  # noqa: E731
        assert sorted(token(p)[:2] for p in (a, b)) == ["0x", "1x"]  # one in each process

        front(a).get_by_role("button", name="Play").click()
        a.get_by_role("button", name="Pause").wait_for()
        wait_until(lambda: shown_time(a) > 0.5, what="A's time to run")
        front(b)
        b.get_by_role("button", name="Play").wait_for()
        assert shown_time(b) == 0.0  # B's simulation did not move

        # A reloads: its own simulation again, from where it was
        front(a).get_by_role("button", name="Pause").click()
        a.get_by_role("button", name="Play").wait_for()
        t = shown_time(a)
        before = token(a)
        a.reload()
        a.get_by_text("Length").first.wait_for(timeout=SLOW)
        wait_until(lambda: "/s/" in address(a), what="the address to carry the session")
        assert token(a) == before
        wait_until(lambda: shown_time(a) == t, what=f"the time shown before the reload ({t})")
    finally:
        for p in (a, b):
            if p is not None:
                p.close()
        server.stop()


@pytest.mark.browser
def test_a_session_resumes_only_in_the_browser_that_created_it(classroom, browser_context):
    """Issue #30: the address alone no longer takes a closed tab's simulation over (a projector,
    a copied link): the browser's cookie must match. Another browser is played by this one with
    its cookies cleared (and given back afterwards)."""
    app, url = classroom
    a = open_tab(browser_context, url)
    other = mine = gone = None
    saved = []
    try:
        cookie = next(c for c in browser_context.cookies() if c["name"] == "ejsrl_browser")
        assert cookie["httpOnly"] and cookie["sameSite"] == "Strict"
        assert "ejsrl_browser" not in a.evaluate("document.cookie")  # the page's scripts cannot read it
        session = session_of(app, a)
        slider = a.get_by_role("slider").first
        slider.focus()
        slider.press("End")
        wait_until(lambda: abs(session.app.model.L - 2.0) < 1e-9, what="L == 2")
        where = address(a).split("?")[0]
        a.close()
        wait_until(lambda: session.client_id is None, what="the tab to be gone")

        saved = browser_context.cookies()
        browser_context.clear_cookies()  # another browser, the same address
        other = front(browser_context.new_page())
        other.goto(where)
        other.get_by_text("Length").first.wait_for(timeout=SLOW)
        other.locator(".mantine-Notification-title", has_text="A simulation of your own").wait_for()
        wait_until(lambda: "/s/" in address(other) and address(other).split("?")[0] != where,
                   what="the other browser's own address")
        assert session_of(app, other) is not session
        assert other.get_by_role("slider").first.get_attribute("aria-valuenow") == "1"
        other.close()
        other = None

        browser_context.clear_cookies()
        browser_context.add_cookies(saved)  # the student's own browser again
        mine = front(browser_context.new_page())
        mine.goto(where)
        mine.get_by_text("Length").first.wait_for(timeout=SLOW)
        wait_until(lambda: session.client_id is not None, what="the student's session to be taken back")
        assert address(mine).split("?")[0] == where
        wait_until(lambda: mine.get_by_role("slider").first.get_attribute("aria-valuenow") == "2",
                   what="the slider where the student left it")
        assert mine.locator(".mantine-Notification-title", has_text="A simulation of your own").count() == 0

        # an address this lab never gave (it was restarted since): the page says so
        gone = front(browser_context.new_page())
        gone.goto(f"{url}/s/NeverGivenToken1234/")
        gone.locator(".mantine-Notification-title", has_text="This lab was restarted").wait_for()
    finally:
        for p in (other, mine, gone):
            if p is not None:
                p.close()
        if saved and not any(c["name"] == "ejsrl_browser" for c in browser_context.cookies()):
            browser_context.add_cookies(saved)
