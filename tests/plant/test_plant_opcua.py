"""The reference plant as an OPC UA server (asyncua), driven by an independent asyncua client."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np

from conftest import PlantProc, free_port

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
