"""A small stand-in for ``ejsrl.app.App`` with the interface the viser view uses.

Used by the view's unit tests (no loop thread) and by the browser harness (with
:meth:`FakeApp.start`, a loop thread like the real app's).
"""

from __future__ import annotations

import threading
import time
from types import SimpleNamespace
from typing import Any

from ejsrl.view.elements import value_of


class FakeApp:
    def __init__(self, model: Any, view: list, world: Any = None, *, title: str = "Test lab",
                 description: str = "A **test** lab.", controls: bool = True, fps: float = 30.0,
                 step: Any = None, init: Any = None) -> None:
        self.model = model
        self.view = view
        self.world = world
        self.lock = threading.RLock()
        self.meta = SimpleNamespace(title=title, description=description, author="Tester", spec="test.ejs.yaml")
        self.sim = SimpleNamespace(fps=fps, steps_per_display=1, autoplay=False, realtime=False, controls=controls)
        self.error: Any = None
        self.error_rev = 0
        self.alerts: list[str] = []
        self.applied: list[tuple[Any, Any]] = []
        self.actions: list[Any] = []
        self.gizmos: list[tuple[str, Any]] = []
        self.viewer: Any = None
        self._step = step or (lambda m: setattr(m, "t", m.t + 0.1))
        self._init = init
        self._playing = False
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # -- the simulation -------------------------------------------------------------------
    def play(self) -> None:
        self._playing = True

    def pause(self) -> None:
        self._playing = False

    def is_playing(self) -> bool:
        return self._playing

    def step_once(self) -> None:
        with self.lock:
            self._guarded_step()
            self._frame()

    def reset(self) -> None:
        with self.lock:
            self._playing = False
            if self._init is not None:
                self._init(self.model)
            else:
                self.model.t = 0.0
            if self.error is not None:
                self.error = None
                self.error_rev += 1
            if self.viewer is not None:
                self.viewer.on_reset()
            self._frame()

    def _guarded_step(self) -> None:
        try:
            self._step(self.model)
        except Exception as exc:
            self._fail(exc, "test.ejs.yaml:10:5")

    def _fail(self, exc: Exception, where: str) -> None:
        self._playing = False
        self.error = SimpleNamespace(message=f"{type(exc).__name__}: {exc}", where=where)
        self.error_rev += 1

    def _frame(self) -> None:
        if self.viewer is not None:
            self.viewer.on_frame()

    # -- what the view calls -----------------------------------------------------------------
    def apply_control(self, control: Any, value: Any) -> None:
        with self.lock:
            control.set(self.model, value)
            if control.on_change is not None:
                control.on_change(self.model)
            self.applied.append((control.bind, value))
            self._frame()

    def run_action(self, button: Any) -> None:
        with self.lock:
            button.action(self.model)
            self.actions.append(button.label)
            self._frame()

    def apply_gizmo(self, name: str, T_world: Any) -> None:
        with self.lock:
            self.gizmos.append((name, T_world))

    def safe_value(self, prop: Any, where: str) -> Any:
        try:
            return value_of(prop, self.model)
        except Exception as exc:
            self._fail(exc, where)
            return None

    def pop_alerts(self) -> list[str]:
        out, self.alerts = self.alerts, []
        return out

    # -- a loop thread, as the real app runs ---------------------------------------------------
    def start(self) -> None:
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)

    def _loop(self) -> None:
        period = 1.0 / self.sim.fps
        while not self._stop.is_set():
            t0 = time.monotonic()
            with self.lock:
                if self._playing:
                    self._guarded_step()
                self._frame()
            self._stop.wait(max(0.0, period - (time.monotonic() - t0)))
