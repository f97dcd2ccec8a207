"""``python -m ejsrl.plant``: run the reference plant on MQTT and/or OPC UA until interrupted.

It prints ``ready`` on standard output once every transport it was asked for is serving.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading

from ._core import Plant, PlantConfig
from ._creds import load_credentials


def _hostport(text: str, default_port: int) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    if not host:
        return text, default_port
    return host, int(port)


def _camera_size(text: str) -> tuple[int, int] | tuple[()] | None:
    """``(width, height)`` from ``WxH``, None for ``off``, ``()`` when it is neither."""
    if text.strip().lower() in ("off", "none", "0"):
        return None
    w, sep, h = text.lower().partition("x")
    try:
        return (int(w), int(h)) if sep else ()
    except ValueError:
        return ()


def main(argv: list[str] | None = None, prog: str = "python -m ejsrl.plant") -> int:
    ap = argparse.ArgumentParser(prog=prog, description=__doc__)
    ap.add_argument("--mqtt", metavar="HOST:PORT", help="serve on the MQTT broker at HOST:PORT")
    ap.add_argument("--prefix", default="ejsrl/plant", help="MQTT topic prefix (default ejsrl/plant)")
    ap.add_argument("--opcua", metavar="HOST:PORT", help="serve an OPC UA endpoint at HOST:PORT")
    ap.add_argument("--credentials", metavar="FILE", help="username/password/TLS for the broker (or EJSRL_PLANT_* variables)")
    ap.add_argument("--watchdog", type=float, default=0.5, help="stop when the holder's heartbeat is older than this, s")
    ap.add_argument("--slot", type=float, default=120.0, help="lease slot length while others wait, s")
    ap.add_argument("--latency", type=float, default=0.0, help="injected latency of commands into the plant, s")
    ap.add_argument("--noise", type=float, default=2e-4, help="encoder noise (standard deviation), rad")
    ap.add_argument("--fault-after", nargs=2, metavar=("SECONDS", "TEXT"), help="inject a fault after SECONDS")
    ap.add_argument("--rate", type=float, default=50.0, help="state messages per second")
    ap.add_argument("--camera", default="320x240", metavar="WxH", help="the camera's picture size (default 320x240), or 'off'")
    ap.add_argument("--fps", type=float, default=10.0, help="camera frames per second (default 10)")
    ap.add_argument("--jpeg-quality", type=int, default=80, help="the camera's JPEG quality, 1-100 (default 80)")
    ap.add_argument("--video-latency", type=float, default=0.0, help="injected delay of the camera's frames, s")
    ap.add_argument("--clock-offset", type=float, default=0.0,
                    help="shift the plant's clock by this many s (as another machine's clock would be)")
    a = ap.parse_args(argv)
    if not a.mqtt and not a.opcua:
        ap.error("give --mqtt HOST:PORT, --opcua HOST:PORT or both")
    size = _camera_size(a.camera)
    if size == ():
        ap.error(f"--camera {a.camera!r}: give WIDTHxHEIGHT (e.g. 320x240) or off")
    try:
        creds = load_credentials(a.credentials)
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    plant = Plant(PlantConfig(watchdog=a.watchdog, slot=a.slot, latency=a.latency, noise=a.noise, clock_offset=a.clock_offset))
    camera = None
    if size:
        from ._camera import PlantCamera
        try:
            camera = PlantCamera(plant, width=size[0], height=size[1], fps=a.fps, quality=a.jpeg_quality, latency=a.video_latency)
        except ValueError as e:
            ap.error(str(e))
    plant.start()
    stops = []
    if a.mqtt:
        from ._mqtt import MqttPlant
        m = MqttPlant(plant, *_hostport(a.mqtt, 1883), prefix=a.prefix, creds=creds, rate=a.rate, camera=camera)
        m.start()
        if not m.connected.wait(30):
            print(f"error: no MQTT broker answered at {a.mqtt}", file=sys.stderr)
            return 1
        stops.append(m.stop)
    if a.opcua:
        from ._opcua import OpcUaPlant
        o = OpcUaPlant(plant, *_hostport(a.opcua, 4840), rate=a.rate, camera=camera)
        o.start()
        o.ready.wait(60)
        if o.error or not o.ready.is_set():
            print(f"error: the OPC UA server did not start: {o.error}", file=sys.stderr)
            return 1
        stops.append(o.stop)
    if camera is not None:
        camera.start()
        stops.insert(0, camera.stop)
    if a.fault_after:
        threading.Timer(float(a.fault_after[0]), plant.inject_fault, (a.fault_after[1],)).start()
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: done.set())
    signal.signal(signal.SIGINT, lambda *_: done.set())
    print("ready", flush=True)
    done.wait()
    for s in stops:
        s()
    plant.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
