"""A model-exchange FMU during a run, driven as the FMI 2.0 and 3.0 state machines say.

The FMU's continuous states x (shape (nx,)) are appended to the state of an ODE page, so
the page's solver integrates both: at each evaluation of the rates the FMU gets the time,
its states and its *continuous* inputs (continuous-time mode), its outputs go into the
model variables, and its derivatives join the page's rates.

Everything discrete happens in event mode, as FMI requires (FMPy's ``simulateME`` does
the same; :mod:`fmpy.simulation` is the reference):

- **changed parameters and discrete inputs** (tunable parameters; Integer, Boolean,
  String, Binary, Enumeration and discrete Real inputs) are compared with what was sent
  after every step and before the next (a slider moved in between); a change enters event
  mode at that time, sets them, runs the event iteration and returns to continuous time;
- **time events** (the next event time the FMU announced) are events of the page's
  solver whose function crosses zero at exactly that time, so a step ends there and the
  event iteration runs at the announced time itself;
- **state events** (an event indicator changing sign) are events of the page's solver,
  located inside the step like the spec's own ``events:`` (:mod:`ejsrl.sim._events`,
  Illinois/bisection on the method's own interpolant, to 1e-12 (1 + |t|) s); the FMU
  sees the state just past the crossing, as CVode's roots give it;
- **step events** (``completedIntegratorStep`` asking for event mode) after each step;
- **terminateSimulation** ends the run: the FMU is frozen where it stopped, the model
  pauses and shows the FMU's message as information (``alert``), not an error.

After each event the states the FMU changed are read back and the solver restarts.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ejsrl.fmi._instance import FmuError, FmuTerminated

if TYPE_CHECKING:
    from ejsrl.fmi.coupling import FmuRun

__all__ = ["MeCoupling", "OwnPage", "continuous_inputs"]


class OwnPage:
    """The solver of a model-exchange FMU in a model without ODE pages: it holds no model
    state (the FMU's states are appended by :class:`MeCoupling`) and is advanced from the
    FMU's time to the model's after each step of the model (the inputs read as the model
    holds them then). ``method``/``tolerance``: as an ODE page's."""

    def __init__(self, t0: float, method: str, tolerance: float, where: str) -> None:
        from ejsrl.sim.ode import OdeIntegrator

        self.t = float(t0)
        self.integrator = OdeIntegrator(lambda t, y: np.zeros(0), method, tolerance=tolerance)


        self.names: tuple[str, ...] = ()
        self.event_where: dict[str, str] = {}
        self.where = where

    def state(self) -> tuple[float, np.ndarray]:
        return self.t, np.zeros(0)

    def load(self, t: float, y: np.ndarray) -> None:
        self.t = float(t)

    def restart(self) -> None:
        self.integrator.reset()

    def advance(self, t_new: float) -> None:
        """Integrate to the model's time ``t_new`` (events located on the way)."""
        from ejsrl.sim._errors import UserCodeError
        from ejsrl.sim.ode import ZenoError

        t, y = self.state()
        if not t_new > t:
            return
        try:
            result = self.integrator.step(t, y, t_new - t, t_new)
        except ZenoError as exc:
            raise UserCodeError(str(exc), self.where) from None
        self.load(result.t, result.y)


def continuous_inputs(md: Any, names: Sequence[str]) -> list[bool]:
    """For each input name, whether it is continuous (a Real set in continuous-time mode)."""
    by_name = {v.name: v for v in md.modelVariables}
    return [by_name[n].type in ("Real", "Float64", "Float32") and by_name[n].variability == "continuous" for n in names]


#: time events of one FMU within one step beyond which it is taken for Zeno behaviour
MAX_TIME_EVENTS = 100


class TimeEvents:
    """The page's integrator seen through the FMU's time events: a step that holds the next
    announced event time is cut there, exactly; the event iteration runs at that time and
    the rest of the step follows from the state it left (as many events as the step holds).

    ``inner``: the :class:`~ejsrl.sim.ode.OdeIntegrator` (the page's method, its events and
    the FMU's event indicators); the page calls :meth:`step` and :meth:`reset` as on it."""

    def __init__(self, inner: Any, me: MeCoupling) -> None:
        self.inner = inner
        self.me = me
        self.rates, self.method, self.events = inner.rates, inner.method, inner.events
        self.tolerance, self.max_step = inner.tolerance, inner.max_step

    def reset(self) -> None:
        self.inner.reset()

    def step(self, t: float, y: np.ndarray, h: float, t_end: float | None = None) -> Any:
        from ejsrl.sim.ode import StepResult

        me, inner = self.me, self.inner
        t_end = t + h if t_end is None else t_end
        fired: list[tuple[str, float]] = []
        while True:
            te = me.next_event
            if te is None or me.terminated is not None or te > t_end + 1e-12 * (1.0 + abs(t_end)):
                result = inner.step(t, y, t_end - t if fired else h, t_end)
                if fired:
                    result = StepResult(result.t, result.y, fired + result.fired, result.stop)
                return result
            if len(fired) >= MAX_TIME_EVENTS:
                from ejsrl.sim.ode import ZenoError

                raise ZenoError(f"time event of FMU '{me.run.spec.name}' fired more than {MAX_TIME_EVENTS} times in one step at t={t:.12g}: the FMU keeps announcing events at this time")
            if te > t:  # to the event time, exactly
                part = inner.step(t, y, te - t, te)
                fired += part.fired
                if part.stop or part.t < te:
                    return StepResult(part.t, part.y, fired, part.stop)
                y = part.y
            t = max(t, te)
            fired.append((f"time event of FMU '{me.run.spec.name}'", t))
            y = me._event(t, y)
            inner.reset()
            if t >= t_end:
                return StepResult(t_end, y, fired, False)


class MeCoupling:
    """Couples a started model-exchange :class:`FmuRun` to the ODE page ``page``.

    ``next_event``: the time event announced by the initialization (or None).
    """

    def __init__(self, run: FmuRun, page: Any, next_event: float | None) -> None:
        self.run = run
        self.page = page
        inst = run.inst
        assert inst is not None
        self.inst = inst
        #: the next time event the FMU announced (None: none)
        self.next_event = next_event
        self.terminated: FmuTerminated | None = None
        spec = run.spec
        cont = continuous_inputs(inst.md, spec.inputs)
        self._cont_idx = [k for k, c in enumerate(cont) if c]
        self._disc_idx = [k for k, c in enumerate(cont) if not c]
        self._cont_names = [spec.inputs[k] for k in self._cont_idx]
        self._disc_names = [spec.inputs[k] for k in self._disc_idx]
        self._tunable_idx = [k for k, p in enumerate(spec.parameters) if p in spec.tunable]
        self.sent_discrete: list[Any] = []
        self._n_model = 0
        self._eval_key: tuple[float, bytes] | None = None
        self._z = np.zeros(inst.nz)
        self._dx_frozen = np.zeros(inst.nx)
        self._couple()

    # -- the page's integrator ---------------------------------------------------------------
    def _couple(self) -> None:
        from ejsrl.sim.ode import EventDef, OdeIntegrator

        page, run, inst = self.page, self.run, self.inst
        state0, load0, integ = page.state, page.load, page.integrator
        rates0 = integ.rates
        me = self
        own = isinstance(page, OwnPage)
        set_time, set_states, derivatives = inst.fast_calls()
        self._set_time, self._set_states = set_time, set_states
        self._completed = inst.fast_completed_step()
        spec = run.spec
        read_inputs = spec.read_inputs
        all_cont = len(self._cont_idx) == len(spec.inputs)
        set_cont = inst.setter(self._cont_names, "setting inputs") if self._cont_idx else None
        cont_idx = self._cont_idx
        nx = inst.nx

        def send(t: float | None, x: np.ndarray, inputs: bool = True, outputs: bool = True) -> None:
            """The FMU gets the time and its states (unless t is None), (``inputs``) the
            continuous inputs; (``outputs``) its outputs go to the model."""
            if t is not None:
                set_time(t)
                if nx:
                    set_states(x)
            if inputs and set_cont is not None:
                values = read_inputs()  # type: ignore[misc]
                set_cont(values if all_cont else [values[k] for k in cont_idx])
            if outputs:
                run.receive_outputs()

        self._send = send

        def state() -> tuple[float, np.ndarray]:
            t, y = state0()
            me._n_model = len(y)
            return t, np.concatenate((y, run.x))

        def load(t: float, y: np.ndarray) -> None:
            n = me._n_model
            load0(t, y[:n])
            run.x = np.array(y[n:], dtype=float)

        def rates(t: float, y: np.ndarray) -> np.ndarray:
            n = me._n_model
            load0(t, y[:n])
            x = y[n:]
            try:
                if me.terminated is not None:
                    dx = me._dx_frozen
                else:
                    send(t, x)
                    me._eval_key = None
                    dx = derivatives()
            except FmuError as exc:
                raise run._fail(exc) from None
            dy = rates0(t, y[:n])
            run.calls += 1
            return np.concatenate((dy, dx)) if n else dx

        def own_rates(t: float, x: np.ndarray) -> np.ndarray:
            """The FMU's own solver: the model does not change during it (its inputs were sent
            before, its outputs are read after), so the time and states are all it needs."""
            try:
                if me.terminated is not None:
                    return me._dx_frozen
                send(t, x, False, False)
                me._eval_key = None
                run.calls += 1
                return derivatives()
            except FmuError as exc:
                raise run._fail(exc) from None

        def wrap_event(ev: Any) -> Any:
            def when(t: float, y: np.ndarray) -> float:
                return ev.when(t, y[: me._n_model])

            def action(t: float, y: np.ndarray) -> np.ndarray | None:
                new = ev.action(t, y[: me._n_model].copy())
                return None if new is None else np.concatenate((np.asarray(new, dtype=float), y[me._n_model :]))

            return EventDef(ev.name, when, ev.direction, action, ev.stop)

        events = [wrap_event(e) for e in integ.events]
        name = spec.name
        for k in range(inst.nz):
            events.append(EventDef(f"event indicator {k} of FMU '{name}'", self._indicator(k), 0, self._state_event, after=True))
        page.state, page.load = state, load
        method = integ.method if nx or not own else "euler"  # nothing to measure an error on
        inner = OdeIntegrator(
            own_rates if own else rates,
            method,
            tolerance=integ.tolerance,
            max_step=None if math.isinf(integ.max_step) else integ.max_step,
            events=events,
        )
        page.integrator = TimeEvents(inner, self)
        page.names = tuple(page.names) + (f"the states of FMU '{name}'",)
        page.event_where.update({e.name: spec.where for e in events[len(integ.events) :]})
        page.event_where[f"time event of FMU '{name}'"] = spec.where

    def evaluate(self, t: float, x: np.ndarray) -> None:
        """Give the FMU the time, its states and the continuous inputs; write its outputs into
        the model (skipped when the FMU already has exactly this time and state)."""
        if self.terminated is not None:
            return
        key = (t, x.tobytes())
        if key == self._eval_key:
            return
        self._eval_key = None
        try:
            self._send(t, x)
        except FmuError as exc:
            raise self.run._fail(exc) from None
        self._eval_key = key

    def _indicator(self, k: int) -> Any:
        def when(t: float, y: np.ndarray) -> float:
            if self.terminated is not None:
                return float(self._z[k])
            n = self._n_model
            key = (t, y[n:].tobytes())
            if key != self._z_key:
                self.page.load(t, y)  # the model's part too: the FMU's inputs may read it
                self.evaluate(t, y[n:])
                self._z = self.run.guarded(self.inst.event_indicators)
                self._z_key = key
            return float(self._z[k])

        return when

    _z_key: tuple[float, bytes] | None = None

    # -- events --------------------------------------------------------------------------------
    def _state_event(self, t: float, y: np.ndarray) -> np.ndarray:
        return self._event(t, y)


    def _event(self, t: float, y: np.ndarray, changes: Any = None) -> np.ndarray:
        """Event mode at (t, y): the FMU gets them, ``changes()`` sets what changed, the event
        iteration runs, back to continuous time; returns y with the FMU's new states."""
        if self.terminated is not None:
            return y
        run, inst = self.run, self.inst
        n = self._n_model
        self.page.load(t, y)
        self._eval_key = self._z_key = None
        self.evaluate(t, y[n:])
        run.guarded(inst.enter_event_mode)
        if changes is not None:
            run.guarded(changes)
        changed, self.next_event, terminate = run.guarded(inst.event_update)
        self._eval_key = self._z_key = None
        if terminate:
            self._terminate(t)
            return y
        run.guarded(inst.enter_continuous_time_mode)
        x = run.guarded(inst.get_states) if changed else np.asarray(y[n:], dtype=float)
        run.x = x
        run.receive_outputs()
        return np.concatenate((np.asarray(y[:n], dtype=float), x))

    def _terminate(self, t: float) -> None:
        """The FMU ended the run: freeze it, tell the user, pause (at the end of this step)."""
        self.terminated = FmuTerminated(self.run.spec.name, t, self.inst.said(most=3))
        self._dx_frozen = np.zeros(self.inst.nx)
        try:  # its last values (FMI allows reading them after terminateSimulation)
            self.run.receive_outputs()
        except Exception:  # noqa: BLE001 - an FMU that refuses keeps the model's last outputs
            pass

    def _pending(self) -> Any:
        """What changed since it was last sent: tunable parameters and discrete inputs, as a
        function setting them (to call in event mode), or None."""
        run, spec = self.run, self.run.spec
        params: list[tuple[str, Any]] = []
        if self._tunable_idx and spec.read_parameters is not None:
            now = list(spec.read_parameters())
            params = [(spec.parameters[k], now[k]) for k in self._tunable_idx if not _same(now[k], run.params[k])]
            for k in self._tunable_idx:
                run.params[k] = now[k]
        discrete: list[tuple[str, Any]] = []
        if self._disc_idx:
            values = spec.read_inputs()  # type: ignore[misc]
            now_d = [values[k] for k in self._disc_idx]
            discrete = [(nm, v) for nm, v, old in zip(self._disc_names, now_d, self.sent_discrete) if not _same(v, old)]
            if discrete:
                self.sent_discrete = [_copy(v) for v in now_d]
        if not params and not discrete:
            return None
        inst = self.inst

        def changes() -> None:
            if params:
                inst.set_values([p for p, _ in params], [v for _, v in params], "setting parameters")
            if discrete:
                inst.set_values([d for d, _ in discrete], [v for _, v in discrete], "setting inputs")

        return changes

    def _event_now(self, t: float, changes: Any = None) -> None:
        """An event at the model's time t (between steps): the page's state updated, its solver restarted."""
        t0, y = self.page.state()
        y_new = self._event(t, y, changes)
        if self.terminated is None:
            self.page.load(t0, y_new)
        self.page.restart()

    # -- around each step -----------------------------------------------------------------------
    def before_step(self, t: float) -> None:
        """Values changed between steps (by the user: a slider, a field) go to the FMU in event mode."""
        if self.terminated is None:
            changes = self._pending()
            if changes is not None:
                self._event_now(t, changes)

    def after_step(self, t_new: float) -> None:
        """Tell the FMU the step was accepted; a step event it asks for, or parameters and
        discrete inputs the step changed, run the event iteration at the step's end."""
        run, inst = self.run, self.inst
        own = isinstance(self.page, OwnPage)
        if own and self.terminated is None:
            try:  # the inputs, as the model holds them after its step, held over the FMU's
                self._send(None, run.x, True, False)
                self.page.advance(t_new)
                self._send(t_new, run.x, False, True)  # its outputs at the end
            except FmuError as exc:
                raise run._fail(exc) from None
            self._eval_key = (t_new, run.x.tobytes())
        if self.terminated is None:
            if not own:
                self._eval_key = None
                self.evaluate(t_new, run.x)
            if not inst.needs_completed_step:
                enter, terminate = False, False
            else:
                try:
                    enter, terminate = self._completed()
                except FmuError as exc:
                    raise run._fail(exc) from None
            run.calls += 1
            if terminate:
                self._terminate(t_new)
            else:
                changes = self._pending()
                if enter or changes is not None:
                    self._event_now(t_new, changes)
        if self.terminated is not None and not run.reported:
            run.reported = True
            model = run.model
            model.alert(self.terminated.message)
            model.pause()
            run.free()
        run.t = t_new

    def sent(self, values: Sequence[Any]) -> None:
        """Note the discrete inputs sent at initialization (``values``: all the inputs)."""
        self.sent_discrete = [_copy(values[k]) for k in self._disc_idx]


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return bool(np.array_equal(a, b))
    return bool(a == b)


def _copy(v: Any) -> Any:
    return v.copy() if isinstance(v, np.ndarray) else v

