"""The app's side of a remote laboratory: one session's link to the plant over MQTT.

The link is the only thing that talks to the plant (the browser never does). It

* requests the lease for its session and keeps a heartbeat going (every ``heartbeat`` s, from its
  own thread, so a paused or slow simulation does not trip the plant's watchdog; a killed app
  process stops the heartbeat and the plant stops);
* checks every command against the spec's limits before sending it (the plant checks again);
* sends a command only while connected and holding the lease, tagged with the lease epoch and
  a fresh sequence number; nothing is queued across a disconnect, so no stale command is sent
  after a reconnect;
* never drops a heartbeat: a heartbeat that meets a command still being written is retried
  within the period (paho holds one outgoing message; a dropped heartbeat under load let the
  plant's watchdog stop a holder in the middle of its program);
* closes itself (releasing the lease) within one heartbeat period once ``alive()`` says its
  session is gone (a closed tab), so the next in the queue gets the plant at once;
* reconnects with backoff (0.1 s doubling to 2 s) and says so in :attr:`note` at once;
* measures the round trip (command sent -> the plant's state echoing it), in s.
"""

from __future__ import annotations

import json
import threading
import time
import uuid
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ejsrl.plant._creds import Credentials
from ejsrl.plant._mqtt import json_object, make_client, no_delay
from ejsrl.plant._video import PlantClock, VideoFrame, parse_frame

__all__ = ["PlantLink", "LinkBase", "Limits", "BUSY"]

#: :meth:`PlantLink.send`'s answer while the command before is still being written to the broker
#: (paho holds one message at a time: nothing piles up across a disconnect); try again next frame
BUSY = "the previous command is still being sent"


@dataclass(frozen=True)
class Limits:
    """The app's own limits on a command: joint angles (n,) rad and speed (n,) rad/s."""

    q_min: np.ndarray
    q_max: np.ndarray
    qd_max: np.ndarray | None = None

    def check(self, q: np.ndarray, q_prev: np.ndarray | None, dt: float | None) -> str | None:
        if q.shape != self.q_min.shape or not np.all(np.isfinite(q)):
            return f"a command is {self.q_min.size} finite joint angles"
        bad = np.flatnonzero((q < self.q_min - 1e-9) | (q > self.q_max + 1e-9))
        if bad.size:
            i = int(bad[0])
            return (f"joint {i + 1} at {np.degrees(q[i]):.1f} deg is outside the lab's limits "
                    f"[{np.degrees(self.q_min[i]):.0f}, {np.degrees(self.q_max[i]):.0f}] deg")
        if self.qd_max is not None and q_prev is not None and dt:
            over = np.flatnonzero(np.abs(q - q_prev) / dt > self.qd_max + 1e-9)
            if over.size:
                return f"joint {int(over[0]) + 1} would move faster than its speed limit"
        return None


def refusal(link: Any, qa: np.ndarray, now: float, st: dict[str, Any] | None, online: bool = True) -> str | None:
    """Why the link (MQTT or OPC UA) must not send the set points ``qa`` now, or None: the
    joint limits, the connection, the plant online, the lease held in its state ``st`` and no
    emergency stop."""
    if link.limits is not None:
        why = link.limits.check(qa, link._last_q, None if link._last_t is None else now - link._last_t)
        if why:
            return why
    if not link.connected:
        return "not connected to the plant: commands are disabled"
    if not online:
        return "the plant is offline: commands are disabled"
    if not st or st.get("holder") != link.session:
        return "this session does not hold the plant"
    if st.get("estop"):
        return "emergency stop is on"
    return None


class LinkBase:
    """What a link shows whatever its transport (MQTT: :class:`PlantLink`, OPC UA:
    :class:`ejsrl.app._plant_opcua.OpcUaLink`): the plant's last state, the lease and queue, the
    round trip, and the camera's newest frame with its age on this app's clock."""

    def _init_link(self, session: str | None, limits: Limits | None, heartbeat: float) -> None:
        self.session = session or uuid.uuid4().hex[:12]   # the plant's name for this session (not the tab's token)
        self.limits = limits
        self.heartbeat_period = heartbeat
        #: ``on_state()`` is called (from the network thread) after every state message or connection change
        self.on_state: Any = None
        self.state: dict[str, Any] | None = None          # the plant's last state message
        self.state_at = 0.0                               # monotonic time it arrived
        self.plant_online = False
        self.connected = False
        self.note = "connecting to the plant"
        self.latency: float | None = None                 # last round trip, s
        self.latencies: list[float] = []
        self.wants_lease = False
        self._seq = 0
        self._sent: dict[int, float] = {}                 # commands in flight: seq -> perf_counter when sent
        self._last_q: np.ndarray | None = None
        self._last_t: float | None = None
        self._lock = threading.Lock()
        self._changed = threading.Condition(self._lock)
        #: the plant's clock on this app's: a frame's age is ``now - (frame.t + offset)``
        self.clock = PlantClock()
        self.video_wanted = False
        self.frame: VideoFrame | None = None              # the camera's newest frame (older ones are dropped)
        self.frames = 0                                   # frames taken
        self.states = 0                                   # state messages taken
        self.bad_frames = 0                               # frames refused (see parse_frame)

    # ---- what the lab shows -----------------------------------------------------------------
    @property
    def holds_lease(self) -> bool:
        st = self.state
        return bool(self.connected and st and st.get("holder") == self.session)

    @property
    def queue_position(self) -> int | None:
        """1 for the next in line, None when not waiting."""
        st = self.state
        if not st or self.session not in st.get("queue", []):
            return None
        return st["queue"].index(self.session) + 1

    def measured(self) -> np.ndarray | None:
        st = self.state
        return None if st is None else np.asarray(st["q"], dtype=float)

    def video_age(self, now: float | None = None) -> float | None:
        """Seconds since the newest frame was captured, on this app's clock (None: no frame yet).
        It grows while no frame comes (the plant paused, killed or cut off); a frame of the plant's
        former life (before a restart, another clock) counts from its arrival."""
        f = self.frame
        if f is None:
            return None
        now = time.monotonic() if now is None else now
        st = self.state
        age = self.clock.age(f.t, now) if st is not None and st.get("boot") == f.boot else None
        return max(0.0, now - f.arrived if age is None else age)

    def wait_for(self, pred: Any, timeout: float = 10.0) -> bool:
        """Wait until ``pred(self)`` holds (checked on every state message); True when it did."""
        end = time.monotonic() + timeout
        with self._changed:
            while not pred(self):
                left = end - time.monotonic()
                if left <= 0:
                    return False
                self._changed.wait(min(left, 0.05))
        return True

    # ---- what the transports call -------------------------------------------------------------
    def _now_connected(self) -> None:
        """The transport (re)connected: commands are enabled again, nothing sent before is in
        flight any more (no stale command is replayed), and a lease still wanted is asked for."""
        with self._changed:
            self.connected = True
            self._sent.clear()
            self.note = "connected"
            self._changed.notify_all()
        if self.wants_lease:
            self.request_lease()  # type: ignore[attr-defined] - each transport's own

    def _now_lost(self, why: str | None = None, *, offline: bool = False) -> None:
        """The connection is gone: say so at once and disable commands (``why``: a note of its
        own, e.g. the broker refusing the credentials; ``offline``: no plant state either)."""
        with self._changed:
            self.connected = False
            if offline:
                self.plant_online = False
            self.note = why or "connection to the plant lost: commands disabled, reconnecting"
            self._changed.notify_all()
        if self.on_state is not None:
            self.on_state()

    def _take_state(self, st: dict[str, Any], arrived: float) -> bool:
        """Keep a state message that arrived at ``arrived`` (monotonic s); the caller holds the
        lock. True when the plant restarted since the last one (its queue and clock are new)."""
        rebooted = self.state is not None and st.get("boot") != self.state.get("boot")
        if rebooted:
            self.clock.reset()
        self.clock.add(st.get("t"), arrived)
        self.state, self.state_at, self.plant_online = st, arrived, True
        self.states += 1
        self._changed.notify_all()
        return rebooted

    def _take_frame(self, payload: bytes) -> None:
        """Keep a frame message if it is a whole JPEG (never decoded here), else count it."""
        frame = parse_frame(payload, time.monotonic())
        if isinstance(frame, str):
            self.bad_frames += 1
            return
        with self._changed:
            self.frame = frame
            self.frames += 1
            self._changed.notify_all()


class PlantLink(LinkBase):
    """One session's MQTT link to the plant at ``host:port`` under topic ``prefix``."""

    def __init__(self, host: str, port: int, *, prefix: str = "ejsrl/plant", limits: Limits | None = None,
                 creds: Credentials | None = None, heartbeat: float = 0.1, session: str | None = None,
                 alive: Any = None) -> None:
        self._init_link(session, limits, heartbeat)
        self.prefix = prefix.rstrip("/")
        #: ``alive()`` -> seconds since the session was last seen alive (None: always); the
        #: heartbeat stops after 1 s of it, and the link closes itself after 10 s
        self.alive = alive
        self._refused = False
        self._asked = 0.0
        self._stop = threading.Event()
        self.client = make_client(f"ejsrl-app-{self.session}", creds or Credentials())
        self.client.reconnect_delay_set(min_delay=0.1, max_delay=2)
        self.client.on_connect = self._on_connect
        self.client.on_disconnect = self._on_disconnect
        self.client.on_message = self._on_message
        self.client.connect_async(host, port, keepalive=5)
        self.client.loop_start()
        self._beat = threading.Thread(target=self._beat_loop, name="ejsrl-plant-heartbeat", daemon=True)
        self._beat.start()

    # ---- what the session does --------------------------------------------------------------
    def request_lease(self) -> None:
        self.wants_lease = True
        self._asked = time.monotonic()
        self._publish_surely("lease", {"op": "request"}, 0.2)

    def release_lease(self) -> None:
        self.wants_lease = False
        self._publish_surely("lease", {"op": "release"}, 0.5)

    def estop(self, on: bool = True) -> None:
        """Emergency stop: any session may press it, holder or spectator."""
        self._publish("estop", {"on": bool(on)})

    def want_video(self, on: bool) -> None:
        """Receive the plant's camera frames (subscribe to ``video``) or stop receiving them."""
        if on == self.video_wanted:
            return
        self.video_wanted = on
        if self.connected:
            topic = f"{self.prefix}/video"
            self.client.subscribe(topic, 0) if on else self.client.unsubscribe(topic)

    def send(self, q: Sequence[float], gripper: float | None = None) -> str | None:
        """Send joint set points ``q`` (rad); returns why it was not sent, or None when it was."""
        qa = np.asarray(q, dtype=float).reshape(-1)
        now = time.monotonic()
        st = self.state
        why = refusal(self, qa, now, st, self.plant_online)
        if why:
            return why
        assert st is not None
        with self._lock:
            self._seq += 1
            seq = self._seq
            self._sent.pop(seq - 100, None)     # an ack that never came is forgotten after 100 commands
            self._sent[seq] = time.perf_counter()
        msg: dict[str, Any] = {"epoch": st["epoch"], "seq": seq, "t": self._sent[seq], "q": qa.tolist()}
        if gripper is not None:
            msg["gripper"] = float(gripper)
        if not self._publish("cmd", msg):
            with self._lock:
                self._sent.pop(seq, None)
            return BUSY
        self._last_q, self._last_t = qa, now
        return None

    def close(self) -> None:
        self._stop.set()
        if self.wants_lease and self.connected:
            self.release_lease()
        self.client.disconnect()
        self.client.loop_stop()

    # ---- paho callbacks (the network thread) ------------------------------------------------
    def _publish(self, kind: str, payload: dict[str, Any]) -> bool:
        """Publish at once; False when not connected or paho still holds the message before."""
        if not self.connected:
            return False
        payload["session"] = self.session
        info = self.client.publish(f"{self.prefix}/{kind}", json.dumps(payload), qos=0)
        return info.rc == 0

    def _publish_surely(self, kind: str, payload: dict[str, Any], within: float) -> bool:
        """Publish, retried every 2 ms for ``within`` s while paho still holds the message before
        (a heartbeat, a lease request or release must not be lost to a command being written)."""
        until = time.monotonic() + within
        in_loop = threading.current_thread() is getattr(self.client, "_thread", None)  # it would wait for itself
        while not self._publish(kind, dict(payload)):
            if in_loop or not self.connected or time.monotonic() > until:
                return False
            time.sleep(0.002)
        return True

    def _on_connect(self, client: Any, userdata: Any, flags: Any, reason: Any, props: Any) -> None:
        if reason.is_failure:
            with self._lock:
                self._refused = True
                self.note = f"the broker refused the connection ({reason}): check the plant credentials"
                self._changed.notify_all()
            return
        self._refused = False
        no_delay(client)
        topics = [(f"{self.prefix}/state", 0), (f"{self.prefix}/online", 1)]
        client.subscribe(topics + ([(f"{self.prefix}/video", 0)] if self.video_wanted else []))
        self._now_connected()

    def _on_disconnect(self, client: Any, userdata: Any, flags: Any, reason: Any, props: Any) -> None:
        self._now_lost(self.note if self._refused else None)

    def _on_message(self, client: Any, userdata: Any, msg: Any) -> None:
        if msg.topic.endswith("/video"):
            if self.video_wanted:
                self._take_frame(msg.payload)
            return
        if msg.topic.endswith("/online"):
            with self._lock:
                self.plant_online = msg.payload == b"1"
                if not self.plant_online:
                    self.note = "the plant is offline"
                self._changed.notify_all()
            return
        now, arrived = time.perf_counter(), time.monotonic()
        st = json_object(msg.payload, 1 << 16)
        if st is None:
            return
        with self._lock:
            ack = st.get("ack") or {}
            if ack.get("session") == self.session and ack.get("seq") in self._sent:
                rtt = now - self._sent.pop(ack["seq"])
                self.latency = rtt
                self.latencies.append(rtt)
                del self.latencies[:-1000]
            if self.connected:
                self.note = "connected"
            rebooted = self._take_state(st, arrived)
        if rebooted and self.wants_lease:   # a restarted plant forgot the queue: ask again
            self.request_lease()
        if self.on_state is not None:
            self.on_state()

    def _beat_loop(self) -> None:
        while not self._stop.wait(self.heartbeat_period):
            idle = self.alive() if self.alive is not None else 0.0
            if idle > 10.0:            # the session is gone: give the plant back
                threading.Thread(target=self.close, daemon=True).start()
                return
            if idle < 1.0:             # a session whose frames stopped stops beating: the watchdog stops the plant
                self._publish_surely("heartbeat", {}, self.heartbeat_period)
            st = self.state
            if (self.wants_lease and st and self.connected and st.get("holder") != self.session
                    and self.session not in (st.get("queue") or []) and time.monotonic() - self._asked > 1.0):
                # the request was lost (the broker or the plant restarting) or the watchdog ended the lease
                self.request_lease()


# ---- the spec's plant: section, as the generated app declares it ----------------------------------
@dataclass(frozen=True)
class PlantCommand:
    """Model variable ``var`` drives ``to`` (``joints`` or ``gripper``); ``scale`` converts the
    variable's unit to the plant's (deg -> rad: pi/180); limits in the plant's unit."""

    var: str
    to: str
    scale: float = 1.0
    q_min: list[float] | None = None
    q_max: list[float] | None = None
    max_speed: float | None = None


@dataclass(frozen=True)
class PlantMeasurement:
    """Model variable ``var`` receives ``source``, divided by ``scale`` (rad -> deg: pi/180)."""

    var: str
    source: str
    scale: float = 1.0


@dataclass(frozen=True)
class PlantDef:
    """The spec's ``plant:``: where the broker is and which variables go to and from the plant.
    ``EJSRL_PLANT_HOST``/``EJSRL_PLANT_PORT`` in the environment win over ``host``/``port``."""

    host: str
    port: int
    topic: str = "ejsrl/plant"
    heartbeat: float = 0.1
    rate: float = 20.0
    commands: list[PlantCommand] | None = None
    measurements: list[PlantMeasurement] | None = None
    transport: str = "mqtt"
    #: the plant's camera in Real plant mode: a frame older than ``video_stale`` s is flagged
    #: stale (None: no video); at most ``video_rate`` frames a second go to the page
    video_stale: float | None = None
    video_rate: float = 15.0

    def joints(self) -> PlantCommand | None:
        return next((c for c in self.commands or [] if c.to == "joints"), None)

    def limits(self) -> Limits | None:
        j = self.joints()
        if j is None or j.q_min is None or j.q_max is None:
            return None
        n = len(j.q_min)
        speed = None if j.max_speed is None else np.full(n, j.max_speed)
        return Limits(np.asarray(j.q_min, float), np.asarray(j.q_max, float), speed)

    def connect(self, *, alive: Any = None) -> "PlantLink":
        """A link for one session; credentials from the environment or ``EJSRL_PLANT_CREDENTIALS``."""
        import os

        from ejsrl.plant._creds import load_credentials

        host = os.environ.get("EJSRL_PLANT_HOST") or self.host
        port = int(os.environ.get("EJSRL_PLANT_PORT") or self.port)
        creds = load_credentials(os.environ.get("EJSRL_PLANT_CREDENTIALS") or None)
        if self.transport == "opcua":
            from ejsrl.app._plant_opcua import OpcUaLink

            return OpcUaLink(host, port, limits=self.limits(), heartbeat=self.heartbeat,
                             username=creds.username, password=creds.password, alive=alive)  # type: ignore[return-value]
        return PlantLink(host, port, prefix=self.topic, limits=self.limits(), creds=creds,
                         heartbeat=self.heartbeat, alive=alive)
