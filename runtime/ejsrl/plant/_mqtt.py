"""The plant's MQTT side (paho-mqtt against a real broker such as Debian's mosquitto).

Topics under ``prefix`` (default ``ejsrl/plant``): ``cmd``, ``lease``, ``heartbeat``, ``estop``
in (JSON, QoS 0: a broker never keeps a command for later), ``state`` out (JSON, QoS 0, after
every executed command and ``rate`` times a second), ``video`` out (the camera's frames, see
:mod:`._video`: QoS 0, a frame dropped while the one before it is still being written), and
``online`` (retained ``1``/``0``, ``0`` being the plant's last will, so clients learn at once
that the plant is gone).
"""

from __future__ import annotations

import json
import socket
import threading
import time
from typing import TYPE_CHECKING, Any

from ._core import Plant
from ._creds import Credentials

if TYPE_CHECKING:
    from ._camera import PlantCamera

__all__ = ["MqttPlant", "import_paho", "make_client", "json_object", "no_delay"]


def import_paho() -> Any:
    """paho.mqtt.client, or an ImportError that says what to install."""
    try:
        import paho.mqtt.client as mqtt
    except ImportError as e:  # pragma: no cover - the hint is the point
        raise ImportError("the MQTT transport needs paho-mqtt: python3 -m pip install 'ejsgen[plant]'") from e
    return mqtt


def json_object(payload: bytes, limit: int) -> dict[str, Any] | None:
    """The JSON object in a message of at most ``limit`` bytes, or None (too long, not JSON, not an object)."""
    if len(payload) > limit:
        return None
    try:
        data = json.loads(payload)
    except (ValueError, UnicodeDecodeError):
        return None
    return data if isinstance(data, dict) else None


def no_delay(client: Any) -> None:
    """Send each message at once (TCP_NODELAY): with Nagle's algorithm a small message waits for
    the broker's acknowledgement of the one before it, which Linux delays up to 40 ms; the plant's
    50 Hz state made 1-2 % of the command round trips 40 ms long. Call it on every connect."""
    sock = client.socket()
    if sock is not None:
        try:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        except OSError:  # pragma: no cover - not a TCP socket (a websocket transport)
            pass


def make_client(client_id: str, creds: Credentials) -> Any:
    """A paho client (MQTT 3.1.1, clean session) with the credentials and TLS settings applied."""
    mqtt = import_paho()
    c = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=client_id, clean_session=True)
    if creds.username:
        c.username_pw_set(creds.username, creds.password)
    if creds.tls_ca:
        c.tls_set(ca_certs=creds.tls_ca, certfile=creds.tls_cert, keyfile=creds.tls_key)
    c.max_queued_messages_set(1)      # nothing piles up while the broker is away
    return c


class MqttPlant:
    """Serve ``plant`` on an MQTT broker at ``host:port``."""

    def __init__(self, plant: Plant, host: str, port: int, *, prefix: str = "ejsrl/plant",
                 creds: Credentials | None = None, rate: float = 50.0, camera: PlantCamera | None = None) -> None:
        self.plant, self.prefix, self.rate = plant, prefix.rstrip("/"), rate
        self.camera = camera
        self._frame_info: Any = None          # paho's handle of the last frame published
        self.frames_dropped = 0
        self.client = make_client(f"ejsrl-plant-{plant.boot}", creds or Credentials())
        self.client.will_set(f"{self.prefix}/online", "0", qos=1, retain=True)
        self.client.reconnect_delay_set(min_delay=0.1, max_delay=2)
        self.client.on_connect = self._on_connect
        self.client.on_message = self._on_message
        self.host, self.port = host, port
        self._stop = threading.Event()
        self.connected = threading.Event()

    def start(self) -> None:
        self.client.connect_async(self.host, self.port, keepalive=5)
        self.client.loop_start()
        threading.Thread(target=self._publish_loop, name="ejsrl-plant-mqtt", daemon=True).start()
        if self.camera is not None:
            self.camera.sinks.append(self._publish_frame)

    def _publish_frame(self, frame: bytes) -> None:
        """Publish a camera frame, or drop it while the last one is still being written (a slow
        broker connection gets fewer frames, never a queue of old ones)."""
        if not self.connected.is_set() or not self.client.is_connected():
            return
        last = self._frame_info
        if last is not None and not last[0].is_published() and time.monotonic() - last[1] < 1.0:
            self.frames_dropped += 1
            return
        self._frame_info = (self.client.publish(f"{self.prefix}/video", frame, qos=0), time.monotonic())

    def stop(self) -> None:
        self._stop.set()
        if self.camera is not None and self._publish_frame in self.camera.sinks:
            self.camera.sinks.remove(self._publish_frame)
        if self.client.is_connected():
            try:
                self.client.publish(f"{self.prefix}/online", "0", qos=1, retain=True).wait_for_publish(1.0)
            except (RuntimeError, ValueError):
                pass  # the broker went away meanwhile: the last will says it instead
        self.client.disconnect()
        self.client.loop_stop()

    def _on_connect(self, client: Any, userdata: Any, flags: Any, reason: Any, props: Any) -> None:
        if reason.is_failure:
            return
        no_delay(client)
        p = self.prefix
        client.subscribe([(f"{p}/cmd", 0), (f"{p}/lease", 0), (f"{p}/heartbeat", 0), (f"{p}/estop", 0)])
        client.publish(f"{p}/online", "1", qos=1, retain=True)
        self._frame_info = None               # a frame lost with the old connection holds nothing back
        self.connected.set()

    def _on_message(self, client: Any, userdata: Any, msg: Any) -> None:
        data = json_object(msg.payload, 4096)
        if data is None:
            return
        kind = msg.topic.rsplit("/", 1)[-1]
        session = str(data.get("session", ""))
        if kind == "cmd":
            self.plant.command(data)
            # the state at once, acknowledging it (one message: a second one right after it
            # waits for paho's next loop turn and made the round trip 20x slower)
            self._publish_state()
        elif kind == "heartbeat":
            self.plant.heartbeat(session)
        elif kind == "lease" and data.get("op") in ("request", "release"):
            self.plant.lease(session, data["op"])
            self._publish_state()
        elif kind == "estop":
            self.plant.estop(session, bool(data.get("on", True)))
            self._publish_state()

    def _publish_state(self) -> None:
        self.client.publish(f"{self.prefix}/state", json.dumps(self.plant.state()), qos=0)

    def _publish_loop(self) -> None:
        period = 1.0 / self.rate
        nxt = time.monotonic()
        while not self._stop.is_set():
            nxt += period
            if self.connected.is_set():
                self._publish_state()
            time.sleep(max(0.0, nxt - time.monotonic()))
            nxt = max(nxt, time.monotonic() - period)
