"""The reference plant against a real mosquitto broker: round trip, lease, watchdog, e-stop,
broker restart, limits and credentials (issue #26). Every server is a real process on loopback."""

from __future__ import annotations

import json
import math
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from testkit.plant import Broker, PlantProc

HERE = Path(__file__).parent
DEG = math.pi / 180


def _holder(port: int, target_deg: float) -> subprocess.Popen:
    p = subprocess.Popen([sys.executable, str(HERE / "holder.py"), str(port), str(target_deg)],
                         stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    return p


def _expect(p: subprocess.Popen, word: str) -> None:
    line = p.stdout.readline().strip()
    assert line == word, f"the holder process said {line!r}, expected {word!r}"


def test_command_round_trip_moves_the_arm(plant: PlantProc, link_factory) -> None:
    link = link_factory()
    link.request_lease()
    assert link.wait_for(lambda l: l.holds_lease, 20)
    target = np.array([30, 20, -15, 10, 45]) * DEG
    assert link.send(target, gripper=1.0) is None
    # the measured joints (encoder noise 2e-4 rad) settle on the set point within 1 deg
    assert link.wait_for(lambda l: np.max(np.abs(l.measured() - target)) < 1 * DEG and l.state["status"] == "idle", 20), link.state
    assert link.state["gripper"] == 1.0
    assert link.latency is not None and 0 < link.latency < 1.0


def test_second_session_waits_then_gets_the_plant_when_the_holder_is_killed(broker: Broker, plant: PlantProc, link_factory) -> None:
    a = _holder(broker.port, 150.0)          # another app process takes the plant and starts a long move
    try:
        _expect(a, "holding")
        _expect(a, "sent")
        b = link_factory(session="student-b")
        b.request_lease()
        assert b.wait_for(lambda l: l.queue_position == 1, 20), b.state
        assert b.send(np.zeros(5)) == "this session does not hold the plant"
        assert b.wait_for(lambda l: l.state["status"] == "moving", 20)
        a.send_signal(signal.SIGKILL)
        killed = time.monotonic()
        # the watchdog (0.5 s) stops the plant: standstill well short of the 150 deg target
        assert b.wait_for(lambda l: l.state["status"] == "idle" and "watchdog" in l.state["event"] or l.holds_lease, 20)
        assert b.wait_for(lambda l: l.state["status"] == "idle", 20)
        stopped = time.monotonic() - killed
        assert stopped < 2.0, f"the plant took {stopped:.2f} s to stop after the app was killed"
        assert b.measured()[0] < 140 * DEG
        # and the waiting session gets the plant
        assert b.wait_for(lambda l: l.holds_lease, 20)
        assert b.send(np.zeros(5)) is None
    finally:
        a.kill()
        a.wait()


def test_second_session_gets_the_plant_after_release(broker: Broker, plant: PlantProc, link_factory) -> None:
    a = _holder(broker.port, 5.0)
    try:
        _expect(a, "holding")
        _expect(a, "sent")
        b = link_factory(session="student-b")
        b.request_lease()
        assert b.wait_for(lambda l: l.queue_position == 1, 20)
        a.stdin.write("release\n")
        a.stdin.flush()
        _expect(a, "released")
        assert b.wait_for(lambda l: l.holds_lease, 20)
    finally:
        a.kill()
        a.wait()


def test_emergency_stop_from_a_spectator(plant: PlantProc, link_factory) -> None:
    holder, spectator = link_factory(), link_factory()
    holder.request_lease()
    assert holder.wait_for(lambda l: l.holds_lease, 20)
    assert holder.send(np.array([150, 0, 0, 0, 0]) * DEG) is None
    assert spectator.wait_for(lambda l: l.state["status"] == "moving" and abs(l.state["qd"][0]) > 0.5, 20)
    pressed = time.monotonic()
    spectator.estop()
    assert spectator.wait_for(lambda l: l.state["status"] == "estop" and max(map(abs, l.state["qd"])) == 0.0, 20)
    assert time.monotonic() - pressed < 1.5
    q_stop = spectator.measured()[0]
    assert q_stop < 140 * DEG
    # the holder cannot move it while the e-stop is on, its own check and the plant's
    assert holder.wait_for(lambda l: l.state["estop"], 5)
    assert holder.send(np.zeros(5)) == "emergency stop is on"
    holder.client.publish(f"{holder.prefix}/cmd", json.dumps({"session": holder.session, "epoch": holder.state["epoch"],
                                                              "seq": 10**6, "q": [0] * 5}))
    assert holder.wait_for(lambda l: (l.state.get("refused") or {}).get("reason") == "emergency stop is on", 10)
    time.sleep(0.3)
    assert abs(spectator.measured()[0] - q_stop) < 0.2 * DEG


def test_broker_restart_replays_no_stale_command(broker: Broker, plant: PlantProc, link_factory) -> None:
    link = link_factory()
    link.request_lease()
    assert link.wait_for(lambda l: l.holds_lease, 20)
    assert link.send(np.array([10, 0, 0, 0, 0]) * DEG) is None
    assert link.wait_for(lambda l: abs(l.measured()[0] - 10 * DEG) < 0.5 * DEG and l.state["status"] == "idle", 20)
    old_epoch = link.state["epoch"]
    broker.kill()
    assert link.wait_for(lambda l: not l.connected, 10)
    assert "lost" in link.note
    # a command while the broker is away is refused at once, never queued for later
    assert link.send(np.array([60, 0, 0, 0, 0]) * DEG) == "not connected to the plant: commands are disabled"
    time.sleep(1.0)                            # longer than the plant's watchdog
    broker.start()
    assert link.wait_for(lambda l: l.connected and l.holds_lease and l.state["epoch"] > old_epoch, 30), link.state
    assert "watchdog" in link.state["event"] or link.state["epoch"] > old_epoch
    # the command sent while disconnected never reached the plant
    time.sleep(0.5)
    assert abs(link.measured()[0] - 10 * DEG) < 0.5 * DEG
    # a command of the old lease (one that waited somewhere) is refused by the plant as stale
    link.client.publish(f"{link.prefix}/cmd", json.dumps({"session": link.session, "epoch": old_epoch, "seq": 10**6,
                                                          "q": [1.0, 0, 0, 0, 0]}))
    assert link.wait_for(lambda l: "stale" in ((l.state.get("refused") or {}).get("reason") or ""), 10)
    time.sleep(0.3)
    assert abs(link.measured()[0] - 10 * DEG) < 0.5 * DEG


def test_limits_are_refused_by_the_app_and_by_the_plant(plant: PlantProc, link_factory) -> None:
    from ejsrl.app._plant_link import Limits

    lim = Limits(q_min=np.full(5, -90 * DEG), q_max=np.full(5, 90 * DEG))
    checked = link_factory(limits=lim)
    why = checked.send(np.array([100, 0, 0, 0, 0]) * DEG)
    assert why is not None and "joint 1" in why and "limits" in why
    raw = link_factory()                      # an app without its own limits: the plant still refuses
    raw.request_lease()
    assert raw.wait_for(lambda l: l.holds_lease, 20)
    assert raw.send(np.array([0, 0, 0, 0, 200]) * DEG) is None
    assert raw.wait_for(lambda l: "joint 5" in ((l.state.get("refused") or {}).get("reason") or ""), 10)
    # the workspace: the arm folded down would put the tool below the table
    assert raw.send(np.array([0, -30, -60, 0, 0]) * DEG) is None  # tip 130 mm below
    assert raw.wait_for(lambda l: "below the table" in ((l.state.get("refused") or {}).get("reason") or ""), 10)
    time.sleep(0.3)
    assert np.max(np.abs(raw.measured())) < 0.5 * DEG  # the arm never moved


def test_credentials_come_from_a_file_and_never_show(tmp_path: Path) -> None:
    from testkit.plant import free_port
    from ejsrl.app._plant_link import PlantLink
    from ejsrl.plant import load_credentials

    secret = "s3cret-Pa55-do-not-show"
    b = Broker(tmp_path, free_port(), passwd={"lab": secret})
    b.start()
    creds_file = tmp_path / "plant.creds"
    creds_file.write_text(f"username = lab\npassword = {secret}\n")
    p = PlantProc(tmp_path, ["--mqtt", f"127.0.0.1:{b.port}", "--credentials", str(creds_file)])
    try:
        good = PlantLink("127.0.0.1", b.port, creds=load_credentials(creds_file))
        assert good.wait_for(lambda l: l.state is not None, 30), good.note
        bad = PlantLink("127.0.0.1", b.port)
        assert bad.wait_for(lambda l: "refused" in l.note, 30), bad.note
        assert secret not in repr(load_credentials(creds_file))
        good.close()
        bad.close()
    finally:
        p.stop()
        b.kill()
    assert secret not in p.logs()
    assert secret not in (tmp_path / "mosquitto.log").read_text()


def test_plant_killed_disables_commands_and_a_restarted_plant_starts_at_rest(broker: Broker, tmp_path: Path, link_factory) -> None:
    args = ["--mqtt", f"127.0.0.1:{broker.port}"]
    first = PlantProc(tmp_path, args)
    link = link_factory()
    link.request_lease()
    assert link.wait_for(lambda l: l.holds_lease, 20)
    boot = link.state["boot"]
    first.proc.send_signal(signal.SIGKILL)          # the broker publishes the plant's last will
    first.proc.wait()
    assert link.wait_for(lambda l: not l.plant_online, 20)
    assert link.note == "the plant is offline"
    assert link.send(np.zeros(5)) == "the plant is offline: commands are disabled"
    second = PlantProc(tmp_path, args)
    try:
        # the new plant (a new boot) grants the lease again; its epoch starts afresh and the arm at rest
        assert link.wait_for(lambda l: l.state["boot"] != boot and l.holds_lease, 20)
        assert link.send(np.array([5, 0, 0, 0, 0]) * DEG) is None
        assert link.wait_for(lambda l: abs(l.measured()[0] - 5 * DEG) < 0.5 * DEG, 20)
    finally:
        second.stop()


def test_only_who_pressed_the_estop_rearms(plant: PlantProc, link_factory) -> None:
    teacher, student = link_factory(session="teacher"), link_factory(session="student")
    teacher.estop()
    assert student.wait_for(lambda l: l.state["estop"], 10)
    student.estop(False)
    assert student.wait_for(lambda l: "only who pressed" in l.state["event"], 10)
    assert student.state["estop"]
    teacher.estop(False)
    assert student.wait_for(lambda l: not l.state["estop"], 10)


def test_injected_latency_and_fault(broker: Broker, tmp_path: Path, link_factory) -> None:
    p = PlantProc(tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}", "--latency", "0.2", "--fault-after", "4", "joint 3 encoder lost"])
    try:
        link = link_factory()
        link.request_lease()
        assert link.wait_for(lambda l: l.holds_lease, 20)
        assert link.send(np.array([5, 0, 0, 0, 0]) * DEG) is None
        assert link.wait_for(lambda l: l.latency is not None, 10)
        assert link.latency >= 0.2                      # the command waited 0.2 s before the plant took it
        assert link.wait_for(lambda l: l.state["status"] == "fault", 20)
        assert link.state["fault"] == "joint 3 encoder lost"
        assert link.send(np.zeros(5)) is None
        assert link.wait_for(lambda l: "plant fault" in ((l.state.get("refused") or {}).get("reason") or ""), 10)
    finally:
        p.stop()
