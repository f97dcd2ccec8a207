"""The lease over a long program (issue #26), against the reference plant on a real mosquitto:
a holder that is alive keeps the plant for longer than its slot and through a late heartbeat,
a refusal of a command in flight goes once the next command is executed, and a session that
is gone gives the plant back at once (release) or after the plant's queue timeout (silence)."""

from __future__ import annotations

import math
import threading
import time
from pathlib import Path

import numpy as np

from testkit.plant import Broker, PlantProc

DEG = math.pi / 180


def _watch(link) -> list[tuple[float, str | None, int, dict | None]]:
    """Every state the link takes: (arrival, holder, epoch, refused), appended from its network thread."""
    seen: list[tuple[float, str | None, int, dict | None]] = []

    def on_state() -> None:
        st = link.state or {}
        seen.append((time.monotonic(), st.get("holder"), st.get("epoch"), st.get("refused")))

    link.on_state = on_state
    return seen


def _stream(link, seconds: float, rate: float, stop: threading.Event) -> list[str]:
    """A program: joint 1 swept 0 -> 40 deg -> 0 over ``seconds`` at ``rate`` commands a second,
    the way the panel sends it; returns every reason a command was not sent (BUSY retried)."""
    from ejsrl.app._plant_link import BUSY

    whys: list[str] = []
    t0 = time.monotonic()
    while not stop.is_set() and (t := time.monotonic() - t0) < seconds:
        q = np.array([40 * DEG * math.sin(math.pi * t / seconds), 0, 0, 0, 0])
        why = link.send(q)
        if why is not None and why != BUSY:
            whys.append(why)
        time.sleep(1.0 / rate)
    return whys


def test_a_program_longer_than_the_slot_keeps_the_lease_with_a_class_watching(broker: Broker, tmp_path: Path,
                                                                            link_factory) -> None:
    """12 s of commands at the lab's 25 Hz (three slots of 4 s), the heartbeat thread starved for
    4 s of them (a loaded machine): the holder never loses the plant, the watchdog never stops it
    (its commands say it is alive) and no command of it is refused."""
    plant = PlantProc(tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}", "--watchdog", "0.5", "--slot", "4"])
    try:
        spectator = link_factory(session="spectator")
        seen = _watch(spectator)
        starved = threading.Event()
        holder = link_factory(session="holder", alive=lambda: 1.5 if starved.is_set() else 0.0)
        holder.request_lease()
        assert holder.wait_for(lambda l: l.holds_lease, 20)
        deadline = time.monotonic() + 20  # the spectator's view of the plant lags the holder's own by a message or two
        while not (seen and seen[-1][1] == "holder"):
            assert time.monotonic() < deadline, "the spectator never saw the holder"
            time.sleep(0.02)
        start = len(seen)
        threading.Timer(4.0, starved.set).start()
        threading.Timer(8.0, starved.clear).start()
        whys = _stream(holder, 12.0, 25.0, threading.Event())
        assert whys == []
        during = seen[start:]
        assert len(during) > 12 * 20, len(during)               # the plant spoke all along (50 Hz)
        assert {h for _, h, _, _ in during} == {"holder"}
        assert len({e for _, _, e, _ in during}) == 1             # one lease epoch: no watchdog stop, no re-grant
        assert all(r is None for _, _, _, r in during[-10:]), during[-1]
        assert "watchdog" not in spectator.state["event"]
    finally:
        plant.stop()


def test_a_late_heartbeat_stops_the_arm_but_the_holder_goes_on_and_the_refusal_clears(plant: PlantProc,
                                                                                       link_factory) -> None:
    """The holder falls silent for 1.2 s (watchdog 0.5 s, queue timeout 3 s): the arm stops, the
    lease stays with the holder (a new epoch), a command of the old epoch is refused as stale, and
    the next command goes through and clears that refusal."""
    silent = threading.Event()
    holder = link_factory(session="holder", alive=lambda: 5.0 if silent.is_set() else 0.0)
    holder.request_lease()
    assert holder.wait_for(lambda l: l.holds_lease, 20)
    assert holder.send(np.array([150, 0, 0, 0, 0]) * DEG) is None       # a long move
    assert holder.wait_for(lambda l: l.state["status"] == "moving", 20)
    old_epoch = holder.state["epoch"]
    silent.set()
    assert holder.wait_for(lambda l: "watchdog" in l.state["event"], 10), holder.state["event"]
    assert holder.wait_for(lambda l: l.state["status"] == "idle", 10)
    assert holder.measured()[0] < 140 * DEG                              # stopped short of the target
    time.sleep(0.7)                                                      # 1.2 s silent: < the queue timeout
    assert holder.state["holder"] == "holder" and holder.state["epoch"] > old_epoch
    silent.clear()
    # a command that waited somewhere (the old epoch) is refused as stale, and says so
    holder.client.publish(f"{holder.prefix}/cmd", f'{{"session": "holder", "epoch": {old_epoch}, "seq": 999999, '
                                                  f'"q": [0.5, 0, 0, 0, 0]}}')
    assert holder.wait_for(lambda l: "stale" in ((l.state.get("refused") or {}).get("reason") or ""), 10)
    # the program goes on: its next command is executed and the refusal is gone
    assert holder.send(np.array([30, 0, 0, 0, 0]) * DEG) is None
    assert holder.wait_for(lambda l: l.state.get("refused") is None, 10), holder.state["refused"]
    assert holder.wait_for(lambda l: abs(l.measured()[0] - 30 * DEG) < 1 * DEG and l.state["status"] == "idle", 20)
    assert holder.holds_lease


def test_a_silent_holder_loses_the_lease_after_the_queue_timeout(plant: PlantProc, link_factory, lease_queue) -> None:
    """A holder silent past the queue timeout (3 s) hands the plant to the next in line."""
    queue = lease_queue(link_factory, 5.0)
    took = queue.hand_over(20)
    assert 2.5 < took < 6.0, took
    assert "refused" not in queue.waiting.state["event"]


def test_a_session_gone_releases_the_lease_within_a_heartbeat(plant: PlantProc, link_factory, lease_queue) -> None:
    """``alive()`` says the session is gone (its tab closed): the link releases the lease itself,
    and the next in the queue holds the plant well before any timeout would have passed it on."""
    queue = lease_queue(link_factory, math.inf)
    took = queue.hand_over(10)
    assert took < 1.0, took
    assert queue.waiting.state["event"] == "lease granted"


def test_over_opcua_a_session_gone_releases_the_lease_at_once(tmp_path: Path, lease_queue) -> None:
    """The same over OPC UA: the holder's session gone, the next in the queue holds the plant
    well before the queue timeout (3 s) would have passed it on."""
    from ejsrl.app._plant_opcua import OpcUaLink
    from testkit.plant import ConnectedLinks, free_port

    port = free_port()
    plant = PlantProc(tmp_path, ["--opcua", f"127.0.0.1:{port}", "--camera", "off"])
    try:
        with ConnectedLinks(lambda **kw: OpcUaLink("127.0.0.1", port, **kw)) as make:
            queue = lease_queue(make, math.inf)
            took = queue.hand_over(10)
            assert took < 1.5, took
            assert queue.waiting.state["event"] == "lease granted"
    finally:
        plant.stop()
