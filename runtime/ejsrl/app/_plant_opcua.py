"""The app's side of a remote laboratory over OPC UA (asyncua): the same interface as
:class:`ejsrl.app._plant_link.PlantLink`, for a plant served as an OPC UA server.

One thread of its own connects (backoff 0.1 s doubling to 2 s), reads the plant's ``State``
variable ``rate`` times a second and calls ``Heartbeat`` every ``heartbeat`` s; a command is a
``Command`` method call, whose duration is the round trip shown. A lost connection disables
commands at once; nothing is queued across it.
"""

from __future__ import annotations

import json
import threading
import time
import uuid
from typing import Any, Sequence

import numpy as np

from ejsrl.app._plant_link import LinkBase, Limits, refusal

__all__ = ["OpcUaLink"]


class OpcUaLink(LinkBase):
    """One session's OPC UA link to the plant at ``opc.tcp://host:port/ejsrl/plant/``."""

    def __init__(self, host: str, port: int, *, limits: Limits | None = None, heartbeat: float = 0.1,
                 session: str | None = None, rate: float = 50.0, username: str | None = None, password: str | None = None,
                 alive: Any = None) -> None:
        try:
            from asyncua.sync import Client  # noqa: F401
        except ImportError as e:  # pragma: no cover
            raise ImportError("the OPC UA transport needs asyncua: python3 -m pip install 'ejsgen[plant]'") from e
        self._init_link(session, limits, heartbeat)
        self.url = f"opc.tcp://{host}:{port}/ejsrl/plant/"
        self.rate = rate
        #: ``alive()`` -> seconds since the session was last seen alive (None: always), as for
        #: :class:`PlantLink`: no heartbeat after 1 s of it, the lease released after 10 s
        self.alive = alive
        self._user, self._password = username, password
        self._client: Any = None
        self._obj: Any = None
        self._idx = 0
        self._stop = threading.Event()
        threading.Thread(target=self._run, name="ejsrl-plant-opcua", daemon=True).start()

    # ---- what the session does ----------------------------------------------------------------
    def _call(self, name: str, *args: Any) -> Any:
        obj = self._obj
        if obj is None or not self.connected:
            return None
        try:
            return obj.call_method(f"{self._idx}:{name}", *args)
        except Exception as e:  # noqa: BLE001 - the connection's thread notices and reconnects
            self.note = f"a call to the plant failed: {type(e).__name__}"
            return None

    def request_lease(self) -> None:
        self.wants_lease = True
        self._call("Lease", self.session, "request")

    def release_lease(self) -> None:
        self.wants_lease = False
        self._call("Lease", self.session, "release")

    def estop(self, on: bool = True) -> None:
        self._call("EStop", self.session, bool(on))

    def want_video(self, on: bool) -> None:
        """Read the plant's camera frames (its ``Video`` variable, when ``VideoSeq`` changed) or not."""
        self.video_wanted = on

    def send(self, q: Sequence[float], gripper: float | None = None) -> str | None:
        qa = np.asarray(q, dtype=float).reshape(-1)
        now = time.monotonic()
        st = self.state
        why = refusal(self, qa, now, st)
        if why:
            return why
        assert st is not None
        self._seq += 1
        t0 = time.perf_counter()
        grip = float(st.get("gripper", 0.0) if gripper is None else gripper)
        why = self._call("Command", self.session, int(st["epoch"]), self._seq, t0, [float(x) for x in qa], grip)
        if why is None:
            return "not connected to the plant: commands are disabled"
        self.latency = time.perf_counter() - t0
        self.latencies.append(self.latency)
        del self.latencies[:-1000]
        self._last_q, self._last_t = qa, now
        return why or None

    def close(self) -> None:
        if self.wants_lease:
            self.release_lease()
        self._stop.set()

    # ---- the connection's thread --------------------------------------------------------------
    def _set(self, **kw: Any) -> None:
        with self._changed:
            for k, v in kw.items():
                setattr(self, k, v)
            self._changed.notify_all()
        if self.on_state is not None:
            self.on_state()

    def _run(self) -> None:
        from asyncua.sync import Client

        delay = 0.1
        while not self._stop.is_set():
            client = Client(self.url, timeout=5)
            if self._user:
                client.set_user(self._user)
                client.set_password(self._password or "")
            try:
                client.connect()
            except Exception as e:  # noqa: BLE001
                self._set(note=f"connecting to the plant failed ({type(e).__name__}); retrying in {delay:.1f} s")
                self._stop.wait(delay)
                delay = min(delay * 2, 2.0)
                continue
            delay = 0.1
            try:
                self._idx = client.get_namespace_index("urn:ejsrl:plant")
                self._obj = client.nodes.objects.get_child(f"{self._idx}:Plant")
                state = self._obj.get_child(f"{self._idx}:State")
                video, video_seq = (self._obj.get_child(f"{self._idx}:{n}") for n in ("Video", "VideoSeq"))
                seen = None
                self._now_connected()
                next_beat = 0.0
                while not self._stop.is_set():
                    now = time.monotonic()
                    idle = self.alive() if self.alive is not None else 0.0
                    if idle > 10.0:           # the session is gone (its tab closed): give the plant back
                        self.close()
                        break
                    if now >= next_beat and idle < 1.0:
                        self._obj.call_method(f"{self._idx}:Heartbeat", self.session)
                        next_beat = now + self.heartbeat_period
                    st = json.loads(state.read_value())
                    arrived = time.monotonic()
                    if self.video_wanted and video_seq.read_value() != seen:
                        seen, payload = client.read_values([video_seq, video])
                        if payload:
                            self._take_frame(payload)
                    if (self.wants_lease and st.get("holder") != self.session
                            and self.session not in (st.get("queue") or [])):
                        self._obj.call_method(f"{self._idx}:Lease", self.session, "request")
                    with self._changed:
                        self._take_state(st, arrived)
                    if self.on_state is not None:
                        self.on_state()
                    self._stop.wait(1.0 / self.rate)
            except Exception as e:  # noqa: BLE001 - lost: say so at once, then reconnect
                self._now_lost(f"connection to the plant lost ({type(e).__name__}): commands disabled, reconnecting", offline=True)
            finally:
                self._obj = None
                try:
                    client.disconnect()
                except Exception:  # noqa: BLE001
                    pass
