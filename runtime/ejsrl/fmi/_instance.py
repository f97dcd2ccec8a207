"""One FMU instance through FMPy, FMI 2.0 or 3.0, co-simulation or model exchange.

``FmuInstance`` hides the differences between the versions behind the few calls a
simulation makes (set and get values by name, ``do_step``, the model-exchange calls),
collects what the FMU logs, and turns a failing call into :class:`FmuError` carrying the
FMU's own messages. FMPy is imported lazily: an app without FMUs never needs it.
"""

from __future__ import annotations

import atexit
import shutil
import itertools
import threading
import weakref
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ejsrl.fmi._fast import STATUS as _STATUS
from ejsrl.fmi._fast import FastCalls

__all__ = ["FmuError", "FmuTerminated", "FmuInstance", "load_fmpy", "read_description", "unpacked", "INSTALL_HINT", "PLATFORM_DIRS"]

INSTALL_HINT = "FMUs need FMPy: pip install 'ejsgen[fmu]' (or pip install fmpy)"


#: messages of the FMU's log kept (the latest), characters kept of each, messages shown with an error
LOG_KEEP, LOG_CHARS, LOG_SHOWN = 50, 300, 5


#: FMI 2 logging. FMPy's printf-formatting shim (fmpy.logging.addLoggerProxy) keeps ONE logger
#: per process, replaced at every call: a second instance (a second lab in the same process,
#: or FMPy's own default callbacks) would take over the first's messages, or get none. So the
#: shim is given one dispatcher, once per process, which routes each message by the
#: componentEnvironment the FMU hands back (a key per instance) and passes any other (FMPy's
#: default callbacks, whose environment is NULL) to FMPy's own printLogMessage, as FMPy would.
_LOG_KEYS = itertools.count(1)
_LOGGERS: dict[int, Any] = {}
_PROXY: list[Any] = []  # [the shim's logger function pointer, the dispatcher kept alive] or [None]


def _dispatch_fmi2_log(env: Any, instance_name: bytes | None, status: int, category: bytes | None, message: bytes | None) -> None:
    ref = _LOGGERS.get(env) if env else None
    target = ref() if ref is not None else None
    if target is not None:
        target._logger_text(status, category, message)
        return
    try:
        from fmpy.fmi1 import printLogMessage

        printLogMessage(env, instance_name, status, category, message)
    except Exception:  # noqa: BLE001 - a logger must never raise into the FMU
        pass


def _fmi2_log_proxy(fmi2: Any) -> Any:
    """The logger to give an FMI 2 FMU: FMPy's formatting shim routed to ``_dispatch_fmi2_log``
    (installed again before each instance, should other code have replaced the shim's logger);
    None without the shim."""
    from ctypes import byref

    try:
        from fmpy.logging import addLoggerProxy
    except Exception:  # noqa: BLE001
        return None
    if not _PROXY:
        dispatcher = fmi2.fmi2CallbackLoggerTYPE(_dispatch_fmi2_log)
        _PROXY.append(dispatcher)
    holder = fmi2.fmi2CallbackFunctions()
    holder.logger = _PROXY[0]
    try:
        addLoggerProxy(byref(holder))  # the shim keeps the dispatcher, gives back its own function
    except Exception:  # noqa: BLE001
        return None
    return holder.logger


_INTEGERS = {"Integer", "Enumeration", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64"}


class FmuError(RuntimeError):
    """A failing FMU call; ``log`` holds the FMU's own messages of that call."""

    def __init__(self, message: str, log: Sequence[str] = ()) -> None:
        self.log = list(log)
        text = message + (": " + "; ".join(self.log) if self.log else "")
        super().__init__(text)


class FmuTerminated(Exception):
    """The FMU ended the run itself (``terminateSimulation``): information, not an error.

    ``message``: what to show (the FMU, the time, and its own reason if it logged one)."""

    def __init__(self, name: str, t: float, said: Sequence[str] = ()) -> None:
        reason = "; ".join(said)
        self.message = f"FMU '{name}' ended the simulation at t = {t:.6g}" + (f": {reason}" if reason else "")
        super().__init__(self.message)


def load_fmpy() -> Any:
    """The ``fmpy`` module, or an ``ImportError`` that says how to install it."""
    try:
        import fmpy
    except ImportError as exc:  # pragma: no cover - the test extra installs it
        raise ImportError(INSTALL_HINT) from exc
    return fmpy


def PLATFORM_DIRS() -> tuple[str, str]:  # noqa: N802 - reads like the constant it stands for
    """The binaries/ folder names of this platform: FMI 2.0's (``linux64``) and FMI 3.0's (``x86_64-linux``)."""
    fmpy = load_fmpy()
    return fmpy.platform, fmpy.platform_tuple


_unpacked: dict[tuple[str, int, int], Path] = {}
_lock = threading.Lock()


def unpacked(fmu: Path) -> Path:
    """The folder the ``.fmu`` is extracted to (once per process and file version; removed at exit).

    A folder (an FMU already unpacked) is returned as it is.
    """
    fmu = Path(fmu)
    if fmu.is_dir():
        return fmu
    stat = fmu.stat()
    key = (str(fmu.resolve()), stat.st_mtime_ns, stat.st_size)
    with _lock:
        folder = _unpacked.get(key)
        if folder is None or not folder.is_dir():
            fmpy = load_fmpy()
            folder = Path(fmpy.extract(str(fmu)))
            _unpacked[key] = folder
            atexit.register(shutil.rmtree, folder, True)
    return folder


def read_description(fmu: Path) -> Any:
    """FMPy's ``ModelDescription`` of an ``.fmu`` file or an unpacked FMU folder."""
    fmpy = load_fmpy()
    return fmpy.read_model_description(str(fmu), validate=False)


class FmuInstance(FastCalls):
    """An instantiated FMU: ``kind`` is ``"co_simulation"`` or ``"model_exchange"``.

    ``folder``: the unpacked FMU; ``description``: its FMPy ``ModelDescription``;
    ``name``: the instance name (the spec's name for the FMU).
    """

    def __init__(self, folder: Path, description: Any, kind: str, name: str) -> None:
        self.folder = Path(folder)
        self.md = description
        self.kind = kind
        self.name = name
        self.version = 3 if description.fmiVersion.startswith("3") else 2
        self.log: list[str] = []
        self.vars = {v.name: v for v in description.modelVariables}
        self.nx = int(getattr(description, "numberOfContinuousStates", None) or len(description.derivatives))  # FMI 3 arrays count each element
        self.nz = int(description.numberOfEventIndicators or 0)
        self._fmu: Any = None
        self._callbacks: Any = None
        self._freed = False
        self._groups: dict[tuple[str, ...], dict[str, list[tuple[int, int]]]] = {}
        self._buffers: dict[tuple[Any, ...], tuple[Any, Any, Any]] = {}
        self._xbufs: tuple[np.ndarray, Any, np.ndarray, Any] | None = None
        self._zbuf: tuple[np.ndarray, Any] | None = None
        #: values of the structural parameters set (they size the FMI 3 arrays)
        self.structural: dict[str, Any] = {}
        self._do_step_fn: Any = None
        interface = description.coSimulation if kind == "co_simulation" else description.modelExchange
        #: capability flags: a changing communication step; completedIntegratorStep needed
        self.variable_step = bool(getattr(interface, "canHandleVariableCommunicationStepSize", True)) if kind == "co_simulation" else True
        self.needs_completed_step = bool(getattr(interface, "needsCompletedIntegratorStep", True)) if kind == "model_exchange" else False
        self._once = bool(getattr(interface, "canBeInstantiatedOnlyOncePerProcess", False))
        if self._once:
            _claim_once(self.folder, name)
        try:
            self._instantiate()
        except BaseException:
            if self._once:
                _release_once(self.folder)
            raise

    # -- calls, each turning a failure into FmuError with the FMU's messages -----------------
    def call(self, what: str, fn: Any, *args: Any) -> Any:
        """``fn(*args)``; a failure raises :class:`FmuError` naming ``what`` and what the FMU logged."""
        if self._freed:
            raise FmuError(f"FMU '{self.name}': {what} after the FMU was freed (the app stopped)")
        start = len(self.log)
        try:
            return fn(*args)
        except Exception as exc:  # noqa: BLE001 - FMPy raises FMICallException or plain Exception
            said = self.said(start)
            status = getattr(exc, "status", None)
            how = f"returned {_STATUS[status]}" if isinstance(status, int) and 0 <= status < len(_STATUS) else f"failed ({exc})"
            function = getattr(exc, "function", None)  # FMPy's FMICallException names the FMI function
            if isinstance(function, str) and function != what:
                what = f"{what}: {function}"
            raise FmuError(f"FMU '{self.name}': {what} {how}", said) from None

    def _logger_text(self, status: int, category: bytes | None, message: bytes | None) -> None:
        """The FMU's logger: warnings and errors are kept (the latest ``LOG_KEEP``, each cut
        to ``LOG_CHARS`` characters); the FMU's OK messages (its call trace) are dropped."""
        if status == 0:
            return
        label = _STATUS[status] if 0 <= status < len(_STATUS) else str(status)
        text = " ".join((message or b"").decode("utf-8", "replace").split())
        if len(text) > LOG_CHARS:
            text = text[: LOG_CHARS - 1] + "…"
        self.log.append(f"{label}: {text}")
        del self.log[:-LOG_KEEP]

    def said(self, start: int = 0, most: int = LOG_SHOWN) -> list[str]:
        """What the FMU logged since ``start`` (an index into ``log``), the last ``most`` messages."""
        return [m.split(": ", 1)[1] for m in self.log[start:]][-most:]

    def _log_categories(self) -> list[str]:
        """The FMU's log categories for warnings and errors (all of them if it names none such)."""
        names = [c.name for c in getattr(self.md, "logCategories", []) or []]
        keep = [n for n in names if any(w in n.lower() for w in ("warning", "error", "fatal", "discard", "pending"))]
        return keep

    def _instantiate(self) -> None:
        fmpy = load_fmpy()
        md = self.md
        cs = self.kind == "co_simulation"
        interface = md.coSimulation if cs else md.modelExchange
        common = dict(guid=md.guid, unzipDirectory=str(self.folder), modelIdentifier=interface.modelIdentifier, instanceName=self.name)
        if self.version == 2:
            from ctypes import byref

            from fmpy import fmi2

            cls = fmi2.FMU2Slave if cs else fmi2.FMU2Model
            fmu = self.call("loading the binary", lambda: cls(**common))
            callbacks = fmi2.fmi2CallbackFunctions()
            callbacks.allocateMemory = fmi2.fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
            callbacks.freeMemory = fmi2.fmi2CallbackFreeMemoryTYPE(fmpy.free)
            # the FMU hands componentEnvironment back to the logger: the key of this instance
            self._log_key = next(_LOG_KEYS)
            callbacks.componentEnvironment = self._log_key
            proxy = _fmi2_log_proxy(fmi2)
            if proxy is not None:
                callbacks.logger = proxy
                _LOGGERS[self._log_key] = weakref.ref(self)
            else:  # FMPy without its logging shim: messages unformatted, this instance's own callback
                callbacks.logger = fmi2.fmi2CallbackLoggerTYPE(lambda env, inst, status, cat, msg: self._logger_text(status, cat, msg))
            self._callbacks = callbacks
            self.call("fmi2Instantiate", fmu.instantiate, False, callbacks, True)
        else:
            from fmpy import fmi3

            cls = fmi3.FMU3Slave if cs else fmi3.FMU3Model
            fmu = self.call("loading the binary", lambda: cls(**common))
            self.call(
                "fmi3Instantiate",
                lambda: fmu.instantiate(loggingOn=True, logMessage=lambda env, status, cat, msg: self._logger_text(status, cat, msg)),
            )
        self._fmu = fmu
        categories = self._log_categories()
        if categories:  # only the categories of warnings and errors: no call trace through Python
            try:
                fmu.setDebugLogging(True, categories)
            except Exception:  # noqa: BLE001 - an FMU that refuses keeps logging all: filtered by status
                pass

    # -- values by name -----------------------------------------------------------------------
    def shape(self, name: str) -> tuple[int, ...]:
        """The shape of variable ``name``: () for a scalar, an FMI 3 array's dimensions otherwise
        (a dimension given by a structural parameter takes the value set, else its start)."""
        v = self.vars[name]
        dims = getattr(v, "dimensions", None) or []
        out = []
        for d in dims:
            if d.start is not None:
                out.append(int(d.start))
            else:
                ref = d.variable
                out.append(int(self.structural.get(ref.name, ref.start)))
        return tuple(out)

    def _typed(self, names: Sequence[str]) -> dict[str, list[tuple[int, int]]]:
        """Value references grouped by type: type -> [(position in names, value reference)]."""
        key = tuple(names)
        groups = self._groups.get(key)
        if groups is None:
            groups = {}
            for k, n in enumerate(names):
                v = self.vars[n]
                kind = v.type if not self.shape(n) else v.type + "[]"
                groups.setdefault(kind, []).append((k, v.valueReference))
            self._groups[key] = groups
        return groups

    def _reals(self, names: Sequence[str], items: list[tuple[int, int]]) -> tuple[Any, Any, Any]:
        """For a group of 64-bit reals: (value references as a C array, their count, a value buffer),
        made once per list of names (FMPy's getReal/setReal build them at every call)."""
        key = (tuple(names), "reals")
        got = self._buffers.get(key)
        if got is None:
            from ctypes import c_double, c_uint

            n = len(items)
            got = ((c_uint * n)(*[vr for _, vr in items]), n, (c_double * n)())
            self._buffers[key] = got
        return got

    def _accessor(self, vtype: str, verb: str) -> Any:
        """FMPy's ``setX``/``getX`` of an FMI type (FMI 2 Enumerations are Integers, FMI 3's Int64s)."""
        if self.version == 2:
            name = {"Enumeration": "Integer"}.get(vtype, vtype)
        else:
            name = {"Enumeration": "Int64"}.get(vtype, vtype)
        return getattr(self._fmu, verb + name)

    def set_values(self, names: Sequence[str], values: Sequence[Any], what: str = "setting values") -> None:
        """Set FMU variables by name: numbers, booleans, text or bytes (Binary) by the variable's
        type; an FMI 3 array takes an array of its shape (row-major), checked here."""
        f = self._fmu
        for vtype, items in self._typed(names).items():
            if vtype in ("Real", "Float64"):
                vr_array, n, buf = self._reals(names, items)
                for j, (k, _) in enumerate(items):
                    buf[j] = float(values[k])
                if self.version == 2:
                    self.call(what, f.fmi2SetReal, f.component, vr_array, n, buf)
                else:
                    self.call(what, f.fmi3SetFloat64, f.component, vr_array, n, buf, n)
                continue
            base = vtype.removesuffix("[]")
            vrs = [vr for _, vr in items]
            flat: list[Any] = []
            for k, _ in items:
                value = values[k]
                if vtype.endswith("[]"):
                    want = self.shape(names[k])
                    arr = np.asarray(value)
                    if arr.shape != want:
                        raise FmuError(f"FMU '{self.name}': {what}: '{names[k]}' is an array of shape {want}, not of shape {arr.shape}")
                    flat.extend(arr.ravel().tolist())
                else:
                    if np.ndim(value) != 0 and not isinstance(value, (str, bytes)):
                        raise FmuError(f"FMU '{self.name}': {what}: '{names[k]}' is a single {base}, not an array of shape {np.shape(value)}")
                    flat.append(value)
            if base in ("Real", "Float64", "Float32"):
                flat = [float(x) for x in flat]
            elif base == "Boolean":
                flat = [bool(x) for x in flat]
            elif base == "String":  # FMPy encodes the text
                flat = [x.decode("utf-8") if isinstance(x, bytes) else str(x) for x in flat]
            elif base == "Binary":
                flat = [x.encode() if isinstance(x, str) else bytes(x) for x in flat]
            elif base in _INTEGERS:
                flat = [int(x) for x in flat]
            else:
                raise FmuError(f"FMU '{self.name}': cannot set variables of type {base}")
            self.call(what, self._accessor(base, "set"), vrs, flat)

    def get_values(self, names: Sequence[str], what: str = "reading outputs") -> list[Any]:
        """The FMU variables' values, in the order of ``names`` (an FMI 3 array as a new
        ndarray of its shape, a Binary as bytes, a String as str)."""
        f = self._fmu
        out: list[Any] = [None] * len(names)
        for vtype, items in self._typed(names).items():
            if vtype in ("Real", "Float64"):
                vr_array, n, buf = self._reals(names, items)
                if self.version == 2:
                    self.call(what, f.fmi2GetReal, f.component, vr_array, n, buf)
                else:
                    self.call(what, f.fmi3GetFloat64, f.component, vr_array, n, buf, n)
                for j, (k, _) in enumerate(items):
                    out[k] = buf[j]
                continue
            base = vtype.removesuffix("[]")
            vrs = [vr for _, vr in items]
            fn = self._accessor(base, "get")
            if vtype.endswith("[]"):
                shapes = [self.shape(names[k]) for k, _ in items]
                sizes = [int(np.prod(sh)) for sh in shapes]
                got = list(self.call(what, fn, vrs, sum(sizes)))
                at = 0
                for (k, _), sh, size in zip(items, shapes, sizes):
                    out[k] = np.array(got[at : at + size]).reshape(sh)
                    at += size
                continue
            got = self.call(what, fn, vrs)
            for (k, _), value in zip(items, got):
                if base == "String" and isinstance(value, bytes):
                    value = value.decode("utf-8", "replace")
                out[k] = value
        return out

    # -- lifecycle ----------------------------------------------------------------------------
    def initialize(self, t0: float, set_before: Any, set_during: Any, stop: float | None = None) -> float | None:
        """Set up at ``t0``: ``set_before()`` (structural parameters, parameters, start values)
        then initialization mode, ``set_during()`` (inputs), and out of it (model exchange:
        the event iteration, then continuous-time mode). Returns the next time event the FMU
        announced (model exchange), or None.

        Raises :class:`FmuTerminated` if the FMU ends the run in its first event iteration."""
        f = self._fmu
        if self.version == 2:
            self.call("fmi2SetupExperiment", f.setupExperiment, None, t0, stop)
            set_before()
            self.call("fmi2EnterInitializationMode", f.enterInitializationMode)
            set_during()
            self.call("fmi2ExitInitializationMode", f.exitInitializationMode)
        else:
            set_before()
            self.call("fmi3EnterInitializationMode", f.enterInitializationMode, None, t0, stop)
            set_during()
            self.call("fmi3ExitInitializationMode", f.exitInitializationMode)
        if self.kind != "model_exchange":
            return None
        _changed, next_time, terminate = self.event_update()
        if terminate:
            raise FmuTerminated(self.name, t0, self.said(most=3))
        self.call(self._fn_name("EnterContinuousTimeMode"), f.enterContinuousTimeMode)
        return next_time

    def _fn_name(self, what: str) -> str:
        return f"fmi{self.version}{what}"

    def event_update(self) -> tuple[bool, float | None, bool]:
        """Event iteration (model exchange, in event mode): (continuous states changed, the
        next time event or None, the FMU asks to terminate the simulation)."""
        f = self._fmu
        changed, next_time = False, None
        what = "fmi2NewDiscreteStates" if self.version == 2 else "fmi3UpdateDiscreteStates"
        fn = f.newDiscreteStates if self.version == 2 else f.updateDiscreteStates
        for _ in range(1000):
            again, terminate, _nominals, values_changed, defined, t_next = self.call(what, fn)
            changed = changed or bool(values_changed)
            next_time = float(t_next) if defined else None
            if terminate:
                return changed, next_time, True
            if not again:
                return changed, next_time, False
        raise FmuError(f"FMU '{self.name}': its event iteration ({what}) did not converge in 1000 rounds")

    def do_step(self, t: float, h: float) -> bool:
        """Co-simulation: advance the FMU from ``t`` by ``h``. Returns True if the FMU ended
        the simulation (FMI 3's ``terminateSimulation``, FMI 2's ``fmi2Discard`` with
        ``fmi2Terminated``): the caller reports it as information and stops stepping it."""
        f = self._fmu
        if self.version == 2:
            fn = self._do_step_fn
            if fn is None:
                fn = self._do_step_fn = self._raw("fmi2DoStep") or False
            if fn and not self._freed:  # FMPy's own function, its status read here
                start = len(self.log)
                status = fn(f.component, t, h, 1)
                if status <= 1:
                    return False
                if status == 2 and self._fmi2_terminated():
                    return True
                raise self._failed("fmi2DoStep", "fmi2DoStep", status, start)
            try:
                self.call("fmi2DoStep", f.doStep, t, h)
            except FmuError as exc:
                if "returned discard" in str(exc) and self._fmi2_terminated():
                    return True
                raise
            return False
        _event, terminate, _early, _last = self.call("fmi3DoStep", f.doStep, t, h)
        return bool(terminate)

    def _fmi2_terminated(self) -> bool:
        """FMI 2: after a discarded doStep, whether the FMU says the simulation is over."""
        try:
            return bool(self._fmu.getBooleanStatus(3))  # fmi2Terminated
        except Exception:  # noqa: BLE001 - the status is optional
            return False

    # model exchange: the calls of every evaluation go straight to FMPy's ctypes functions
    # (which raise on an error status), with buffers made once
    def set_time(self, t: float) -> None:
        f = self._fmu
        self.call(self._fn_name("SetTime"), f.fmi2SetTime if self.version == 2 else f.fmi3SetTime, f.component, t)

    def _state_buffers(self) -> tuple[np.ndarray, Any, np.ndarray, Any]:
        """(x, a pointer to it, dx, a pointer to it): the buffers of the state calls, made once."""
        if self._xbufs is None:
            x, dx = np.zeros(self.nx), np.zeros(self.nx)
            self._xbufs = (x, x.ctypes.data_as(_double_p()), dx, dx.ctypes.data_as(_double_p()))
        return self._xbufs

    def set_states(self, x: np.ndarray) -> None:
        """Give the FMU its continuous states x, shape (nx,)."""
        buf, ptr, _, _ = self._state_buffers()
        buf[:] = x
        self.call(self._fn_name("SetContinuousStates"), self._fmu.setContinuousStates, ptr, self.nx)

    def get_states(self) -> np.ndarray:
        """The FMU's continuous states, a new array of shape (nx,)."""
        buf, ptr, _, _ = self._state_buffers()
        self.call(self._fn_name("GetContinuousStates"), self._fmu.getContinuousStates, ptr, self.nx)
        return buf.copy()

    def derivatives(self) -> np.ndarray:
        """dx/dt at the time, states and inputs given last: a new array of shape (nx,)."""
        _, _, buf, ptr = self._state_buffers()
        if self.version == 2:
            self.call("fmi2GetDerivatives", self._fmu.getDerivatives, ptr, self.nx)
        else:
            self.call("fmi3GetContinuousStateDerivatives", self._fmu.getContinuousStateDerivatives, ptr, self.nx)
        return buf.copy()

    def event_indicators(self) -> np.ndarray:
        """The event indicators z at the time, states and inputs given last: a new array (nz,)."""
        if not self.nz:
            return np.zeros(0)
        if self._zbuf is None:
            z = np.zeros(self.nz)
            self._zbuf = (z, z.ctypes.data_as(_double_p()))
        z, ptr = self._zbuf
        self.call(self._fn_name("GetEventIndicators"), self._fmu.getEventIndicators, ptr, self.nz)
        return z.copy()

    def completed_step(self) -> tuple[bool, bool]:
        """Model exchange: tell the FMU a step was accepted; (it asks for event mode, it asks to
        terminate). Not called for an FMU that does not need it (needsCompletedIntegratorStep)."""
        if not self.needs_completed_step:
            return False, False
        enter, terminate = self.call(self._fn_name("CompletedIntegratorStep"), self._fmu.completedIntegratorStep)
        return bool(enter), bool(terminate)

    def enter_event_mode(self) -> None:
        self.call(self._fn_name("EnterEventMode"), self._fmu.enterEventMode)

    def enter_continuous_time_mode(self) -> None:
        self.call(self._fn_name("EnterContinuousTimeMode"), self._fmu.enterContinuousTimeMode)

    def free(self) -> None:
        """Terminate and free the instance and unload its binary (once; errors ignored)."""
        if self._freed or self._fmu is None:
            return
        self._freed = True
        try:
            self._fmu.terminate()
        except Exception:  # noqa: BLE001 - an FMU in an error state may refuse; free it anyway
            pass
        try:
            self._fmu.freeInstance()
        except Exception:  # noqa: BLE001
            pass
        _LOGGERS.pop(getattr(self, "_log_key", None), None)
        if self._once:
            _release_once(self.folder)

    @property
    def freed(self) -> bool:
        return self._freed


#: FMUs that may be instantiated only once per process (canBeInstantiatedOnlyOncePerProcess),
#: by unpacked folder, while an instance of them lives: the FMU's own limit is the process's
_ONCE: dict[str, str] = {}


def _claim_once(folder: Path, name: str) -> None:
    with _lock:
        holder = _ONCE.get(str(folder))
        if holder is not None:
            raise FmuError(
                f"FMU '{name}' can be instantiated only once per process (canBeInstantiatedOnlyOncePerProcess), and it already runs "
                "(the lab open in another tab?); close the other tab, or export the FMU without that restriction"
            )
        _ONCE[str(folder)] = name


def _release_once(folder: Path) -> None:
    with _lock:
        _ONCE.pop(str(folder), None)


def _double_p() -> Any:
    from ctypes import POINTER, c_double

    return POINTER(c_double)
