"""The base class of every generated ``Model`` and the evolution pages it runs.

A generated app defines ``class Model(ModelBase)`` whose methods are the spec's code,
rewritten: ``_declare`` (initial values), ``_init``, ``_fixed_relations``, the custom
functions, and for each ODE page its state packing, rates and events. ``ModelBase``
runs them in the order the language prescribes and gives the prelude's simulation
controls (``play()``, ``pause()``, ``reset()``, ...) to user code, which calls them as
methods of the model.
"""

from __future__ import annotations

import math
import operator
import sys
import traceback
from collections.abc import Callable, Sequence
from types import TracebackType
from typing import Any, ClassVar

import numpy as np

from ejsrl.sim._errors import UserCodeError
from ejsrl.sim.names import prelude
from ejsrl.sim.world_access import WorldAccess, WorldFunctionsAccess

__all__ = ["ModelBase", "CodePage", "OdePage", "UserCodeError", "SetValueError", "Controller", "locate_error"]


class SetValueError(ValueError):
    """A ``--set`` value that does not fit its variable (found when the variable is declared)."""


class Controller:
    """What the prelude's simulation controls talk to (an app, or a headless run).

    This default is used when a model runs on its own (in tests): play/pause only set a
    flag, alerts are collected, reset and initialize run at once.

    It is also the model's :class:`~ejsrl.sim.world_access.WorldAccess`; this default has
    no scene, so its world functions and ``capture`` raise.

    ``user_values`` are the values the user set from the view (by bind target, in the
    order set), which ``initialize()`` keeps and ``reset()`` forgets.
    """

    def __init__(self) -> None:
        self.playing = False
        self.alerts: list[str] = []
        self.model: ModelBase | None = None
        self.user_values: dict[str, tuple[Callable[[Any, Any], None], Any]] = {}

    def remember_user_value(self, key: str, setter: Callable[[Any, Any], None], value: Any) -> None:
        """Note that the user set ``key`` (a bind target) to ``value``; ``setter(model, value)`` writes it."""
        self.user_values.pop(key, None)  # the latest setting goes last
        self.user_values[key] = (setter, value.copy() if isinstance(value, np.ndarray) else value)

    def restore_user_values(self, model: ModelBase) -> None:
        """Write the values the user set from the view back into ``model``, in the order they were set."""
        for setter, value in self.user_values.values():
            setter(model, value.copy() if isinstance(value, np.ndarray) else value)

    def play(self) -> None:
        self.playing = True

    def pause(self) -> None:
        self.playing = False

    def is_playing(self) -> bool:
        return self.playing

    def step_once(self) -> None:
        if self.model is not None:
            self.model._ejs_step()

    def request_reset(self) -> None:
        self.user_values.clear()
        if self.model is not None:
            self.model._ejs_reset()

    def request_initialize(self) -> None:
        if self.model is not None:
            self.model._ejs_initialize()

    def alert(self, text: str) -> None:
        self.alerts.append(text)

    # -- the world (``WorldAccess``): the app has one; a model on its own has none ---------------
    def capture(self, name: str) -> np.ndarray:
        raise RuntimeError("capture() needs a scene; this model runs without one")

    def capture_depth(self, name: str) -> np.ndarray:
        raise RuntimeError("capture_depth() needs a scene; this model runs without one")

    def world_functions(self) -> WorldFunctionsAccess:
        raise RuntimeError("this model runs without a scene")

    @property
    def world(self) -> Any:
        raise RuntimeError("this model runs without a scene")


class CodePage:
    """An evolution page of plain code: ``fn()`` runs once per step."""

    def __init__(self, name: str, fn: Callable[[], None], enabled: bool = True) -> None:
        self.name = name
        self.fn = fn
        self.enabled = enabled

    def run(self) -> bool:
        if self.enabled:
            self.fn()
        return False

    def restart(self) -> None:
        """Nothing to forget."""


_add_reduce = np.add.reduce  # what ndarray.sum calls, without its Python layer


class OdePage:
    """An evolution page of ODEs, advanced by ``step()`` of its independent variable.

    ``state()`` -> ``(t, y)`` reads the independent variable and the packed state (1-D
    float64); ``load(t, y)`` writes them back into the model; ``rates(t, y)`` gives dy/dt
    (it loads the state and runs the preliminary code first); ``events`` are
    ``ejsrl.sim.ode.EventDef``. ``names`` are the state variables, for messages.
    """

    def __init__(
        self,
        name: str,
        *,
        method: str,
        step: Callable[[], float],
        state: Callable[[], tuple[float, np.ndarray]],
        load: Callable[[float, np.ndarray], None],
        rates: Callable[[float, np.ndarray], np.ndarray],
        names: Sequence[str],
        events: Sequence[Any] = (),
        tolerance: float = 1e-6,
        max_step: float | None = None,
        enabled: bool = True,
        where: str = "",
        event_where: dict[str, str] | None = None,
    ) -> None:
        from ejsrl.sim.ode import OdeIntegrator, ZenoError

        self._zeno_error = ZenoError  # run() names it without an import statement each step
        self.name = name
        self.method = method
        self.step_fn = step
        self.state = state
        self.load = load
        self.names = tuple(names)
        self.enabled = enabled
        self.where = where
        self.event_where = dict(event_where or {})
        self.integrator = OdeIntegrator(rates, method, tolerance=tolerance, max_step=max_step, events=events)
        self.fired: list[tuple[str, float]] = []
        # The step count that keeps the independent variable on t0 + n*h (exact multiples of
        # the step, no round-off accumulated by adding h again and again): the count restarts
        # from the current time whenever the step changes, the time was changed from outside
        # (not the value this page wrote last), or an event stopped the simulation mid-step.
        self._t0 = 0.0
        self._h = math.nan
        self._n = 0
        self._t_last = math.nan

    @classmethod
    def of(
        cls,
        model: Any,
        name: str,
        independent: str,
        states: Sequence[str],
        rates: Callable[[], Sequence[Any]],
        *,
        method: str,
        step: float | Callable[[], float],
        preliminary: Callable[[], None] | None = None,
        events: Sequence[Any] = (),
        tolerance: float = 1e-6,
        max_step: float | None = None,
        enabled: bool = True,
        where: str = "",
        event_where: dict[str, str] | None = None,
    ) -> OdePage:
        """A page integrating the model variables ``states`` over the variable ``independent``.

        The page packs the states (numbers or arrays of any shape, in order) into one vector
        and writes them back itself. ``rates()`` gives one rate per state (a number, or an
        array of the state's shape), computed from the model's variables after the state has
        been written into the model and ``preliminary()`` has run. ``step``: a number or a
        function giving it. ``events``: :class:`~ejsrl.sim.ode.EventDef` whose ``when()``
        and ``action()`` take no arguments (the page writes the state at the event's time into
        the model first; the action changes the model; None: no action) and whose
        ``direction`` may be ``"up"``, ``"down"`` or ``"both"``.
        """
        from ejsrl.sim._layout import StateLayout
        from ejsrl.sim.ode import EventDef

        names = tuple(states)
        read = operator.attrgetter(*names) if len(names) > 1 else (lambda m: (getattr(m, names[0]),))
        layout: list[StateLayout | None] = [None]  # stays None when every state is a number
        numbers: list[bool | None] = [None]  # decided by the first state read, as a state keeps its kind
        # What load() last gave the model: the packed vector and the values it wrote (views of
        # it for arrays). While the model still holds exactly those objects, the vector (seen
        # through the views, so in-place changes count) is the state: state() copies it
        # instead of packing again.
        loaded: list[Any] = [None, ()]
        is_ = operator.is_

        def state() -> tuple[float, np.ndarray]:
            values = read(model)
            if numbers[0] is None:
                numbers[0] = all(np.ndim(v) == 0 and not isinstance(v, np.ndarray) for v in values)
            if numbers[0]:
                return getattr(model, independent), np.array(values, dtype=float)
            y, held = loaded
            if y is not None and all(map(is_, values, held)):
                return getattr(model, independent), y.copy()
            lay = layout[0] = StateLayout.of(layout[0], *values)
            return getattr(model, independent), lay.pack(values)

        first = names[0] if names else ""
        second = names[1] if len(names) == 2 else None

        def load(t: float, y: np.ndarray) -> None:
            setattr(model, independent, t)
            lay = layout[0]
            if lay is None:
                values = y.tolist()
            else:
                values = lay.unpack(y)
                if len(y) == lay.size:  # not the model's part of a longer vector (FMU states appended)
                    loaded[0], loaded[1] = y, values
            if second is not None:  # the common one- and two-state pages without a loop
                setattr(model, first, values[0])
                setattr(model, second, values[1])
            elif len(names) == 1:
                setattr(model, first, values[0])
            else:
                for n, v in zip(names, values):
                    setattr(model, n, v)

        def page_rates(t: float, y: np.ndarray) -> np.ndarray:
            load(t, y)
            if preliminary is not None:
                preliminary()
            got = rates()
            lay = layout[0]
            if lay is None:
                return np.array(got, dtype=float)
            out = np.empty(lay.size)
            if lay.flat:  # a rate of the wrong shape fails to broadcast into its slice
                if second is not None and type(got) is list and len(got) == 2:
                    sl = lay.slices
                    out[sl[0]] = got[0]
                    out[sl[1]] = got[1]
                else:
                    for sl, rate in zip(lay.slices, got):
                        out[sl] = rate
            else:
                for view, rate in zip(lay.views(out), got):
                    view[...] = rate
            return out

        def event(ev: Any) -> EventDef:
            def when(t: float, y: np.ndarray) -> float:
                load(t, y)
                return ev.when()

            def action(t: float, y: np.ndarray) -> np.ndarray:
                load(t, y.copy())
                if ev.action is not None:
                    ev.action()
                return state()[1]

            direction = {"up": 1, "down": -1, "both": 0}.get(ev.direction, ev.direction)
            return EventDef(ev.name, when, direction, action, stop=ev.stop)

        step_fn = step if callable(step) else (lambda: step)
        return cls(
            name, method=method, step=step_fn, state=state, load=load, rates=page_rates, names=names,
            events=[event(e) for e in events], tolerance=tolerance, max_step=max_step, enabled=enabled,
            where=where, event_where=event_where,
        )

    def run(self) -> bool:
        """Advance one step; True if an event asked the simulation to stop."""
        if not self.enabled:
            return False
        h = float(self.step_fn())
        t, y = self.state()
        if t == self._t_last and h == self._h:
            n = self._n + 1
        else:
            self._t0, self._h, n = t, h, 1
        try:
            result = self.integrator.step(t, y, h, self._t0 + n * h)
        except self._zeno_error as exc:
            where = next((w for name, w in self.event_where.items() if f"'{name}'" in str(exc)), self.where)
            raise UserCodeError(str(exc), where) from None
        y_new = result.y
        if not math.isfinite(_add_reduce(y_new)):  # y_new.sum() in one C call; a NaN or inf anywhere makes the sum non-finite
            bad = int(np.flatnonzero(~np.isfinite(y_new))[0])
            raise UserCodeError(
                f"the state became non-finite (element {bad} of {', '.join(self.names)}) near t = {result.t:.6g}; "
                "check the rates for a division by zero or an overflow, or use a smaller step",
                self.where,
            )
        self.load(result.t, y_new.copy())
        self.fired = result.fired
        self._n, self._t_last = n, result.t
        if result.stop:  # the next step counts from the event's time
            self._h = math.nan
        return bool(result.stop)

    def restart(self) -> None:
        """Forget step-size memory and implicit-solver state (the state was changed from outside)."""
        self.integrator.reset()


def locate_error(exc: BaseException, model_cls: type, tb: TracebackType | None = None) -> str:
    """The spec location ``file:line:col`` of the deepest frame of ``exc`` in the app's code."""
    module = sys.modules.get(model_cls.__module__)
    app_file = getattr(module, "__file__", None)
    lines: dict[int, tuple[int, int]] = getattr(model_cls, "SPEC_LINES", {})
    spec = getattr(model_cls, "SPEC", "") or getattr(getattr(module, "META", None), "spec", "")
    where = ""
    for frame, lineno in traceback.walk_tb(tb or exc.__traceback__):
        if app_file is not None and frame.f_code.co_filename == app_file and lineno in lines:
            line, col = lines[lineno]
            where = f"{spec}:{line}:{col}"
    return where


def describe_error(exc: BaseException, model_cls: type) -> UserCodeError:
    """Turn any exception from user code into a ``UserCodeError`` with its spec location."""
    if isinstance(exc, UserCodeError):
        return exc
    where = locate_error(exc, model_cls)
    text = str(exc)
    message = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    return UserCodeError(message, where)


class ModelBase:
    """Base of generated models.

    Class attributes set by the generated code:
    ``VARIABLES`` (name -> value type: ``float``, ``int``, ``bool``, ``str``, ``array``,
    ``object``, or ``auto`` for an ``expr:`` variable), ``INDEPENDENT`` (the independent
    variable of the first ODE page, or ``"t"`` if declared, else None; left out when ``"t"``),
    ``SPEC_LINES`` (app.py line -> (spec line, column), written as the compact text
    :meth:`_ejs_lines` reads, turned into the table when the class is made).
    ``SPEC`` (the spec's file name, for error locations) is left out too: the module's
    ``META.spec`` is read instead.
    """

    SPEC: ClassVar[str] = ""
    SPEC_LINES: ClassVar[dict[int, tuple[int, int]]] = {}
    VARIABLES: ClassVar[dict[str, str]] = {}
    INDEPENDENT: ClassVar[str | None] = "t"
    PROGRAMS: ClassVar[dict[str, Any]] = {}

    def __init__(
        self, controller: Controller | None = None, overrides: dict[str, Any] | None = None, *, start: bool = True
    ) -> None:
        self._ejs_ctl = controller if controller is not None else Controller()
        if getattr(self._ejs_ctl, "model", None) is None:
            self._ejs_ctl.model = self
        self._ejs_overrides = dict(overrides or {})
        self._ejs_pages: list[Any] = []
        self._ejs_programs: Any = None
        self._ejs_fmus: Any = None  # the FMUs of this run (ejsrl.fmi.Fmus), made at each reset
        if self.PROGRAMS:
            from ejsrl.sim.programs import Programs

            self._ejs_programs = Programs(self, self.PROGRAMS)
        if start:
            self._ejs_reset()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if isinstance(cls.__dict__.get("SPEC_LINES"), str):
            cls.SPEC_LINES = ModelBase._ejs_lines(cls.__dict__["SPEC_LINES"])

    @staticmethod
    def _ejs_lines(table: str) -> dict[int, tuple[int, int]]:
        """``SPEC_LINES`` from its compact text: ``"35-44=13:5 48=24:5"`` maps app.py lines
        35..44 to spec lines 13..22 (column 5) and line 48 to spec line 24, column 5."""
        out: dict[int, tuple[int, int]] = {}
        for entry in table.split():
            lines, at = entry.split("=")
            first, _, last = lines.partition("-")
            line, col = (int(v) for v in at.split(":"))
            for k in range(int(last or first) - int(first) + 1):
                out[int(first) + k] = (line + k, col)
        return out

    # -- generated parts (overridden) ----------------------------------------------------
    def _declare(self) -> None:
        """Give every variable its initial value, in declaration order."""

    def _init(self) -> None:
        """The spec's ``init`` code."""

    def _fixed_relations(self) -> None:
        """The spec's ``fixed_relations`` code."""

    def _evolution(self) -> list[Any]:
        """The evolution pages (``CodePage`` / ``OdePage``), freshly built."""
        return []

    def _fmus(self) -> list[Any]:
        """The spec's FMUs (``ejsrl.fmi.FmuDef``), freshly declared."""
        return []

    def _ejs_evolves(self) -> bool:
        """Whether a step can change anything: the model has evolution pages, robot programs or FMUs."""
        return bool(self._ejs_pages) or bool(self.PROGRAMS) or self._ejs_fmus is not None

    # -- lifecycle ------------------------------------------------------------------------
    def _ejs_reset(self, keep: Callable[[], None] | None = None) -> None:
        """Programs stopped, initial values, ``--set`` overrides, fresh solvers, ``init``,
        fixed relations, then the ``autostart`` programs that ``init`` did not start.

        ``init`` (and the custom functions it calls) may start programs with
        ``start_program(name)``: they run from then on.

        ``keep()``, if given, runs right after the variables take their initial values
        (before ``init``), to put back values that a restart keeps.
        """
        programs = self._ejs_programs
        if programs is not None:  # stopped first, so that ``init`` may start some
            programs.stop_all()
        self._ejs_declare()
        if keep is not None:
            keep()
        self._ejs_pages = self._evolution()
        self._init()
        self._ejs_start_fmus()
        self._fixed_relations()
        if programs is not None:
            programs.autostart()

    def _ejs_declare(self) -> None:
        """``_declare`` with the ``--set`` overrides taking each variable's place as it is declared.

        So a later ``expr:`` variable sees the overridden value (``--set N=10`` sizes arrays
        declared from ``N``). An override may be a function of the declared value (for
        ``expr:`` variables, whose type is known only once their expression has given a
        value): it returns the value to use, or raises :class:`SetValueError`. The
        interception lives in a throwaway subclass used only while declaring, so attribute
        writes elsewhere (the hot path) pay nothing.
        """
        overrides = self._ejs_overrides
        if not overrides:
            self._declare()
            return
        cls = type(self)

        def __setattr__(obj: Any, name: str, value: Any) -> None:
            if name in overrides:
                new = overrides[name]
                value = new(value) if callable(new) else new
            object.__setattr__(obj, name, value)

        declaring = type(f"{cls.__name__}Declaring", (cls,), {"__setattr__": __setattr__})
        self.__class__ = declaring
        try:
            self._declare()
        finally:
            self.__class__ = cls
        for name, value in overrides.items():  # variables not declared (cannot happen after validation)
            if not hasattr(self, name):
                setattr(self, name, value)

    def _ejs_initialize(self) -> None:
        """A reset that keeps the user's settings: every variable takes its initial value
        except those the user set from the view, which keep the value set there; then
        fresh solvers, ``init``, the fixed relations, programs stopped."""
        self._ejs_reset(keep=lambda: self._ejs_ctl.restore_user_values(self))

    def _ejs_step(self) -> bool:
        """One simulation step: every page in order, then the fixed relations.

        Returns True if an event with ``stop: true`` fired.
        """
        stop = False
        fmus = self._ejs_fmus
        if fmus is not None:
            fmus.before_step()
        for page in self._ejs_pages:
            stop = page.run() or stop
        if fmus is not None:
            fmus.after_step()
        if self._ejs_programs is not None:
            self._ejs_programs.advance()
        self._fixed_relations()
        return stop

    def _ejs_start_fmus(self) -> None:
        """Free the last run's FMUs and instantiate the spec's afresh (after ``init``, so
        their parameters may come from it); model-exchange FMUs join their ODE page."""
        self._ejs_close()
        defs = self._fmus()
        if defs:
            from ejsrl.fmi import Fmus

            self._ejs_fmus = Fmus(self, defs)
            self._ejs_fmus.start(self._ejs_pages)

    def _ejs_close(self) -> None:
        """Free what the model holds outside Python (its FMU instances); the app calls it when it stops."""
        if self._ejs_fmus is not None:
            self._ejs_fmus.close()
            self._ejs_fmus = None

    def _ejs_restart_solvers(self) -> None:
        for page in self._ejs_pages:
            page.restart()

    def _ejs_time(self) -> float | None:
        """The current value of the independent variable (None if the model has none)."""
        if self.INDEPENDENT is None:
            return None
        return float(getattr(self, self.INDEPENDENT))

    def _ejs_values(self) -> dict[str, Any]:
        """Every variable's current value (for CSV output and tests)."""
        return {name: getattr(self, name) for name in self.VARIABLES}

    # -- the prelude's simulation controls -------------------------------------------------
    @prelude("control")
    def play(self) -> None:
        """Start (or go on with) the simulation."""
        self._ejs_ctl.play()

    @prelude("control")
    def pause(self) -> None:
        """Pause the simulation."""
        self._ejs_ctl.pause()

    @prelude("control")
    def step(self) -> None:
        """Run one simulation step."""
        self._ejs_ctl.step_once()

    @prelude("control")
    def reset(self) -> None:
        """Return every variable to its initial value and run ``init`` (after the current action).

        Values set from the view are forgotten; the simulation pauses.
        """
        self._ejs_ctl.request_reset()

    @prelude("control")
    def initialize(self) -> None:
        """Restart, keeping the user's settings (after the current action).

        Every variable returns to its initial value except those the user set from the
        view (sliders, fields, gizmos), which keep the value set there; then ``init`` and
        the fixed relations run. The simulation goes on playing if it was.
        """
        self._ejs_ctl.request_initialize()

    @prelude("control")
    def is_playing(self) -> bool:
        """True while the simulation runs."""
        return bool(self._ejs_ctl.is_playing())

    @prelude("control")
    def alert(self, text: Any) -> None:
        """Show a message in the UI (printed in headless runs)."""
        from ejsrl.sim._console import prints_quiet

        if not prints_quiet():  # a throw-away run (a served lab's start-up measurement): nobody to tell
            self._ejs_ctl.alert(str(text))

    @prelude("control")
    def clear_trace(self, name: str | None = None) -> None:
        """Erase the drawing panels' `trace` called `name` (every trace when left out): it starts again at its point's next position (EjsS's `trace.clear()`).

        A trace also starts again after `reset()`/`initialize()` and when the independent
        variable goes back; call this when a new run starts with the variable unchanged (a
        relaunch at t = 0). An unnamed trace is `trace1`, `trace2`... in its panel. In a run
        without a view (headless, a sweep) it does nothing.
        """
        from ejsrl.sim._traces import trace_clears

        trace_clears(self._ejs_ctl).request(name)

    @prelude("control")
    def print(self, *values: Any, sep: str | None = " ", end: str | None = "\n", file: Any = None, flush: bool = False) -> None:
        """Print as Python does (the terminal; a headless run's output), and in this tab's ``console`` element, if the lab has one.

        The simulation keeps its last lines (``ejsrl.sim._console.ConsoleLog``); text for
        another ``file`` goes there only.
        """
        import builtins

        from ejsrl.sim._console import console_log, prints_quiet

        if prints_quiet():  # a throw-away run (a served lab's start-up measurement): nobody reads it
            return
        builtins.print(*values, sep=sep, end=end, file=file, flush=flush)
        if file is None or file is sys.stdout:
            text = (" " if sep is None else str(sep)).join(str(v) for v in values) + ("\n" if end is None else str(end))
            console_log(self._ejs_ctl).write(text)

    @property
    def _ejs_world(self) -> WorldAccess:
        """The world as this model's code reaches it: its controller (the app)."""
        return self._ejs_ctl

    @prelude("control")
    def capture(self, name: str) -> np.ndarray:
        """The current RGB image (H, W, 3) uint8 seen by the virtual camera ``name``."""
        return self._ejs_world.capture(name)

    @prelude("control")
    def capture_depth(self, name: str) -> np.ndarray:
        """The current depth image (H, W) float32 of camera ``name``: Z in metres, inf where nothing is seen."""
        return self._ejs_world.capture_depth(name)

    # -- the prelude's world functions (named scene objects) --------------------------------------
    @prelude("world")
    def object_pose(self, name: str) -> np.ndarray:
        """The (4, 4) pose in the world of the scene object ``name``."""
        return self._ejs_world.world_functions().object_pose(name)

    @prelude("world")
    def move_object(self, name: str, pose: Any) -> None:
        """Place the scene object ``name``: a (4, 4) world pose or an [x, y, z] position."""
        self._ejs_world.world_functions().move_object(name, pose)

    @prelude("world")
    def attach(self, name: str, robot: str, link: int | None = None) -> None:
        """Attach the object ``name`` to a link of the robot element ``robot`` (default: its last link).

        The object keeps its pose relative to the link from now on (as when grasped).
        """
        self._ejs_world.world_functions().attach(name, robot, link)

    @prelude("world")
    def release(self, name: str) -> None:
        """Release an attached object where it is now."""
        self._ejs_world.world_functions().release(name)

    @prelude("world")
    def collisions(self) -> list[tuple[str, str]]:
        """The pairs of named scene objects and robot links that touch now (sorted)."""
        return self._ejs_world.world_functions().collisions()

    @prelude("world")
    def set_view(self, position: Any = None, target: Any = None, up: Any = None, fov: float | None = None, *,
                 preset: str | None = None, follow: str | None = None, follow_offset: bool | None = None) -> None:
        """Point the 3D view's camera (every tab of this simulation): `position`, `target`, `up` ([x, y, z]), `fov` (degrees), `preset` (`front`, `top`, ...), `follow` (an object's name, `""` to stop), `follow_offset`; what is left out stays; Restore view undoes it.

        The arguments are those of the scene's ``view`` element (see ``ejsrl.world.view3d``).
        """
        self._ejs_world.world_functions().set_view(position, target, up, fov, preset=preset, follow=follow,
                                                   follow_offset=follow_offset)

    @prelude("program")
    def start_program(self, name: str) -> None:
        """Start the robot program ``name`` (from its first line)."""
        self._ejs_program_runner().start(name)

    @prelude("program")
    def stop_program(self, name: str) -> None:
        """Stop the robot program ``name``."""
        self._ejs_program_runner().stop(name)

    def _ejs_program_runner(self) -> Any:
        if self._ejs_programs is None:
            raise RuntimeError("this model has no robot programs")
        return self._ejs_programs

    def _ejs_program_status(self, name: str) -> str:
        return self._ejs_program_runner().status(name)
