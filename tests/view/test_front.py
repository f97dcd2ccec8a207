"""A class served from several processes (``--processes N``, by default one per core): the
front relays each tab to a worker process; every guarantee of one process holds through it.

The apps run as a teacher runs them (``python app.py``); raw viser clients play students."""

from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import sys
import time

import pytest
from websockets.exceptions import InvalidStatus

from ejsrl.app._front import Front, default_processes, split_places, worker_command
from testkit.guard_client import Client, gui_update, run_async
from testkit.served import Served, alive, cpu_seconds

_READOUT = re.compile(r"^\*\*t\*\* = ([-+0-9.eE]+)")


# -- routing, without processes ----------------------------------------------------------------------


def ready_front(places: list[int]) -> Front:
    front = Front(["true"], "127.0.0.1", 0, count=len(places), max_sessions=sum(places))
    for w, p in zip(front.workers, places):
        w.ready, w.places, w.port = True, p, 1000 + w.index
    return front


def test_a_session_address_goes_to_the_process_named_in_its_token():
    front = ready_front([2, 2, 2])
    assert front.route("/s/2xAbCdEfGhIjKl/", websocket=True) is front.workers[2]
    assert front.route("/s/1xAbCdEfGhIjKl/?x=1", websocket=False) is front.workers[1]
    assert front.route("/s/1xAbCdEfGhIjKl", websocket=True) is front.workers[1]
    # a token naming no process (another server's, or made up) is a new tab
    front.workers[0].tabs = 1
    assert front.route("/s/7xAbCdEfGhIjKl/", websocket=True) is front.workers[1]
    # ... and so is a session whose process is starting again
    front.workers[2].ready = False
    assert front.route("/s/2xAbCdEfGhIjKl/", websocket=True) is front.workers[1]


def test_a_new_tab_goes_to_the_least_full_process_and_files_go_in_turn():
    front = ready_front([2, 1])
    chosen = []
    for _ in range(3):
        w = front.route("/", websocket=True)
        w.tabs += 1
        chosen.append(w.index)
    assert chosen == [0, 1, 0]  # the least full first: the class spreads over the cores
    assert front.route("/", websocket=True).index == 0  # all full: the first tells the tab so
    files = [front.route("/assets/index.js", websocket=False).index for _ in range(4)]
    assert sorted(files) == [0, 0, 1, 1]
    for w in front.workers:
        w.ready = False
    assert front.route("/", websocket=True) is None


def test_places_are_shared_evenly_and_processes_follow_the_cores():
    assert split_places(5, 2) == [3, 2] and split_places(7, 3) == [3, 2, 2] and split_places(2, 2) == [1, 1]
    with pytest.raises(ValueError):
        split_places(1, 3)
    assert default_processes(1) == 1 and default_processes(2) == 2 and default_processes(64) == 8


def test_the_workers_are_started_with_the_apps_own_command_line(monkeypatch, tmp_path):
    app = tmp_path / "app.py"
    app.write_text("")
    monkeypatch.setattr(sys, "argv", [str(app), "--port", "9000"])
    monkeypatch.setattr(sys, "orig_argv", ["python3", "-P", "-X", "utf8", str(app), "--port", "9000"])
    assert worker_command() == [sys.executable, "-P", "-X", "utf8", str(app), "--port", "9000"]
    # run as a module or a command string: nothing to start again
    monkeypatch.setattr(sys, "orig_argv", ["python3", "-m", "lab", "--port", "9000"])
    monkeypatch.setattr(sys, "argv", [str(app), "--port", "9000"])
    assert worker_command() is None
    monkeypatch.setattr(sys, "argv", ["-c"])
    monkeypatch.setattr(sys, "orig_argv", ["python3", "-c", "pass"])
    assert worker_command() is None


def test_a_process_that_cannot_start_is_reported_and_retried_later(caplog):
    front = Front([sys.executable, "-c", "import sys; sys.exit(3)"], "127.0.0.1", 0, count=1, max_sessions=None)
    with pytest.raises(RuntimeError, match=r"serving process 0 did not start \(it ended with status 3\)"):
        front.start()
    worker = front.workers[0]
    worker.ready = True  # as if it had served, then died
    with caplog.at_level("WARNING", logger="ejsrl.serve"):
        front.supervise()
    assert "serving process 0 stopped (status 3); starting a new one" in caplog.text
    assert "did not start (it ended with status 3); trying again in 10 s" in caplog.text
    tried = worker.proc
    front.supervise()  # within the wait: no new process
    assert worker.proc is tried and not worker.ready
    worker.retry_at = 0.0
    front.supervise()
    assert worker.proc is not tried


# -- a served lab ------------------------------------------------------------------------------------


def token_of(client: Client) -> str | None:
    for text in client.texts():
        match = re.search(r"s/([A-Za-z0-9_-]{8,64})/'", text)
        if match:
            return match.group(1)
    return None


def sim_time(client: Client) -> float | None:
    """The latest simulated time the student's panel shows."""
    found = None
    for m in client.received:
        if m.get("type") in ("GuiUpdateMessage", "GuiMarkdownMessage"):
            data = m.get("updates", m.get("props", {}))
            match = _READOUT.match(str(data.get("_markdown", data.get("content", ""))))
            if match:
                found = float(match.group(1))
    return found


async def student(port: int, path: str = "") -> Client:
    client = await Client.open(port, path=path)
    await client.until(lambda: token_of(client) is not None or "This lab is full" in " ".join(client.texts()),
                       "the panel", timeout=90)
    return client


async def play(client: Client) -> None:
    uuid = next(m["uuid"] for m in client.received if m.get("type") == "GuiButtonMessage" and m["props"]["label"] == "Play")
    await client.send(gui_update(uuid, value=True))


@pytest.fixture(scope="module")
def served(built, tmp_path_factory):
    server = Served(built("pendulum"), tmp_path_factory.mktemp("front"), "--processes", "2", "--max-sessions", "3", "--grace", "30")
    yield server
    server.stop()


def test_a_class_is_served_from_two_processes_that_both_run_simulations(served):
    assert "up to 3 at once from 2 processes" in served.out.read_text()
    workers = served.children()
    assert len(workers) == 2

    async def scenario() -> None:
        a, b = await student(served.port), await student(served.port)
        try:
            # one tab in each process: the class spreads over the cores
            assert sorted(token_of(c)[:2] for c in (a, b)) == ["0x", "1x"], [token_of(a), token_of(b)]
            before = [cpu_seconds(p) for p in workers]
            await play(a)
            await play(b)
            await Client.until(lambda: all((sim_time(c) or 0) > 1.0 for c in (a, b)), "both simulations to run", timeout=60)
            used = [cpu_seconds(p) - c0 for p, c0 in zip(workers, before)]
            assert min(used) > 0.05, used  # both processes stepped a simulation
        finally:
            await a.close()
            await b.close()

    run_async(scenario(), timeout=120)


def test_a_reload_through_the_front_finds_its_session_and_state(served):
    async def scenario() -> None:
        a = await student(served.port)
        token = token_of(a)
        await play(a)
        await Client.until(lambda: (sim_time(a) or 0) > 0.5, "the simulation to run", timeout=60)
        await a.close()
        shown = sim_time(a)
        again = await student(served.port, path=f"/s/{token}/")
        try:
            assert token_of(again) == token
            # the same simulation: its time goes on from where the tab left it, not from 0
            await Client.until(lambda: sim_time(again) is not None, "the time readout", timeout=30)
            assert sim_time(again) >= shown
        finally:
            await again.close()

    run_async(scenario(), timeout=120)


def test_the_tab_after_the_last_place_is_told_the_lab_is_full(served):
    async def scenario() -> None:
        tabs = [await student(served.port) for _ in range(3)]
        extra = await student(served.port)
        try:
            assert all(token_of(t) for t in tabs)
            assert len({token_of(t) for t in tabs}) == 3
            assert token_of(extra) is None and "This lab is full" in " ".join(extra.texts())
            # the class's places, not the share of the process that answered
            assert "All **3** places are taken" in " ".join(extra.texts())
            await Client.until(lambda: "the lab is full (3 places)" in served.err.read_text(), "the teacher's line")
        finally:
            for c in (*tabs, extra):
                await c.close()

    run_async(scenario(), timeout=180)


def test_the_front_refuses_other_sites_pages_and_unknown_hosts(served):
    async def scenario() -> None:
        for kw in ({"origin": "http://evil.example"}, {"host": f"evil.example:{served.port}"}):
            with pytest.raises(InvalidStatus) as refused:
                await Client.open(served.port, camera=False, **kw)
            assert refused.value.response.status_code == 403, kw
        ok = await Client.open(served.port, camera=False, origin=f"http://127.0.0.1:{served.port}")
        await ok.close()

    run_async(scenario(), timeout=60)


def test_a_broken_request_gets_an_error_and_the_front_serves_on(served):
    import socket
    import urllib.request

    for junk in (b"NONSENSE\r\n\r\n", b"GET / HTTP/1.1\r\n" + b"X-Long: " + b"a" * 70_000 + b"\r\n\r\n"):
        with socket.create_connection(("127.0.0.1", served.port), timeout=20) as s:
            s.sendall(junk)
            answer = b""
            with contextlib.suppress(ConnectionError):
                while chunk := s.recv(4096):
                    answer += chunk
        assert answer == b"" or answer.startswith(b"HTTP/1.1 4"), answer[:80]
    with urllib.request.urlopen(f"http://127.0.0.1:{served.port}/", timeout=30) as r:
        assert r.status == 200 and b"<html" in r.read().lower()


def test_a_process_that_dies_is_started_again_and_new_tabs_are_served(built, tmp_path):
    server = Served(built("pendulum"), tmp_path, "--processes", "2", "--max-sessions", "4")
    try:
        old = server.children()
        assert len(old) == 2
        os.kill(old[0], signal.SIGKILL)
        deadline = time.monotonic() + 120
        while not (len(server.children()) == 2 and old[0] not in server.children()
                   and "starting a new one" in server.err.read_text()):
            assert time.monotonic() < deadline, server.err.read_text()
            time.sleep(0.2)

        async def scenario() -> None:
            tabs = [await student(server.port) for _ in range(4)]  # needs both processes' places
            try:
                assert all(token_of(t) for t in tabs), [t.texts() for t in tabs]
            finally:
                for t in tabs:
                    await t.close()

        # the new process reports itself before the front relays to it: every tab is served
        time.sleep(0.5)
        run_async(scenario(), timeout=180)
        assert server.proc.poll() is None
    finally:
        server.stop()


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_stopping_the_front_stops_every_process(built, tmp_path, sig):
    server = Served(built("pendulum"), tmp_path, "--processes", "2")
    workers = server.children()
    assert len(workers) == 2
    server.proc.send_signal(sig)
    status = server.proc.wait(30)
    err = server.err.read_text()
    assert status == 128 + sig and "Traceback" not in err, err
    assert err.count("stopped by") == 1, err  # one line, the front's
    deadline = time.monotonic() + 10
    while any(alive(p) for p in workers):
        assert time.monotonic() < deadline, "a serving process outlived its front"
        time.sleep(0.1)


def test_processes_whose_front_is_killed_stop_on_their_own(built, tmp_path):
    server = Served(built("pendulum"), tmp_path, "--processes", "2")
    workers = server.children()
    server.proc.kill()
    server.proc.wait(10)
    deadline = time.monotonic() + 15
    while any(alive(p) for p in workers):
        assert time.monotonic() < deadline, "a serving process outlived its front"
        time.sleep(0.1)


def test_shared_serving_and_one_process_need_no_front(built, tmp_path):
    # one place is served by one process: a second would be a place more than the teacher gave
    for args in (("--shared",), ("--processes", "1"), ("--processes", "2", "--max-sessions", "1")):
        server = Served(built("pendulum"), tmp_path, *args)
        try:
            assert server.children() == []
        finally:
            server.stop()
    r = subprocess.run([sys.executable, "-P", str(built("pendulum") / "app.py"), "--shared", "--processes", "2"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "--shared serves one simulation from one process" in r.stderr


def test_the_start_up_lines_say_where_how_many_and_what_was_taken(capsys):
    from ejsrl.app._loop import announce

    announce("Lab", "127.0.0.1", 8081, places=6, processes=2, asked_port=8080)
    out, err = capsys.readouterr()
    assert out.splitlines()[0] == "Lab: serving on http://127.0.0.1:8081 (port 8080 was taken) (Ctrl+C to stop)"
    assert "up to 6 at once from 2 processes" in out and err == ""
    announce("Lab", "127.0.0.1", 8080, places=None, asked_port=8080)
    out, _ = capsys.readouterr()
    assert "port 8080 was taken" not in out and "every browser tab shows and drives this one simulation (--shared)" in out
    announce("Lab", "0.0.0.0", 8080, places=3)
    out, err = capsys.readouterr()
    assert "up to 3 at once (--max-sessions N to change" in out and "processes" not in out
    assert err.startswith("warning: --host 0.0.0.0 opens this lab")
