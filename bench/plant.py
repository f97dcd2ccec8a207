"""Benchmark the remote laboratory's plant link (issue #26) on loopback, through Debian's mosquitto.

- round trip: a PlantLink command -> broker -> reference plant (executes it, publishes its state)
  -> broker -> the link sees the plant's acknowledgement; against a bare paho client doing the
  same publish/subscribe through the same broker to a bare echo client (goal: <= 1.5x, <= 2 ms
  median). The two are interleaved, one message at a time, so load hits both alike;
- e-stop -> plant stopped: a spectator's e-stop to the first state at rest, the arm turning at
  full speed;
- watchdog trip: the holder's app process is killed with SIGKILL mid-move; the time until the
  plant says the watchdog stopped it and until it is at rest (the watchdog's limit is 0.5 s).

- video: the reference plant's camera at 640 x 480, asked for 30 frames/s: frames/s received by
  a link, the frames' age on arrival, the bytes a watching session receives, the plant's CPU.

The bare echo runs in a process of its own, as the plant does (a client in the measuring process
itself would skip the second process's wake-up and flatter the bare side). Each round prints the
medians of ``--n`` interleaved round trips and, measured apart, the CPU time a round trip costs
(this process plus the plant's or the echo's), which load hardly changes. Options: ``--n N``,
``--rounds R``, ``--video-seconds S``. Prints the load average beside every figure.
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


_ECHO = """
import sys, paho.mqtt.client as mqtt
echo = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="bench-echo")
echo.on_connect = lambda c, *a: (c.subscribe("bench/in", 0), print("ready", flush=True))
echo.on_message = lambda c, u, m: c.publish("bench/out", m.payload, qos=0)
echo.connect("127.0.0.1", int(sys.argv[1]))
echo.loop_forever()
"""


def _bare(port: int) -> tuple[subprocess.Popen, object, threading.Event]:
    """The bare pair: an echo client in a process of its own (as the plant is: bench/in -> bench/out)
    and a measuring client here."""
    import paho.mqtt.client as mqtt

    echo = subprocess.Popen([sys.executable, "-c", _ECHO, str(port)], stdout=subprocess.PIPE, text=True)
    assert echo.stdout.readline().strip() == "ready"
    got = threading.Event()
    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="bench-bare")
    client.on_connect = lambda c, *a: c.subscribe("bench/out", 0)
    client.on_message = lambda c, u, m: got.set()
    client.connect("127.0.0.1", port)
    client.loop_start()
    time.sleep(0.5)
    return echo, client, got


def _cpu(pid: int) -> float:
    """CPU seconds (user + system) a process has used (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _uptime() -> str:
    """The load averages over 1, 5 and 15 minutes, as uptime prints them."""
    return "/".join(Path("/proc/loadavg").read_text().split()[:3])


class _Ours:
    """One round trip of the plant link: a command, until the plant's state acknowledges it."""

    def __init__(self, link: object) -> None:
        self.link, self.i = link, 0

    def __call__(self) -> float | None:
        link = self.link
        self.i += 1
        assert link.send(np.radians([0.01 * (self.i % 2 * 2 - 1), 0, 0, 0, 0])) is None
        seq = link._seq
        if not link.wait_for(lambda l: seq not in l._sent, 5):
            return None
        return link.latency


class _Theirs:
    def __init__(self, client: object, got: threading.Event) -> None:
        self.client, self.got = client, got
        self.payload = b'{"session": "bench", "epoch": 1, "seq": 1, "t": 0.0, "q": [0.0, 0.0, 0.0, 0.0, 0.0]}'

    def __call__(self) -> float | None:
        self.got.clear()
        t0 = time.perf_counter()
        self.client.publish("bench/in", self.payload, qos=0)
        return time.perf_counter() - t0 if self.got.wait(5) else None


def _round_trips(ours: _Ours, theirs: _Theirs, n: int, plant_pid: int, echo_pid: int) -> dict[str, float]:
    """``n`` round trips each, interleaved one by one (wall time, load hits both alike); then
    ``n`` of each alone for their CPU time: this process plus the far end's (plant or echo)."""
    a, b = [], []
    for _ in range(n):
        for side, out in ((ours, a), (theirs, b)):
            t = side()
            if t is not None:
                out.append(t)
    cpu = {}
    for name, side, far in (("ours", ours, plant_pid), ("theirs", theirs, echo_pid)):
        c0, f0 = time.process_time(), _cpu(far)
        for _ in range(n):
            side()
        cpu[name] = (time.process_time() - c0 + _cpu(far) - f0) / n
    return {"ours": float(np.median(a)), "theirs": float(np.median(b)), "ours90": float(np.percentile(a, 90)),
            "theirs90": float(np.percentile(b, 90)), "cpu_ours": cpu["ours"], "cpu_theirs": cpu["theirs"]}


def _print_round(k: int, r: dict[str, float], what: str) -> None:
    print(f"  round {k} ({what}; load {_uptime()}): plant link {r['ours'] * 1e3:.2f} ms (p90 {r['ours90'] * 1e3:.2f}), "
          f"bare paho echo {r['theirs'] * 1e3:.2f} ms (p90 {r['theirs90'] * 1e3:.2f}), ratio {r['ours'] / r['theirs']:.2f}x; "
          f"CPU per round trip {r['cpu_ours'] * 1e6:.0f} us vs {r['cpu_theirs'] * 1e6:.0f} us ({r['cpu_ours'] / r['cpu_theirs']:.2f}x)",
          flush=True)


def _start_plant(port: int, *extra: str) -> subprocess.Popen:
    plant = subprocess.Popen([sys.executable, "-m", "ejsrl.plant", "--mqtt", f"127.0.0.1:{port}", "--watchdog", "0.5",
                              "--noise", "0", *extra], stdout=subprocess.PIPE, text=True)
    assert plant.stdout.readline().strip() == "ready"
    return plant


def _video(port: int, seconds: float) -> None:
    """The camera at 640 x 480, asked for 30 frames/s: the frames/s and ages a link sees, the
    plant's CPU, and the command round trip while it streams."""
    from ejsrl.app._plant_link import PlantLink

    plant = _start_plant(port, "--camera", "640x480", "--fps", "30")
    link = PlantLink("127.0.0.1", port, session="bench-video")
    try:
        assert link.wait_for(lambda l: l.connected and l.state is not None, 30)
        link.want_video(True)
        assert link.wait_for(lambda l: l.frame is not None, 30)
        ages, sizes = [], []
        n0, t0, c0 = link.frames, time.monotonic(), _cpu(plant.pid)
        while time.monotonic() - t0 < seconds:
            seq = link.frame.seq
            if link.wait_for(lambda l: l.frame.seq != seq, 5):
                ages.append(link.video_age())
                sizes.append(len(link.frame.jpeg))
        dt = time.monotonic() - t0
        fps = (link.frames - n0) / dt
        print(f"video 640 x 480 asked at 30 frames/s (load {_uptime()}): {fps:.1f} frames/s received, age at arrival "
              f"median {np.median(ages) * 1e3:.0f} ms (p90 {np.percentile(ages, 90) * 1e3:.0f}), {np.mean(sizes) / 1e3:.0f} kB a frame "
              f"({fps * np.mean(sizes) / 1e6:.2f} MB/s a watching session), plant CPU {(_cpu(plant.pid) - c0) / dt * 100:.0f}% of a core",
              flush=True)
    finally:
        link.close()
        plant.terminate()
        plant.wait(10)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=500, help="round trips per side and round (default 500)")
    ap.add_argument("--rounds", type=int, default=3, help="rounds of round trips (default 3)")
    ap.add_argument("--video-seconds", type=float, default=5.0, help="how long to watch the 640 x 480 video (default 5 s)")
    a = ap.parse_args(argv)
    sys.path.insert(0, str(HERE.parent / "runtime"))
    from ejsrl.app._plant_link import PlantLink

    tmp = Path(tempfile.mkdtemp(prefix="bench-plant-"))
    port = _free_port()
    conf = tmp / "mosquitto.conf"
    conf.write_text(f"listener {port} 127.0.0.1\nallow_anonymous true\npersistence false\nset_tcp_nodelay true\n" + ("user root\n" if os.geteuid() == 0 else ""))
    broker = subprocess.Popen(["mosquitto", "-c", str(conf)], stderr=subprocess.DEVNULL)
    _wait_port(port)
    plant = _start_plant(port, "--camera", "off")
    echo, bare, got = _bare(port)
    try:
        link = PlantLink("127.0.0.1", port, session="bench")
        assert link.wait_for(lambda l: l.connected and l.state is not None, 30)
        link.request_lease()
        assert link.wait_for(lambda l: l.holds_lease, 30)
        ours, theirs = _Ours(link), _Theirs(bare, got)
        print(f"{os.cpu_count()} cores; command round trip through mosquitto, medians of {a.n} interleaved (goal <= 1.5x and <= 2 ms):")
        rounds = []
        for k in range(a.rounds):
            rounds.append(_round_trips(ours, theirs, a.n, plant.pid, echo.pid))
            _print_round(k + 1, rounds[-1], "camera off")
        ratios = [r["ours"] / r["theirs"] for r in rounds]
        print(f"  ratio over the rounds: {min(ratios):.2f}-{max(ratios):.2f}x (median {np.median(ratios):.2f}x)")

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
        print(f"e-stop -> plant at rest (seen by the app; load {_uptime()}): median {np.median(stops) * 1e3:.0f} ms, "
              f"worst {max(stops) * 1e3:.0f} ms from {np.degrees(1.2):.0f}+ deg/s")
        link.release_lease()
        link.wait_for(lambda l: l.state["holder"] is None, 10)

        # watchdog: SIGKILL of the holder's app mid-move
        trips, rests = [], []
        for k in range(3):
            holder = subprocess.Popen([sys.executable, str(HERE.parent / "tests" / "plant" / "holder.py"), str(port),
                                       "150" if k % 2 == 0 else "-150"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                                      env={**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE.parent / "runtime"), os.environ.get("PYTHONPATH", "")])})
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
        print(f"watchdog (limit 0.5 s) after SIGKILL of the holder (load {_uptime()}): trip median {np.median(trips) * 1e3:.0f} ms "
              f"(worst {max(trips) * 1e3:.0f}), at rest median {np.median(rests) * 1e3:.0f} ms (worst {max(rests) * 1e3:.0f})")
        link.close()
        plant.terminate()
        plant.wait(10)

        # the same round trips while the plant's camera streams (its default: 320 x 240, 10 frames/s)
        plant = _start_plant(port)
        link = PlantLink("127.0.0.1", port, session="bench-camera")
        assert link.wait_for(lambda l: l.connected and l.state is not None, 30)
        link.request_lease()
        assert link.wait_for(lambda l: l.holds_lease, 30)
        r = _round_trips(_Ours(link), theirs, a.n, plant.pid, echo.pid)
        _print_round(a.rounds + 1, r, "camera on, 320 x 240 at 10 frames/s")
        link.close()
        plant.terminate()
        plant.wait(10)
        _video(port, a.video_seconds)
    finally:
        if plant.poll() is None:
            plant.terminate()
            plant.wait(10)
        bare.loop_stop()
        echo.kill()
        echo.wait()
        broker.kill()
        broker.wait()
    return 0


if __name__ == "__main__":
    sys.exit(main())
