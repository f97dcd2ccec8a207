"""Classroom serving: a simulation per browser tab.

A served lab gives every tab that connects its own :class:`ejsrl.app.App` (model, control
panel, plots, images, 3D scene, play/pause and error pause), shown through viser's
per-client API (``client.gui``, ``client.scene``). :class:`Classroom` keeps the sessions:

- **Created on connect**, up to ``max_sessions`` connected at once; the next tab is told
  that the lab is full and to try again later (nobody else slows down).
- **A reload finds its session again.** viser gives a reloaded tab a new client, so each
  session has a random token that the tab's address carries (``/s/<token>/``, written
  into the address bar with ``history.replaceState``). The page at that address is the
  lab's page; its websocket connects to the same path, where the server reads the token.
  A tab closed for longer than ``grace`` seconds loses its session: it is freed.
  A copy of the address opened while its tab is still open gets a session of its own.
  Waiting for a reloading tab's old connection to close holds no thread (the tab is
  settled when the old one goes, or after :data:`RELOAD_WAIT_SECONDS`).
- **A session is bound to its browser.** The page sets a cookie naming the browser
  (:data:`ejsrl.view._guard.BROWSER_COOKIE`, HttpOnly, SameSite=Strict); a session
  resumes only on a websocket carrying the cookie of the browser that created it.
  Another browser opening the address (a projector, a shared screen) gets a lab of its
  own, and is told so. An address whose session is gone (freed after the grace period,
  or the process that held it was restarted) gets a new lab with a note saying why.
- **Idle costs nothing.** A session is stepped by the shared :class:`Scheduler` at the
  lab's frame rate while it plays, and for a moment after each change a user makes
  (to show it); a paused session, or one whose tab is gone, is not stepped at all.
- **A slow tab stalls nobody.** Frames go to a tab only once it has taken the previous
  ones (viser coalesces what is waiting); a tab that stays behind for
  :data:`DROP_AFTER_SECONDS` is disconnected with a log line (a reload brings it back).
"""

from __future__ import annotations

import asyncio
import collections
import gc
import logging
import math
import secrets
import threading
import time
from collections.abc import Callable
from typing import Any

from ejsrl.app._capacity import (  # noqa: F401 - how many sessions fit; re-exported here
    CPU_SHARE, MAX_DEFAULT_SESSIONS, SEND_SECONDS, VIEW_FACTOR, default_max_sessions, measure_frame_cost,
)
from ejsrl.app._scheduler import Scheduler, default_workers
from ejsrl.app._wake import BatchedWake
from ejsrl.view._fair import QuietLog

__all__ = ["Classroom", "Session", "default_max_sessions", "measure_frame_cost", "GRACE_SECONDS"]

log = logging.getLogger("ejsrl.serve")

#: how long a closed tab's session is kept for a reload (seconds)
GRACE_SECONDS = 60.0
#: after a change from the browser, a paused session is refreshed for this long (seconds):
#: the change shows, and a control the user held gets the model's value back
IDLE_TAIL_SECONDS = 1.0
#: messages waiting for a tab above which, at two frames running (more for labs faster than
#: 30 frames/s), its frames are skipped (the model still steps). Zero: viser keeps only the
#: newest update of each property, so a tab that cannot keep up never has more than a
#: frame's worth waiting; drawing more then only takes the GIL from the event loop that
#: must send them. With 64 the skip never fired, and 40 pendulum sessions on a busy server
#: fell to 8-10 frames/s each as the steppers starved the sender.
SKIP_BACKLOG = 0
#: ... and above which, held for DROP_AFTER_SECONDS, the tab is disconnected
DROP_BACKLOG = 256
DROP_AFTER_SECONDS = 10.0
#: the longest viser's event loop keeps a client's messages before sending them (seconds:
#: its window of 1/60 s, and a little for the loop to get the GIL)
VISER_WINDOW = 1.0 / 60.0 + 0.004
#: a tab reloading may connect before its old connection is seen to close: how long the
#: new one waits for the old one to go before it is given a session of its own (seconds)
RELOAD_WAIT_SECONDS = 2.0
#: the longest a tab's frames are held (its connection behind) before one is sent anyway
#: (seconds), unless more than DROP_BACKLOG messages wait for it (a tab that reads nothing):
#: under overload every tab still gets 5 frames a second, none is starved (one tab of 60
#: got 0.5 frames/s while the others got 12)
MAX_HOLD_SECONDS = 0.2
#: seconds over which the frames shown to a tab are counted (``app.shown_fps``)
SHOWN_WINDOW = 2.0
#: how many addresses of freed sessions are remembered (to tell their tabs why the lab is new)
FREED_MEMORY = 4096
#: seconds between GIL hand-overs while serving a class (Python's default is 5 ms): the
#: stepper threads and viser's event-loop thread share one GIL, and a frame ready to be sent
#: waited up to a whole interval for the loop to get it. With 1 ms, ``bench/classroom.py``
#: held 45 pendulum sessions at full rate instead of 35, at less CPU per session.
SWITCH_INTERVAL = 0.001


def _token_script(token: str) -> str:
    """HTML that writes the session's address into the tab's address bar (no reload)."""
    # viser's page adds ?websocket=<its websocket's address> when that address is not the
    # page's host alone: dropped, since the page at /s/<token>/ connects there anyway
    js = (
        "var p=location.pathname.replace(/s\\/[A-Za-z0-9_-]+\\/?$/,'');if(p.slice(-1)!='/')p+='/';"
        "var q=location.search.replace(/^\\?/,'').split('&amp;').filter(function(x){return x&amp;&amp;!/^websocket=/.test(x)}).join('&amp;');"
        f"history.replaceState(null,'',p+'s/{token}/'+(q?'?'+q:'')+location.hash);"
    )
    return f'<img style="display:none" alt="" src="data:," onerror="{js}">'


def _full_text(limit: int | None) -> str:
    places = "Every place is" if limit is None else ("The one place is" if limit == 1 else f"All **{limit}** places are")
    return (
        "### This lab is full\n\n"
        f"{places} taken: every student gets a simulation of their own, and this "
        "machine cannot run more without slowing everyone down.\n\n"
        "**Try again later**: reload this page in a few minutes, or ask your teacher."
    )


class Session:
    """One tab's simulation: its ``app``, the ``view`` showing it (None while the tab is
    gone) and the ``token`` its address carries."""

    def __init__(self, classroom: Classroom, token: str, client_id: int, browser: str | None = None) -> None:
        self.classroom = classroom
        self.token = token
        #: the browser that created it (its cookie; None: a client without one, a script)
        self.browser = browser
        self.client_id: int | None = client_id
        self.app: Any = None
        self.view: Any = None
        self.detached_at: float | None = None
        self.resume_playing = False
        self.awake_until = -math.inf
        self.behind_since: float | None = None
        #: frames in a row at which the tab had not been sent the frame before
        self.unsent_ticks = 0
        #: frames shown to the tab (not held) since ``shown_mark`` (clock seconds), for ``app.shown_fps``
        self.shown_frames = 0
        self.shown_mark: float | None = None
        #: when the tab was last sent a frame (clock seconds)
        self.shown_at: float | None = None
        self.freed = False
        #: serialises taking the session (a tab connecting) and leaving it (a tab closing)
        self.lock = threading.RLock()

    def wake(self) -> None:
        """A change from the browser: show it (and keep refreshing a moment)."""
        self.awake_until = self.classroom.clock() + IDLE_TAIL_SECONDS
        self.classroom.scheduler.wake(self)

    def tick(self, due: float) -> float | None:
        """One frame (the scheduler's task); when the next one is due, or None to rest."""
        app, view = self.app, self.view
        if app is None or view is None or view.closed or self.freed:
            return None
        # held when the frame before the last is still unsent too (a frame may wait a window
        # of viser's, and a camera picture takes a while to encode and send: one unsent frame
        # is ordinary), or more frames for a lab whose frames come faster than the window
        period = 1.0 / max(float(app.sim.fps), 1.0)
        backlog = self.classroom.backlog(self.client_id)
        self.unsent_ticks = self.unsent_ticks + 1 if backlog > SKIP_BACKLOG else 0
        hold = self.unsent_ticks >= 1 + math.ceil(VISER_WINDOW / period)
        if hold and backlog <= DROP_BACKLOG and self.shown_at is not None \
                and self.classroom.clock() - self.shown_at >= MAX_HOLD_SECONDS:
            hold = False  # a tab always a little behind (an overloaded server) still gets a frame now and then
        view.hold = hold
        app.frame()
        now = self.classroom.clock()
        if not hold:
            self.shown_at = now
        self._count_shown(app, now, shown=not hold)
        if not (app.is_playing() or now < self.awake_until):
            return None
        nxt = due + period
        return nxt if nxt >= now else now  # behind: no catching up, back of the queue


    def _count_shown(self, app: Any, now: float, *, shown: bool) -> None:
        """Keep ``app.shown_fps``: frames a second the tab was sent over the last
        :data:`SHOWN_WINDOW` seconds of play (None while paused), which its time readout
        reports when it is low."""
        if not app.is_playing():
            app.shown_fps, self.shown_mark = None, None
            return
        if self.shown_mark is None:
            self.shown_mark, self.shown_frames = now, 0
            return
        self.shown_frames += 1 if shown else 0
        if now - self.shown_mark >= SHOWN_WINDOW:
            app.shown_fps = self.shown_frames / (now - self.shown_mark)
            self.shown_mark, self.shown_frames = now, 0


class Classroom:
    """The sessions of a served lab (see the module docstring).

    ``make_app()`` builds a new ``App`` (not playing unless the lab autoplays); ``server``:
    a viser server from :func:`ejsrl.view.viser_view.make_server`; ``max_sessions``: tabs
    served at once; ``grace``: seconds a closed tab's session is kept for a reload;
    ``token_prefix``: what every session's token starts with (which process serves it,
    when a class is served from several: :mod:`ejsrl.app._front`).
    """

    def __init__(
        self,
        make_app: Callable[[], Any],
        server: Any,
        *,
        max_sessions: int,
        grace: float = GRACE_SECONDS,
        workers: int | None = None,
        clock: Callable[[], float] = time.monotonic,
        token_prefix: str = "",
    ) -> None:
        self.make_app = make_app
        self.token_prefix = token_prefix
        self.server = server
        self.max_sessions = max(1, int(max_sessions))
        #: the places of the whole class, which the full message gives: ``max_sessions``, or
        #: when the class is served from several processes theirs together (None: not known here)
        self.class_places: int | None = self.max_sessions
        self.grace = float(grace)
        self.clock = clock
        self.scheduler = Scheduler(workers or default_workers(), clock=clock)
        self.sessions: dict[str, Session] = {}
        self._by_client: dict[int, Session] = {}
        #: the tabs that were told the lab is full
        self.turned_away: set[int] = set()
        self.dropped_clients = 0
        self._lock = threading.RLock()
        self._stopped = threading.Event()
        self._full_log = QuietLog(log, "tabs turned away (the lab is full)")
        #: asked first about every tab that connects: False leaves the tab to the caller (a lab
        #: served with ``ejsgen run --watch`` shows a build error instead, :mod:`ejsrl.app._reload`)
        self.admit: Callable[[Any], bool] | None = None
        #: tabs waiting for their session's old connection to close: token -> [(client, browser, until)]
        self._waiting: dict[str, list[tuple[Any, str | None, float]]] = {}
        #: tokens of sessions freed after the grace period (the latest FREED_MEMORY)
        self._freed_tokens: collections.OrderedDict[str, None] = collections.OrderedDict()
        #: how many tabs were given a new lab for another browser's address (for tests and logs)
        self.other_browser = 0
        #: one wake of viser's event loop for the frames of many sessions (made with the first tab)
        self.wake: BatchedWake | None = None
        server.on_client_connect(self._connect)
        server.on_client_disconnect(self._disconnect)
        self._reaper = threading.Thread(target=self._reap_loop, name="ejsrl-sessions", daemon=True)
        self._reaper.start()

    # -- queries ---------------------------------------------------------------------------------
    def session_of(self, client_id: int) -> Session | None:
        with self._lock:
            return self._by_client.get(client_id)

    def connected(self) -> list[Session]:
        """The sessions whose tab is open."""
        with self._lock:
            return [s for s in self.sessions.values() if s.client_id is not None]

    def backlog(self, client_id: int | None) -> int:
        """How many messages wait to be sent to client ``client_id`` (0 if unknown)."""
        if client_id is None:
            return 0
        states = getattr(self.server._websock_server, "_client_state_from_id", {})  # viser 1.1's internals
        state = states.get(client_id)
        buffer = getattr(state, "message_buffer", None)
        return len(getattr(buffer, "message_from_id", ()))

    # -- connecting and leaving -------------------------------------------------------------------
    def _connect(self, client: Any) -> None:
        from ejsrl.view._guard import browser_of, session_token

        if self.admit is not None and not self.admit(client):
            return
        token = session_token(self.server, client.client_id)
        browser = browser_of(self.server, client.client_id)
        with self._lock:
            old = self.sessions.get(token) if token else None
            if old is not None and old.client_id is not None and not old.freed and old.browser == browser:
                # a reload whose old connection is still closing (or a copy of the address in the
                # same browser): settled when the old connection goes, or by the reaper
                self._waiting.setdefault(old.token, []).append((client, browser, self.clock() + RELOAD_WAIT_SECONDS))
                return
        self._settle(client, token, browser)

    def _settle(self, client: Any, token: str | None, browser: str | None) -> None:
        """Give ``client`` the session of address ``token`` if it is free and this browser's,
        else a new one (or tell it the lab is full)."""
        note: tuple[str, str] | None = None
        with self._lock:
            if client.client_id not in self._live_clients():
                return  # it left while it waited
            old = self.sessions.get(token) if token else None
            if old is not None and old.client_id is None and not old.freed and old.browser == browser:
                old.client_id = client.client_id
                old.detached_at = None
                self._by_client[client.client_id] = old
                session, fresh = old, False
            elif sum(1 for s in self.sessions.values() if s.client_id is not None) >= self.max_sessions:
                self.turned_away.add(client.client_id)
                session = None
            else:
                if token:
                    note = self._why_new(token, old)
                new_token = self.token_prefix + secrets.token_urlsafe(12)
                session = Session(self, new_token, client.client_id, browser)
                self.sessions[new_token] = session
                self._by_client[client.client_id] = session
                fresh = True
        if session is None:
            self._full_log(logging.WARNING, "full", "ejsrl: the lab is full (%s); a new tab was turned away",
                           _places(self.class_places))
            self._show_full(client)
            return
        try:
            self._attach(session, client, fresh)
        except Exception:
            log.exception("ejsrl: could not start a session")
            with self._lock:
                self._by_client.pop(client.client_id, None)
                if fresh:
                    self.sessions.pop(session.token, None)
            self._free(session)
            return
        if note is not None:
            try:
                client.add_notification(note[0], note[1], color="yellow", auto_close_seconds=None)
            except Exception:  # noqa: BLE001
                log.debug("telling a client why its lab is new failed", exc_info=True)

    def _live_clients(self) -> Any:
        """The ids of the clients viser has connected now."""
        return getattr(self.server, "_connected_clients", {})

    def _why_new(self, token: str, old: Session | None) -> tuple[str, str]:
        """What to tell a tab that opened address ``token`` and gets a new lab (lock held)."""
        if old is not None:
            self.other_browser += 1
            return ("A simulation of your own", "This address belongs to a simulation open in another browser; "
                    "this tab has a new simulation of its own.")
        if token in self._freed_tokens:
            return ("Your earlier simulation ended", f"Its tab was closed for more than {self.grace:.0f} s, so it "
                    "was freed. This is a new simulation.")
        return ("This lab was restarted", "The simulation this address had is gone: the lab (or the copy of it "
                "that ran your simulation) was restarted, or the address belongs to another server of the "
                "class. This is a new simulation.")

    def _settle_waiting(self, token: str, *, expired_only: bool) -> None:
        """Settle the tabs waiting for session ``token``: all of them (its old connection has
        closed: the first gets it), or those whose wait is over."""
        now = self.clock()
        with self._lock:
            queue = self._waiting.get(token, [])
            ready = [w for w in queue if not expired_only or w[2] <= now]
            rest = [w for w in queue if w not in ready]
            if rest:
                self._waiting[token] = rest
            else:
                self._waiting.pop(token, None)
        for client, browser, _until in ready:
            self._settle(client, token, browser)

    def _attach(self, session: Session, client: Any, fresh: bool) -> None:
        from ejsrl.app._slow import telling
        from ejsrl.view.viser_view import ViserView

        with session.lock:
            if fresh:
                with telling(lambda title, body: [client.add_notification(title, body, color="yellow", loading=True)]):
                    app = self.make_app()  # a slow init: is said in the tab too
                app.on_wake = session.wake
                session.app = app
            app = session.app
            if app is None:  # freed meanwhile
                return
            old_view = session.view
            if old_view is not None and not old_view.closed:  # the old tab's leaving is not handled yet
                self._close_view(session, old_view)
            self._batch_wakes(client.client_id)
            view = ViserView(app, self.server, client=client)
            client.gui.add_html(_token_script(session.token))
            with app.lock:
                if old_view is not None:
                    view.adopt(old_view)
                app.views = [view]
                session.view = view
                if session.resume_playing and app.error is None:
                    app.playing = True
                session.resume_playing = False
        with self._lock:
            gone = session.client_id != client.client_id
        if gone:  # the tab closed while its panel was being built
            self._detach(session, client.client_id)
            return
        log.info("ejsrl: %s session %s… (%d connected)", "new" if fresh else "reconnected",
                 session.token[:6], len(self.connected()))
        session.wake()

    def _batch_wakes(self, client_id: int) -> None:
        """Send the client's frames through the class's one batched wake of viser's event loop
        (:mod:`ejsrl.app._wake`); nothing when viser's internals are not the expected ones."""
        state = getattr(self.server._websock_server, "_client_state_from_id", {}).get(client_id)  # viser 1.1's internals
        buffer = getattr(state, "message_buffer", None)
        loop = getattr(buffer, "event_loop", None)
        if buffer is None or loop is None:
            return
        with self._lock:
            if self.wake is None:
                self.wake = BatchedWake(loop)
        self.wake.install(buffer)

    def _disconnect(self, client: Any) -> None:
        with self._lock:
            self.turned_away.discard(client.client_id)
            for token, queue in list(self._waiting.items()):
                kept = [w for w in queue if w[0].client_id != client.client_id]
                if len(kept) != len(queue):
                    if kept:
                        self._waiting[token] = kept
                    else:
                        del self._waiting[token]
            session = self._by_client.pop(client.client_id, None)
            if session is None:
                return
            if session.client_id == client.client_id:
                session.client_id = None
                session.detached_at = self.clock()
        self._detach(session, client.client_id)
        if session.token in self._waiting:  # a reload of this tab waits for it: settle it now
            self._settle_waiting(session.token, expired_only=False)

    def _detach(self, session: Session, client_id: int) -> None:
        """Client ``client_id`` is gone: stop stepping its session, keep it for a reload."""
        with session.lock:
            view = session.view
            if view is None or view.closed or view.client is None or view.client.client_id != client_id:
                return  # not its view (a reload was quicker), or already done
            self.scheduler.remove(session)
            self._close_view(session, view)
        # the closed view is kept until a reload takes its plots over, or the session is freed
        self._trim_detached()

    @staticmethod
    def _close_view(session: Session, view: Any) -> None:
        """Pause the session (remembering whether it played) and close ``view``."""
        app = session.app
        with app.lock:
            session.resume_playing = bool(app.playing)
            app.playing = False
            view.close()
            app.views = [v for v in app.views if v is not view]

    def _show_full(self, client: Any) -> None:
        try:
            client.gui.set_panel_label("This lab is full")
            client.gui.add_markdown(_full_text(self.class_places))
            client.add_notification("This lab is full", "Try again later: reload this page in a few minutes.",
                                    color="yellow", auto_close_seconds=None)
        except Exception:
            log.debug("telling a client the lab is full failed", exc_info=True)

    # -- freeing ------------------------------------------------------------------------------------
    def _trim_detached(self) -> None:
        """Keep at most ``max_sessions`` closed tabs' sessions (the oldest go first)."""
        with self._lock:
            detached = sorted((s for s in self.sessions.values() if s.client_id is None and s.detached_at is not None),
                              key=lambda s: s.detached_at)
            extra = detached[: max(0, len(detached) - self.max_sessions)]
            for s in extra:
                self.sessions.pop(s.token, None)
        for s in extra:
            self._free(s)

    def _free(self, session: Session) -> None:
        with session.lock:
            session.freed = True
            self.scheduler.remove(session)
            app, view, session.app, session.view = session.app, session.view, None, None
            if view is not None:
                view.close()
            if app is not None:
                app.on_wake = None
                app.views = []

    def _reap_loop(self) -> None:
        while not self._stopped.wait(0.25):
            try:
                self.reap()
            except Exception:  # noqa: BLE001
                log.exception("ejsrl: looking after the sessions failed")

    def reap(self) -> int:
        """Free the sessions of tabs closed longer than ``grace``, and disconnect tabs that
        stay behind; returns how many sessions were freed."""
        now = self.clock()
        with self._lock:
            expired = [s for s in self.sessions.values()
                       if s.client_id is None and s.detached_at is not None and now - s.detached_at > self.grace]
            for s in expired:
                self.sessions.pop(s.token, None)
                self._freed_tokens[s.token] = None
            while len(self._freed_tokens) > FREED_MEMORY:
                self._freed_tokens.popitem(last=False)
            live = [s for s in self.sessions.values() if s.client_id is not None]
            waited = [t for t, q in self._waiting.items() if any(w[2] <= now for w in q)]
        for token in waited:
            self._settle_waiting(token, expired_only=True)
        for s in expired:
            self._free(s)
        if expired:
            gc.collect()
            _trim_heap()
            log.info("ejsrl: freed %d session(s) of closed tabs", len(expired))
        for s in live:
            cid = s.client_id
            backlog = self.backlog(cid)
            if backlog <= DROP_BACKLOG:
                s.behind_since = None
                continue
            if s.behind_since is None:
                s.behind_since = now
            elif now - s.behind_since > DROP_AFTER_SECONDS and cid is not None:
                s.behind_since = None
                self.dropped_clients += 1
                log.warning("ejsrl: disconnected a tab that stayed behind (%d messages waiting for %.0f s); "
                            "a reload brings its session back", backlog, DROP_AFTER_SECONDS)
                self._close_connection(cid)
        return len(expired)

    def _close_connection(self, client_id: int) -> None:
        ws = self.server._websock_server
        connection = ws._live_connections.get(client_id)
        loop = getattr(ws, "_background_event_loop", None)
        if connection is None or loop is None:
            return
        try:
            asyncio.run_coroutine_threadsafe(connection.close(1008, "the tab fell behind"), loop)
        except RuntimeError:
            pass

    def stop(self) -> None:
        self._stopped.set()
        self.scheduler.stop()
        with self._lock:
            sessions = list(self.sessions.values())
            self.sessions.clear()
            self._by_client.clear()
        for s in sessions:
            self._free(s)


def _places(n: int | None) -> str:
    return "every place taken" if n is None else ("1 place" if n == 1 else f"{n} places")


def _trim_heap() -> None:
    """Give freed memory back to the system (glibc keeps it otherwise)."""
    try:
        import ctypes

        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except Exception:  # noqa: BLE001 - not glibc: nothing to do
        pass
