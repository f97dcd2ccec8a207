"""FMUs inside a model: the spec's ``fmus:`` section at run time.

A generated app declares its FMUs as ``Model.FMUS = [FmuDef(...), ...]``; the model
(``ejsrl.sim.model.ModelBase``) makes an :class:`Fmus` at every reset (so a reset
re-instantiates each FMU) and calls it around each step:

- **co-simulation**: at a communication point (the model's time reached the FMU's), the
  inputs are read from the model and held; after the evolution pages the FMU advances by
  ``doStep`` to the model's new time (one step, or as many communication steps of
  ``step`` as fit) and its outputs are written into the model variables. The model's
  pages thus see the outputs of the last communication point during a step, as a
  Simulink block with a sample time does (zero-order hold both ways).
- **model exchange**: the FMU's continuous states are appended to the state of an ODE
  page (or of the FMU's own solver when the model has none), so one solver integrates
  both; events follow the FMI state machine (:mod:`ejsrl.fmi._me`): state events are
  located inside the step by the same engine as the spec's own ``events:``
  (:mod:`ejsrl.sim._events`), time events end a step exactly, parameters and discrete
  inputs are set in event mode.

A failing FMU call raises :class:`~ejsrl.sim._errors.UserCodeError` naming the FMU and
the call, with the FMU's own log messages (its warnings and errors) and the spec line of
the FMU, so the app pauses and shows it (a headless run exits non-zero with it). An FMU
that ends the run itself (``terminateSimulation``) pauses it with its message shown as
information. This package imports nothing of :mod:`ejsrl.sim.model`: the model drives it.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ejsrl.fmi._instance import FmuError, FmuInstance, FmuTerminated, read_description, unpacked
from ejsrl.sim._errors import UserCodeError

__all__ = ["FmuDef", "Fmus", "FmuRun"]

_EPS = 1e-9


@dataclass
class FmuDef:
    """One FMU as the spec declares it (the generated app's ``Model.FMUS``).

    ``file``: the ``.fmu`` relative to the app folder; ``kind``: ``"co_simulation"`` or
    ``"model_exchange"``; ``inputs``/``outputs``/``parameters``: FMU variable names, in
    the order of the values that ``read_inputs()`` and ``read_parameters()`` (methods of
    the model) return and ``write_outputs(values)`` takes; ``tunable``: the parameters that
    may change during a run (sent again when their value changes); ``start``: constant
    start values by FMU variable; ``step()``: the communication step (None: one
    ``doStep`` per model step); ``ode``: the index of the evolution page that integrates
    a model-exchange FMU; ``where``: the spec location of the entry.
    """

    name: str
    file: str
    kind: str
    inputs: tuple[str, ...] = ()
    read_inputs: Callable[[], Sequence[Any]] | None = None
    outputs: tuple[str, ...] = ()
    write_outputs: Callable[[Sequence[Any]], None] | None = None
    parameters: tuple[str, ...] = ()
    read_parameters: Callable[[], Sequence[Any]] | None = None
    tunable: tuple[str, ...] = ()
    start: dict[str, Any] = field(default_factory=dict)
    step: Callable[[], float] | None = None
    ode: int | None = None
    method: str = "dopri5"
    tolerance: float = 1e-6
    where: str = ""


class FmuRun:
    """One FMU during one run of the model (from a reset to the next)."""

    def __init__(self, model: Any, spec: FmuDef, base_dir: Path) -> None:
        self.model = model
        self.spec = spec
        self.path = base_dir / spec.file
        self.calls = 0
        self.inst: FmuInstance | None = None
        self.t = 0.0
        self.held: list[Any] | None = None
        self.params: list[Any] = []
        self.x = np.zeros(0)
        self.me: Any = None
        #: the FMU ended the run itself (co-simulation); the message was shown once
        self.terminated: FmuTerminated | None = None
        self.reported = False
        self._h: float | None = None
        self._set_inputs: Callable[[Sequence[Any]], None] | None = None
        self._get_outputs: Callable[[], list[Any]] | None = None

    # -- errors ----------------------------------------------------------------------------
    def _fail(self, exc: FmuError) -> UserCodeError:
        return UserCodeError(str(exc), self.spec.where)

    def guarded(self, fn: Callable[[], Any]) -> Any:
        try:
            return fn()
        except FmuError as exc:
            raise self._fail(exc) from None

    # -- start -----------------------------------------------------------------------------
    def start(self, t0: float, pages: Sequence[Any]) -> None:
        spec = self.spec
        if not self.path.exists():
            raise UserCodeError(f"FMU '{spec.name}': the file {spec.file} is missing from the app folder", spec.where)
        try:
            folder = unpacked(self.path)
            md = read_description(folder)
        except ImportError as exc:  # FMPy missing: say how to install it, at the FMU's spec line
            raise UserCodeError(f"FMU '{spec.name}': {exc}", spec.where) from None
        self.inst = self.guarded(lambda: FmuInstance(folder, md, spec.kind, spec.name))
        inst = self.inst
        self._set_inputs = inst.setter(spec.inputs, "setting inputs") if spec.inputs and spec.read_inputs is not None else None
        self._get_outputs = inst.getter(spec.outputs) if spec.outputs and spec.write_outputs is not None else None
        self.t = float(t0)
        self.params = list(spec.read_parameters()) if spec.read_parameters else []
        structural = [k for k, p in enumerate(spec.parameters) if inst.vars[p].causality == "structuralParameter"]
        sent_inputs: list[Any] = []

        def before() -> None:
            for k in structural:  # first: they size the arrays
                inst.structural[spec.parameters[k]] = self.params[k]
            if structural:
                inst.set_values([spec.parameters[k] for k in structural], [self.params[k] for k in structural], "setting structural parameters")
            if spec.start:
                inst.set_values(list(spec.start), list(spec.start.values()), "setting start values")
            rest = [k for k in range(len(spec.parameters)) if k not in structural]
            if rest:
                inst.set_values([spec.parameters[k] for k in rest], [self.params[k] for k in rest], "setting parameters")

        def during() -> None:
            if spec.inputs and spec.read_inputs is not None:
                values = list(spec.read_inputs())
                inst.set_values(spec.inputs, values, "setting inputs")
                sent_inputs.extend(values)

        try:
            next_event = self.guarded(lambda: inst.initialize(self.t, before, during))
        except FmuTerminated as exc:
            raise UserCodeError(exc.message + " (while initializing)", spec.where) from None
        self.calls += 1
        if spec.kind == "model_exchange":
            from ejsrl.fmi._me import MeCoupling

            self.x = self.guarded(inst.get_states)
            self.me = MeCoupling(self, self._page(pages), next_event)
            if sent_inputs:
                self.me.sent(sent_inputs)
        self.receive_outputs()

    def _page(self, pages: Sequence[Any]) -> Any:
        """The ODE page ``spec.ode`` that integrates a model-exchange FMU's states."""
        spec = self.spec
        if spec.ode is None:
            from ejsrl.fmi._me import OwnPage

            return OwnPage(self.t, spec.method, spec.tolerance, spec.where)
        if not (0 <= spec.ode < len(pages)) or not hasattr(pages[spec.ode], "integrator"):  # an ODE page
            raise UserCodeError(f"FMU '{spec.name}': model exchange needs an ODE page to integrate its states", spec.where)
        return pages[spec.ode]

    def _send_inputs(self) -> None:
        if self._set_inputs is not None:
            self._set_inputs(self.spec.read_inputs())  # type: ignore[misc]

    def receive_outputs(self) -> None:
        """Read the FMU's outputs and write them into the model variables."""
        get = self._get_outputs
        if get is not None:
            try:
                values = get()
            except FmuError as exc:
                raise self._fail(exc) from None
            self.spec.write_outputs(values)  # type: ignore[misc]

    def _send_tunable(self) -> None:
        """Send the tunable parameters whose value changed since they were last sent."""
        spec = self.spec
        if not spec.tunable or spec.read_parameters is None:
            return
        now = list(spec.read_parameters())
        changed = [k for k, (a, b) in enumerate(zip(now, self.params)) if spec.parameters[k] in spec.tunable and not _same(a, b)]
        if changed:
            self.guarded(lambda: self.inst.set_values([spec.parameters[k] for k in changed], [now[k] for k in changed], "setting parameters"))  # type: ignore[union-attr]
            for k in changed:
                self.params[k] = now[k]

    # -- around each step -----------------------------------------------------------------------
    def before_step(self, t: float) -> None:
        """Model exchange: changes go to the FMU in event mode; co-simulation: sample and send
        the inputs if the model is at a communication point."""
        if self.me is not None:
            self.me.before_step(t)
            return
        if self.terminated is not None or self.held is not None:
            return
        if t >= self.t - _EPS * max(1.0, abs(self.t)):
            if self.spec.tunable:
                self._send_tunable()
            if self._set_inputs is not None:
                try:
                    self._set_inputs(self.spec.read_inputs())  # type: ignore[misc]
                except FmuError as exc:
                    raise self._fail(exc) from None
            self.held = []

    def after_step(self, t_new: float) -> None:
        """Co-simulation: advance the FMU to the model's time; model exchange: finish the step."""
        if self.me is not None:
            self.me.after_step(t_new)
            return
        if self.held is None or self.terminated is not None:
            return
        step = self.spec.step
        inst = self.inst
        assert inst is not None
        if step is None:
            h = t_new - self.t
            if h <= 0:
                return
            self._do_step(inst, h)
            self.t = t_new
        else:
            H = float(step())
            if not (H > 0 and math.isfinite(H)):
                raise UserCodeError(f"FMU '{self.spec.name}': the communication step must be a positive number, not {H!r}", self.spec.where)
            if t_new < self.t + H - _EPS * max(1.0, abs(t_new)):
                return  # not yet at the next communication point: inputs stay held
            while t_new >= self.t + H - _EPS * max(1.0, abs(t_new)) and self.terminated is None:
                self._do_step(inst, H)
                self.t += H
        self.held = None
        if self.terminated is not None:
            self._report()
            return
        self.receive_outputs()

    def _do_step(self, inst: FmuInstance, h: float) -> None:
        if not inst.variable_step:  # noqa: SIM102
            if self._h is None:
                self._h = h
            elif abs(h - self._h) > 1e-9 * self._h:
                raise UserCodeError(
                    f"FMU '{self.spec.name}' cannot take a communication step that changes (canHandleVariableCommunicationStepSize is false): "
                    f"it stepped by {self._h:.6g}, now by {h:.6g} at t = {self.t:.6g}",
                    self.spec.where,
                )
        start = len(inst.log)
        try:
            ended = inst.do_step(self.t, h)
        except FmuError as exc:
            raise self._fail(exc) from None
        if ended:
            self.terminated = FmuTerminated(self.spec.name, self.t + h, inst.said(start, 3))
        self.calls += 1

    def _report(self) -> None:
        """The FMU ended the run: its message as information, the model paused, the FMU freed."""
        if self.reported or self.terminated is None:
            return
        self.reported = True
        try:
            self.receive_outputs()
        except UserCodeError:
            pass  # an FMU that stopped may refuse to be read: the model keeps the last outputs
        self.model.alert(self.terminated.message)
        self.model.pause()
        self.free()

    def free(self) -> None:
        if self.inst is not None:
            self.inst.free()


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return bool(np.array_equal(a, b))
    return bool(a == b)


class Fmus:
    """The model's FMUs during one run; freed at the next reset and when the app stops."""

    def __init__(self, model: Any, defs: Sequence[FmuDef], base_dir: Path | None = None) -> None:
        base = Path(base_dir) if base_dir is not None else app_folder(model)
        self.runs = [FmuRun(model, d, base) for d in defs]
        self.model = model
        self._independent: str | None = getattr(model, "INDEPENDENT", None)
        # the instances to free: when closed, or once the model is collected (a browser tab's
        # session that ends), or at exit; the list holds no reference back to the model
        self._instances: list[FmuInstance] = []
        self._finalizer = weakref.finalize(self, _free_all, self._instances)

    def start(self, pages: Sequence[Any]) -> None:
        t0 = self.model._ejs_time() or 0.0
        for run in self.runs:
            try:
                run.start(t0, pages)
            finally:
                if run.inst is not None:
                    self._instances.append(run.inst)

    def before_step(self) -> None:
        t = float(getattr(self.model, self._independent)) if self._independent else 0.0
        for run in self.runs:
            run.before_step(t)

    def after_step(self) -> None:
        t = float(getattr(self.model, self._independent)) if self._independent else 0.0
        for run in self.runs:
            run.after_step(t)

    @property
    def calls(self) -> int:
        """FMI calls of the main kinds so far (doStep, derivatives, completed steps)."""
        return sum(r.calls for r in self.runs)

    def close(self) -> None:
        """Free every FMU instance (and unload its binary)."""
        self._finalizer()

    @property
    def closed(self) -> bool:
        return not self._finalizer.alive


def app_folder(model: Any) -> Path:
    """Where the app's files are: its controller's ``base_dir`` (the app folder, or where a
    ``.pyz`` extracted them), else the folder of the module defining the model."""
    base = getattr(model._ejs_ctl, "base_dir", None)
    if base is not None:
        return Path(base)
    import sys

    module = sys.modules.get(type(model).__module__)
    return Path(getattr(module, "__file__", ".")).resolve().parent


def _free_all(instances: list[FmuInstance]) -> None:
    for inst in instances:
        inst.free()
