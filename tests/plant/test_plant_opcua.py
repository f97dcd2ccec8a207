"""The reference plant as an OPC UA server (asyncua), driven by an independent asyncua client."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np

from testkit.plant import PlantProc, free_port

DEG = math.pi / 180


def test_opcua_lease_command_measure_and_estop(tmp_path: Path) -> None:
    from asyncua.sync import Client

    port = free_port()
    plant = PlantProc(tmp_path, ["--opcua", f"127.0.0.1:{port}", "--watchdog", "2"])
    try:
        with Client(f"opc.tcp://127.0.0.1:{port}/ejsrl/plant/", timeout=20) as c:
            idx = c.get_namespace_index("urn:ejsrl:plant")
            obj = c.nodes.objects.get_child(f"{idx}:Plant")
            measured = obj.get_child(f"{idx}:Measured")
            state = obj.get_child(f"{idx}:State")
            lease = json.loads(obj.call_method(f"{idx}:Lease", "cell-1", "request"))
            assert lease["holder"] == "cell-1"
            target = [0.3, 0.2, -0.1, 0.1, 0.5]
            seq = 0

            def beat_until(pred, timeout: float = 20.0) -> bool:
                end = time.monotonic() + timeout
                while time.monotonic() < end:
                    obj.call_method(f"{idx}:Heartbeat", "cell-1")
                    if pred():
                        return True
                    time.sleep(0.1)
                return False

            seq += 1
            assert obj.call_method(f"{idx}:Command", "cell-1", lease["epoch"], seq, 0.0, target, 0.0) == ""
            assert beat_until(lambda: np.max(np.abs(np.array(measured.read_value()) - target)) < 1 * DEG)
            # refused by the plant: out of joint 2's limits, and a stale sequence number
            seq += 1
            why = obj.call_method(f"{idx}:Command", "cell-1", lease["epoch"], seq, 0.0, [0.0, 3.0, 0.0, 0.0, 0.0], 0.0)
            assert "joint 2" in why
            assert "stale" in obj.call_method(f"{idx}:Command", "cell-1", lease["epoch"], 1, 0.0, [0.0] * 5, 0.0)
            # another client's e-stop stops it
            seq += 1
            assert obj.call_method(f"{idx}:Command", "cell-1", lease["epoch"], seq, 0.0, [2.5, 0.0, 0.0, 0.0, 0.0], 0.0) == ""
            assert beat_until(lambda: json.loads(state.read_value())["status"] == "moving")
            obj.call_method(f"{idx}:EStop", "teacher", True)
            assert beat_until(lambda: json.loads(state.read_value())["status"] == "estop"
                              and max(map(abs, json.loads(state.read_value())["qd"])) == 0.0, 5)
            assert measured.read_value()[0] < 2.4
    finally:
        plant.stop()


def test_the_apps_opcua_link_drives_the_plant_and_sees_it_go(tmp_path: Path) -> None:
    from ejsrl.app._plant_opcua import OpcUaLink

    port = free_port()
    plant = PlantProc(tmp_path, ["--opcua", f"127.0.0.1:{port}"])
    try:
        link = OpcUaLink("127.0.0.1", port)
        spectator = OpcUaLink("127.0.0.1", port, session="spectator")
        assert link.wait_for(lambda l: l.connected and l.state is not None, 30), link.note
        link.request_lease()
        assert link.wait_for(lambda l: l.holds_lease, 20)
        target = np.array([20, 10, -10, 5, 30]) * DEG
        assert link.send(target) is None
        assert link.latency is not None and link.latency < 2.0
        assert link.wait_for(lambda l: np.max(np.abs(l.measured() - target)) < 1 * DEG, 20)
        assert "joint 2" in link.send(np.array([0, 170, 0, 0, 0]) * DEG)   # refused by the plant
        assert spectator.wait_for(lambda l: l.connected, 30)
        spectator.estop()
        assert link.wait_for(lambda l: l.state["status"] == "estop", 10)
        assert link.send(target) == "emergency stop is on"
        plant.stop()                                      # the plant goes away: shown at once
        assert link.wait_for(lambda l: not l.connected, 20)
        assert "lost" in link.note or "failed" in link.note
        assert link.send(target) == "not connected to the plant: commands are disabled"
        link.close()
        spectator.close()
    finally:
        plant.stop()


def test_a_lab_with_transport_opcua_connects_over_opcua(tmp_path: Path, monkeypatch) -> None:
    from ejsgen.cli import build
    from ejsrl.app._plant_link import PlantCommand, PlantDef

    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text("ejs: 1\ntitle: cell\nmodel:\n  variables:\n    q: {expr: 'np.zeros(5)'}\n"
                    "plant:\n  transport: opcua\n  port: 4840\n  commands:\n    q: {to: joints}\n")
    assert "transport='opcua'" in (build(spec, tmp_path / "app") / "app.py").read_text()
    port = free_port()
    plant = PlantProc(tmp_path, ["--opcua", f"127.0.0.1:{port}"])
    monkeypatch.setenv("EJSRL_PLANT_PORT", str(port))
    try:
        link = PlantDef("127.0.0.1", 4840, transport="opcua", commands=[PlantCommand("q", "joints")]).connect()
        assert type(link).__name__ == "OpcUaLink"
        assert link.wait_for(lambda l: l.state is not None and l.state["status"] == "idle", 30), link.note
        link.close()
    finally:
        plant.stop()
