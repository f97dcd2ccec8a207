"""Benchmark the remote laboratory's plant link (issue #26) on loopback, through Debian's mosquitto.

- round trip: a PlantLink command -> broker -> reference plant (executes it, publishes its state)
  -> broker -> the link sees the plant's acknowledgement; against a bare paho client doing the
  same publish/subscribe through the same broker to a bare echo client (goal: <= 1.5x, <= 2 ms
  median). The two are interleaved, one message at a time, so load hits both alike;
- e-stop -> plant stopped: a spectator's e-stop to the first state at rest, the arm turning at
  full speed;
- watchdog trip: the holder's app process is killed with SIGKILL mid-move; the time until the
  plant says the watchdog stopped it and until it is at rest (the watchdog's limit is 0.5 s).

Options: ``--n N`` round trips per side (default 500). Prints the load average beside the figures.
"""

from __future__ import annotations

import argparse
import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_port(port: int) -> None:
    for _ in range(400):
        try:
            socket.create_connection(("127.0.0.1", port), 0.5).close()
            return
        except OSError:
            time.sleep(0.05)
    raise TimeoutError(port)


def _bare_pair(port: int) -> tuple[object, object, threading.Event, list[float]]:
    """A bare echo client (echo/in -> echo/out) and a bare measuring client."""
    import paho.mqtt.client as mqtt

    echo = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="bench-echo")
    echo.on_connect = lambda c, *a: c.subscribe("bench/in", 0)
    echo.on_message = lambda c, u, m: c.publish("bench/out", m.payload, qos=0)
    echo.connect("127.0.0.1", port)
    echo.loop_start()
    got = threading.Event()
    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="bench-bare")
    client.on_connect = lambda c, *a: c.subscribe("bench/out", 0)
    client.on_message = lambda c, u, m: got.set()
    client.connect("127.0.0.1", port)
    client.loop_start()
    time.sleep(0.5)
    return echo, client, got, []


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=500)
    a = ap.parse_args(argv)
    sys.path.insert(0, str(HERE.parent / "runtime"))
    from ejsrl.app._plant_link import PlantLink

    tmp = Path(tempfile.mkdtemp(prefix="bench-plant-"))
    port = _free_port()
    conf = tmp / "mosquitto.conf"
    conf.write_text(f"listener {port} 127.0.0.1\nallow_anonymous true\npersistence false\n" + ("user root\n" if os.geteuid() == 0 else ""))
    broker = subprocess.Popen(["mosquitto", "-c", str(conf)], stderr=subprocess.DEVNULL)
    _wait_port(port)
    plant = subprocess.Popen([sys.executable, "-m", "ejsrl.plant", "--mqtt", f"127.0.0.1:{port}", "--watchdog", "0.5",
                              "--noise", "0"], stdout=subprocess.PIPE, text=True)
    assert plant.stdout.readline().strip() == "ready"
    try:
        link = PlantLink("127.0.0.1", port, session="bench")
        assert link.wait_for(lambda l: l.connected and l.state is not None, 30)
        link.request_lease()
        assert link.wait_for(lambda l: l.holds_lease, 30)
        echo, bare, got, _ = _bare_pair(port)
        ours, theirs = [], []
        payload = b'{"session": "bench", "epoch": 1, "seq": 1, "t": 0.0, "q": [0.0, 0.0, 0.0, 0.0, 0.0]}'
        for i in range(a.n):
            q = np.radians([10.0 * ((i % 2) * 2 - 1) * 0.01, 0, 0, 0, 0])
            before = len(link.latencies)
            assert link.send(q) is None
            link.wait_for(lambda l: len(l.latencies) > before, 5)
            if len(link.latencies) > before:
                ours.append(link.latencies[-1])
            got.clear()
            t0 = time.perf_counter()
            bare.publish("bench/in", payload, qos=0)
            if got.wait(5):
                theirs.append(time.perf_counter() - t0)
        mo, mb = np.median(ours) * 1e3, np.median(theirs) * 1e3
        print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
        print(f"round trip through mosquitto, median of {len(ours)}/{len(theirs)}: plant link {mo:.2f} ms "
              f"(p90 {np.percentile(ours, 90) * 1e3:.2f}), bare paho echo {mb:.2f} ms (p90 {np.percentile(theirs, 90) * 1e3:.2f}), "
              f"ratio {mo / mb:.2f}x (goal <= 1.5x and <= 2 ms)")
        echo.loop_stop()
        bare.loop_stop()

        # e-stop -> stopped, the arm turning fast
        stops = []
        for k in range(3):
            target = np.radians([150.0 if k % 2 == 0 else -150.0, 0, 0, 0, 0])
            link.estop(False)
            link.wait_for(lambda l: not l.state["estop"], 5)
            link.send(target)
            link.wait_for(lambda l: abs(l.state["qd"][0]) > 1.2, 10)
            t0 = time.monotonic()
            link.estop(True)
            link.wait_for(lambda l: l.state["status"] == "estop" and max(map(abs, l.state["qd"])) == 0.0, 10)
            stops.append(time.monotonic() - t0)
        link.estop(False)
        link.wait_for(lambda l: not l.state["estop"], 5)
        print(f"e-stop -> plant at rest (seen by the app): median {np.median(stops) * 1e3:.0f} ms, worst {max(stops) * 1e3:.0f} ms "
              f"from {np.degrees(1.2):.0f}+ deg/s")
        link.release_lease()
        link.wait_for(lambda l: l.state["holder"] is None, 10)

        # watchdog: SIGKILL of the holder's app mid-move
        trips, rests = [], []
        for k in range(3):
            holder = subprocess.Popen([sys.executable, str(HERE.parent / "tests" / "plant" / "holder.py"), str(port),
                                       "150" if k % 2 == 0 else "-150"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                                      env={**os.environ, "PYTHONPATH": str(HERE.parent / "runtime")})
            assert holder.stdout.readline().strip() == "holding"
            assert holder.stdout.readline().strip() == "sent"
            link.wait_for(lambda l: l.state["status"] == "moving" and abs(l.state["qd"][0]) > 1.0, 10)
            holder.send_signal(signal.SIGKILL)
            t0 = time.monotonic()
            link.wait_for(lambda l: "watchdog" in (l.state.get("event") or ""), 10)
            trips.append(time.monotonic() - t0)
            link.wait_for(lambda l: l.state["status"] == "idle", 10)
            rests.append(time.monotonic() - t0)
            holder.wait()
        print(f"watchdog (limit 0.5 s) after SIGKILL of the holder: trip median {np.median(trips) * 1e3:.0f} ms "
              f"(worst {max(trips) * 1e3:.0f}), at rest median {np.median(rests) * 1e3:.0f} ms (worst {max(rests) * 1e3:.0f})")
        print("video: not measured (the reference plant has no camera stream yet)")
        link.close()
    finally:
        plant.terminate()
        plant.wait(10)
        broker.kill()
        broker.wait()
    return 0


if __name__ == "__main__":
    sys.exit(main())
