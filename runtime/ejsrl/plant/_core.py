"""The reference plant's safety core: the lease and its queue, the heartbeat watchdog, the e-stop.

One :class:`Plant` serves every transport (MQTT, OPC UA), so the lease is granted by the plant
itself: one holder at a time for the whole class, whichever app process a student's session
runs in. Message schema (JSON over MQTT, the same fields as OPC UA method arguments):

* command  ``{"session": str, "epoch": int, "seq": int, "t": float, "q": [5 x rad], "gripper": 0..1}``
* lease    ``{"session": str, "op": "request" | "release"}``
* heartbeat ``{"session": str}`` (every ``heartbeat`` s; the lease holder and everyone queued)
* estop    ``{"session": str, "on": bool}`` (anyone; ``on: false`` re-arms, by whoever pressed it)
* state    see :meth:`Plant.state`

A command is executed only when it comes from the holder, carries the current lease epoch and a
sequence number above the last one, and passes the plant's own limits: a command that waited in
a broker or a client across a reconnect carries an old epoch or sequence number and is refused.

The watchdog stops the arm when the holder's heartbeat is older than ``watchdog`` s and starts a
new epoch (every command in flight is stale), but the holder keeps the lease until its heartbeat
is ``queue_timeout`` s old: a holder whose heartbeat was late (a loaded machine) goes on with its
program, a holder that is gone hands the plant to the next in line. A command executed from the
holder counts as a heartbeat. ``refused`` is the last refusal (with the epoch it happened in); it
is cleared when the same session's next command is executed and when the lease changes hands.
"""

from __future__ import annotations

import threading
import time
import uuid
from collections import deque
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ._arm import N_JOINTS, Arm, ArmParams

__all__ = ["Plant", "PlantConfig"]


@dataclass(frozen=True)
class PlantConfig:
    """Timing of the plant's safety; every time in s."""

    watchdog: float = 0.5          #: the plant stops when the holder's heartbeat is older than this
    slot: float = 120.0            #: how long one session holds the plant while others wait
    queue_timeout: float = 3.0     #: a queued session, or the holder, without heartbeat this long loses its place
    latency: float = 0.0           #: injected one-way latency of commands into the plant
    noise: float = 2e-4            #: encoder noise, rad (standard deviation)
    dt: float = 0.001              #: integration step of the arm
    clock_offset: float = 0.0      #: added to the plant's clock (its state's and frames' ``t``): another machine's clock


class Plant:
    """The plant: an :class:`Arm` stepped in real time in its own thread, guarded by the lease.

    Thread-safe: transports call :meth:`command`, :meth:`lease`, :meth:`heartbeat`, :meth:`estop`
    and :meth:`state` from their own threads.
    """

    def __init__(self, config: PlantConfig | None = None, params: ArmParams | None = None, *, seed: int | None = None) -> None:
        self.cfg = config or PlantConfig()
        self.arm = Arm(params, noise=self.cfg.noise, seed=seed)
        self.boot = uuid.uuid4().hex[:8]
        self._lock = threading.RLock()
        self.holder: str | None = None
        # a restarted plant starts its lease epochs elsewhere: no command of its former life matches
        self.epoch = int(self.boot, 16) * 1000
        self.slot_end = 0.0
        self.queue: deque[str] = deque()
        self._beats: dict[str, float] = {}
        self._last_seq = -1
        self.estopped = False
        self.estop_by: str | None = None
        self.fault: str | None = None
        self.event = "ready"                       # the last thing the plant did, said to everyone
        self.ack: dict[str, Any] | None = None     # the last command executed: session, seq, t
        self.refused: dict[str, Any] | None = None  # the last command refused and why
        self._pending: deque[tuple[float, dict[str, Any]]] = deque()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.on_tick: Callable[[], None] | None = None
        self.stopped_at: float | None = None       # monotonic time the arm came to rest after a stop
        self._rearm_after_watchdog = False
        self._watchdog_tripped = False             # the watchdog stopped the current holder's arm

    # ---- the plant's clock ------------------------------------------------------------------
    def clock(self) -> float:
        """The plant's clock, s: the times in its state and its camera's frames (another
        machine's clock for the app: monotonic here, shifted by ``clock_offset``)."""
        return time.monotonic() + self.cfg.clock_offset

    def pose(self) -> tuple[float, np.ndarray]:
        """``(t, q)``: the plant's clock and the arm's true joint angles (5,) rad, for its camera."""
        with self._lock:
            return self.clock(), self.arm.q.copy()

    # ---- the lease --------------------------------------------------------------------------
    def lease(self, session: str, op: str) -> dict[str, Any]:
        """Request or release the lease for ``session``; returns the lease part of the state."""
        session = str(session)[:64]
        now = time.monotonic()
        with self._lock:
            if op == "request":
                self._beats[session] = now
                if self.holder != session and session not in self.queue:
                    self.queue.append(session)
                self._grant(now)
            elif op == "release":
                if self.holder == session:
                    self._revoke("released by its holder", now)
                elif session in self.queue:
                    self.queue.remove(session)
                self._beats.pop(session, None)
            return self._lease_state(now)

    def _grant(self, now: float) -> None:
        while self.holder is None and self.queue:
            nxt = self.queue.popleft()
            if now - self._beats.get(nxt, -1e9) > self.cfg.queue_timeout:
                continue
            self.holder = nxt
            self.epoch += 1
            self._last_seq = -1
            self.slot_end = now + self.cfg.slot
            self.refused = None
            self._watchdog_tripped = False
            self.event = "lease granted"

    def _revoke(self, why: str, now: float) -> None:
        self.holder = None
        self.epoch += 1          # every command of the old lease is stale from now on
        self.refused = None
        self.event = why
        self._grant(now)

    def heartbeat(self, session: str) -> None:
        with self._lock:
            self._beats[str(session)[:64]] = time.monotonic()

    # ---- commands ---------------------------------------------------------------------------
    def command(self, msg: dict[str, Any]) -> str | None:
        """Queue a command through the injected latency; returns why it is refused at once, or None."""
        with self._lock:
            if self.cfg.latency > 0:
                self._pending.append((time.monotonic() + self.cfg.latency, msg))
                return None
            return self._execute(msg)

    def _execute(self, msg: dict[str, Any]) -> str | None:
        session = str(msg.get("session", ""))[:64]
        try:
            epoch, seq = int(msg["epoch"]), int(msg["seq"])
            q = np.asarray(msg["q"], dtype=float).reshape(-1)
            grip = float(msg.get("gripper", self.arm.gripper))
        except (KeyError, TypeError, ValueError):
            return self._refuse(msg, "a command needs epoch, seq and q")
        if self.estopped:
            return self._refuse(msg, "emergency stop is on")
        if self.fault:
            return self._refuse(msg, f"plant fault: {self.fault}")
        if session != self.holder:
            return self._refuse(msg, "this session does not hold the plant")
        if epoch != self.epoch or seq <= self._last_seq:
            return self._refuse(msg, "stale command (from an earlier lease or already superseded)")
        why = self.arm.check(q) if q.shape == (N_JOINTS,) else f"a set point is {N_JOINTS} joint angles"
        if why is None and not 0.0 <= grip <= 1.0:
            why = "the gripper opening is between 0 and 1"
        if why:
            return self._refuse(msg, why)
        self._last_seq = seq
        self._beats[session] = time.monotonic()     # the holder's command says it is alive
        if self.refused is not None and self.refused.get("session") == session:
            self.refused = None                     # superseded: this session's commands go through again
        self.arm.q_set = q.copy()
        self.arm.gripper = grip
        self.ack = {"session": session, "seq": seq, "t": msg.get("t")}
        return None

    def _refuse(self, msg: dict[str, Any], why: str) -> str:
        self.refused = {"session": str(msg.get("session", ""))[:64], "seq": msg.get("seq"), "reason": why,
                        "epoch": self.epoch}
        return why

    # ---- stops ------------------------------------------------------------------------------
    def estop(self, session: str, on: bool = True) -> None:
        """Emergency stop (anyone may press it; the arm brakes to rest and holds) or re-arm (only
        the session that pressed it: a teacher's stop is not undone by a student)."""
        with self._lock:
            if on:
                if not self.estopped:
                    self.stopped_at = None
                self.estopped, self.estop_by = True, str(session)[:64]
                self.arm.braking = True
                self.event = "emergency stop"
            elif self.estopped and str(session)[:64] != self.estop_by:
                self.event = "only who pressed the emergency stop can re-arm the plant"
            else:
                self.estopped, self.estop_by = False, None
                self.arm.braking = False
                self.event = "re-armed after the emergency stop"

    def inject_fault(self, text: str | None) -> None:
        """Put the plant in fault (it brakes and refuses commands) or clear the fault with None."""
        with self._lock:
            self.fault = text
            self.arm.braking = bool(text) or self.estopped
            if text:
                self.stopped_at = None
                self.event = f"fault: {text}"

    def _watchdog(self, now: float) -> None:
        if self.holder is not None:
            age = now - self._beats.get(self.holder, -1e9)
            if age > max(self.cfg.queue_timeout, self.cfg.watchdog):
                self._revoke(f"the holder was silent for {age:.1f} s: the lease passed on", now)
            elif age > self.cfg.watchdog and not self._watchdog_tripped:
                # stop now; the holder keeps the lease (a new epoch) until it is silent queue_timeout s
                self.arm.braking = True
                self.stopped_at = None
                self.epoch += 1
                self._last_seq = -1
                self.event = f"watchdog: no heartbeat from the holder for {age:.2f} s; plant stopped"
                self._watchdog_tripped = True
                self._rearm_after_watchdog = True
            elif age <= self.cfg.watchdog and self._watchdog_tripped:
                self._watchdog_tripped = False          # the heartbeat is back: the holder goes on
            if self.holder is not None and now > self.slot_end and self.queue:
                self._revoke("the holder's slot ended", now)
        for s in [s for s in self.queue if now - self._beats.get(s, -1e9) > self.cfg.queue_timeout]:
            self.queue.remove(s)

    # ---- the real-time loop -----------------------------------------------------------------
    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="ejsrl-plant", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread:
            self._thread.join(2.0)

    def _run(self) -> None:
        last = time.monotonic()
        while not self._stop.is_set():
            time.sleep(0.002)
            now = time.monotonic()
            with self._lock:
                while self._pending and self._pending[0][0] <= now:
                    self._execute(self._pending.popleft()[1])
                self._watchdog(now)
                elapsed = min(now - last, 0.1)
                n = max(1, int(round(elapsed / self.cfg.dt)))
                for _ in range(n):
                    self.arm.step(elapsed / n)
                if self.arm.braking and self.stopped_at is None and not self.arm.moving():
                    self.stopped_at = now
                    if getattr(self, "_rearm_after_watchdog", False) and not self.estopped and not self.fault:
                        # stopped by the watchdog: hold position; the next holder starts from rest
                        self.arm.braking = False
                        self._rearm_after_watchdog = False
            last = now
            if self.on_tick:
                self.on_tick()

    def _lease_state(self, now: float) -> dict[str, Any]:
        return {"holder": self.holder, "epoch": self.epoch, "queue": list(self.queue),
                "slot_left": max(0.0, self.slot_end - now) if self.holder else 0.0}

    def state(self) -> dict[str, Any]:
        """The plant's state as every client sees it: measured joints (rad), speeds (rad/s),
        gripper (0..1), ``status`` (``moving``/``idle``/``stopping``/``estop``/``fault``), the lease
        (``holder``, ``epoch``, ``queue``, ``slot_left`` s), ``estop``, ``fault``, ``event``,
        the last executed command ``ack`` (echoing the sender's ``t`` for its round trip) and
        the last ``refused`` one, ``boot`` (changes when the plant restarts) and ``t`` (plant clock, s)."""
        now = time.monotonic()
        with self._lock:
            q, qd = self.arm.measure()
            moving = self.arm.moving()
            status = ("fault" if self.fault else "estop" if self.estopped
                      else "stopping" if self.arm.braking and moving else "moving" if moving else "idle")
            return {"t": now + self.cfg.clock_offset, "boot": self.boot, "q": q.tolist(), "qd": qd.tolist(), "gripper": self.arm.gripper,
                    "status": status, "estop": self.estopped, "estop_by": self.estop_by, "fault": self.fault, "event": self.event,
                    "ack": self.ack, "refused": self.refused, **self._lease_state(now)}
