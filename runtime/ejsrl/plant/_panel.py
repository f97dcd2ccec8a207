"""The plant panel of a remote laboratory: the Simulation / Real plant switch, the emergency stop,
and what the student must see (connection, lease and queue position, latency, the plant's status).

Built by the control panel (:class:`ejsrl.view._gui.Panel`) for a model with ``_plant()``, one per
session. Every frame (:meth:`PlantPanel.refresh`, under the app's lock) it writes the measured
values into the model's measurement variables and, in Real plant mode while this session holds
the lease, sends the command variables to the plant (at most ``rate`` times a second, only when
they changed). The browser only picks the mode and presses buttons; it never talks to the plant.
"""

from __future__ import annotations

import time
import weakref
from typing import Any

import numpy as np

from ejsrl.app._plant_link import BUSY
from ejsrl.view.elements import escape_markdown

__all__ = ["PlantPanel", "MODES"]

MODES = ("Simulation", "Real plant")


class PlantPanel:
    """The plant controls in ``gui`` for ``app`` (whose ``model._plant()`` declares the plant)."""

    def __init__(self, gui: Any, app: Any) -> None:
        self.app = app
        self.defn = app.model._plant()
        # the link beats from its own thread, paused or not; it closes (giving the plant back)
        # within a heartbeat period of this panel's tab closing, and stops when the app process dies
        me = weakref.ref(self)
        self._in_view = False                       # seen among the app's views (a closed tab's view leaves them)

        def gone_for() -> float:
            panel = me()
            return float("inf") if panel is None else panel._gone_for()

        self.link = self.defn.connect(alive=gone_for)
        weakref.finalize(self, self.link.close)
        self._woken_key: tuple[Any, ...] | None = None
        self.link.on_state = lambda: (p := me()) is not None and p._maybe_wake()
        self.real = False
        self._sent: tuple[float, ...] | None = None
        self._sent_at = 0.0
        self._shown = ""
        self.refusal: str | None = None
        self.mode = gui.add_dropdown("Plant mode", MODES, initial_value=MODES[0],
                                     hint="Real plant: your commands go to the robot when it is your turn")
        self.estop_button = gui.add_button("EMERGENCY STOP", color="red", hint="Stops the real robot for everyone")
        self.rearm_button = gui.add_button("Re-arm the plant", color="gray", visible=False)
        self.status = gui.add_markdown("")
        # the plant's camera (Real plant mode): the plant's JPEG goes to the page as it came,
        # the newest frame only, at most video_rate a second (viser keeps only the newest unsent one)
        self.video: Any = None
        self._video_shown: tuple[str, int] | None = None
        self._video_at = 0.0
        self._video_label = ""
        if self.defn.video_stale is not None:
            self.video = gui.add_image(np.full((2, 2, 3), 40, dtype=np.uint8), label="Plant camera",
                                       format="jpeg", visible=False)
            self._video_label = "Plant camera"

        @self.mode.on_update
        def _(_e: Any) -> None:
            value = self.mode.value
            if value not in MODES:          # a browser may send anything: only the two modes count
                self.mode.value = MODES[1] if self.real else MODES[0]
                return
            self.set_real(value == MODES[1])

        @self.estop_button.on_click
        def _(_e: Any) -> None:
            self.link.estop(True)

        @self.rearm_button.on_click
        def _(_e: Any) -> None:
            self.link.estop(False)

    def _gone_for(self) -> float:
        """0 while this panel's tab is open, infinity once its view left the app's views (the tab
        closed, or its session was freed): the link then releases the lease and closes."""
        views = list(getattr(self.app, "views", None) or [])
        mine = any(self in getattr(getattr(v, "panel", None), "drawings", ()) and not getattr(v, "closed", False)
                   for v in views)
        if mine:
            self._in_view = True
            return 0.0
        return float("inf") if self._in_view else 0.0

    def _wake(self) -> None:
        """Ask for frames (a paused session in a class gets none until something changes)."""
        wake = getattr(self.app, "on_wake", None)
        if wake is not None:
            wake()

    def _maybe_wake(self) -> None:
        """On a state message: frames while the robot moves, in Real plant mode, and when what
        the panel shows changed; a paused spectator of an idle plant costs nothing."""
        link, st = self.link, self.link.state or {}
        key = (link.connected, link.plant_online, st.get("status"), st.get("estop"), st.get("event"),
               st.get("holder") == link.session, link.queue_position)
        if self.real or st.get("status") != "idle" or key != self._woken_key:
            self._woken_key = key
            self._wake()

    def set_real(self, real: bool) -> None:
        """Switch this session to Real plant mode (join the queue for the lease) or back."""
        if real == self.real:
            return
        self.real = real
        self._sent = None
        self._wake()
        if self.video is not None:
            self.link.want_video(real)
            if not real and self.video.visible:
                self.video.visible = False
                self._video_shown = None
        if real:
            self.link.request_lease()
        else:
            self.link.release_lease()

    # ---- every frame (the caller holds app.lock) -----------------------------------------------
    def refresh(self) -> None:
        model = self.app.model
        link = self.link
        st = link.state
        for m in self.defn.measurements or []:
            value = self._measured(m.source, st)
            if value is None:
                continue
            if isinstance(value, np.ndarray):
                value = value / m.scale
                old = getattr(model, m.var, None)
                if isinstance(old, np.ndarray) and old.shape == value.shape:
                    old[...] = value
                    continue
            elif isinstance(value, float):
                value = value / m.scale
            setattr(model, m.var, value)
        if self.real and link.holds_lease and not (st or {}).get("estop"):
            self._send(model)
        if self.video is not None and self.real:
            self._show_frame()
        self._show(st)

    def _show_frame(self) -> None:
        """Send the link's newest frame to the page if it is new and the rate allows."""
        f, now = self.link.frame, time.monotonic()
        if f is None or (f.boot, f.seq) == self._video_shown or now - self._video_at < 1.0 / self.defn.video_rate:
            return
        self.video._data = f.jpeg          # the plant's JPEG as it came: checked by the link, never decoded here
        self._video_shown, self._video_at = (f.boot, f.seq), now
        if not self.video.visible:
            self.video.visible = True

    def video_line(self) -> str:
        """What the panel says of the video: its age in ms, or STALE past ``video_stale`` s."""
        age, stale = self.link.video_age(), self.defn.video_stale or 0.0
        label = "Plant camera" if age is None or age <= stale else "Plant camera: STALE"
        if label != self._video_label:
            self.video.label = self._video_label = label
        if age is None:
            return "**Video:** waiting for the plant's camera"
        if age > stale:
            return f"**Video: STALE** (the newest frame is {age:.1f} s old)"
        return f"**Video:** {age * 1000:.0f} ms old"

    def _measured(self, source: str, st: dict[str, Any] | None) -> Any:
        link = self.link
        if source == "connected":
            return 1.0 if link.connected else 0.0
        if source == "holds_lease":
            return 1.0 if link.holds_lease else 0.0
        if source == "queue_position":
            return float(link.queue_position or 0)
        if source == "latency":
            return None if link.latency is None else float(link.latency)
        if source == "video_age":
            return link.video_age()
        if st is None:
            return None
        if source in ("joints", "speeds"):
            return np.asarray(st["q" if source == "joints" else "qd"], dtype=float)
        if source == "gripper":
            return float(st["gripper"])
        return str(st.get(source) or "")

    def _send(self, model: Any) -> None:
        now = time.monotonic()
        if now - self._sent_at < 1.0 / self.defn.rate:
            return
        joints = self.defn.joints()
        grip = next((c for c in self.defn.commands or [] if c.to == "gripper"), None)
        q = None if joints is None else np.asarray(getattr(model, joints.var), dtype=float).reshape(-1) * joints.scale
        g = None if grip is None else float(getattr(model, grip.var))
        if q is None:
            st = self.link.state or {}
            q = np.asarray(st.get("q", np.zeros(5)), dtype=float)
        key = tuple(np.round(q, 6)) + ((g,) if g is not None else ())
        if key == self._sent:
            return
        why = self.link.send(q, g)
        if why == BUSY:
            return                              # the one before is still on its way: next frame
        self._sent_at = now
        if why is None:
            self._sent, self.refusal = key, None
        else:
            self.refusal = why

    def _show(self, st: dict[str, Any] | None) -> None:
        link = self.link
        lines = []
        if not link.connected:
            lines.append(f"**Plant:** {escape_markdown(link.note)}")
        elif st is None or not link.plant_online:
            lines.append("**Plant:** offline (no state from the plant)")
        else:
            age = time.monotonic() - link.state_at
            status = escape_markdown(str(st.get("status", "")))
            lines.append(f"**Plant:** {status}" + (f" (no news for {age:.1f} s)" if age > 1.0 else ""))
            if st.get("estop"):
                lines.append("**EMERGENCY STOP is on**: the robot is stopped for everyone")
            if self.real:
                if link.holds_lease:
                    waiting = len(st.get("queue") or [])
                    lines.append("**You control the robot**" + (f" ({st.get('slot_left', 0):.0f} s left: {waiting} waiting)" if waiting else ""))
                elif link.queue_position:
                    lines.append(f"**Waiting for the robot:** you are number {link.queue_position} in the queue")
                else:
                    lines.append("**Watching:** asking for the robot")
            else:
                lines.append("**Simulation:** you watch the real robot; switch to Real plant to drive it")
            if link.latency is not None:
                lines.append(f"**Latency:** {link.latency * 1000:.1f} ms round trip")
            event = st.get("event")
            if event == "lease granted" and not link.holds_lease:
                event = "the robot went to the next in the queue" if st.get("holder") else ""
            if event:
                lines.append(f"*{escape_markdown(str(event))}*")
            if self.refusal and self.real and link.holds_lease:
                lines.append(f"Not sent: {escape_markdown(self.refusal)}")
            refused = st.get("refused") or {}
            if (refused.get("session") == link.session and refused.get("reason")
                    and refused.get("epoch", st.get("epoch")) == st.get("epoch")):
                lines.append(f"Refused by the plant: {escape_markdown(str(refused['reason']))}")
        if self.video is not None and self.real:
            lines.append(self.video_line())
        text = "  \n".join(lines)
        if text != self._shown:
            self.status.content = text
            self._shown = text
        estop = bool(st and st.get("estop") and st.get("estop_by") == link.session)
        if self.rearm_button.visible != estop:
            self.rearm_button.visible = estop

    def clear(self) -> None:
        """Reset: nothing to forget (the plant is real)."""
        self._sent = None

    def close(self) -> None:
        self.link.close()
