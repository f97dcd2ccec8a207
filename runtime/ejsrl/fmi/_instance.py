"""One FMU instance through FMPy, FMI 2.0 or 3.0, co-simulation or model exchange.

``FmuInstance`` hides the differences between the versions behind the few calls a
simulation makes (set and get values by name, ``do_step``, the model-exchange calls),
collects what the FMU logs, and turns a failing call into :class:`FmuError` carrying the
FMU's own messages. FMPy is imported lazily: an app without FMUs never needs it.
"""

from __future__ import annotations

import atexit
import shutil
import threading
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["FmuError", "FmuInstance", "load_fmpy", "read_description", "unpacked", "INSTALL_HINT", "PLATFORM_DIRS"]

INSTALL_HINT = "FMUs need FMPy: pip install 'ejsgen[fmu]' (or pip install fmpy)"

_STATUS = ("OK", "warning", "discard", "error", "fatal", "pending")


class FmuError(RuntimeError):
    """A failing FMU call; ``log`` holds the FMU's own messages of that call."""

    def __init__(self, message: str, log: Sequence[str] = ()) -> None:
        self.log = list(log)
        text = message + (": " + "; ".join(self.log) if self.log else "")
        super().__init__(text)


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


class FmuInstance:
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
        self.nx = len(description.derivatives)
        self.nz = int(description.numberOfEventIndicators or 0)
        self._fmu: Any = None
        self._callbacks: Any = None
        self._freed = False
        self._groups: dict[tuple[str, ...], dict[str, list[tuple[int, int]]]] = {}
        self._buffers: dict[tuple[Any, ...], tuple[Any, Any, Any]] = {}
        self._xbufs: tuple[np.ndarray, Any, np.ndarray, Any] | None = None
        self._instantiate()

    # -- calls, each turning a failure into FmuError with the FMU's messages -----------------
    def call(self, what: str, fn: Any, *args: Any) -> Any:
        """``fn(*args)``; a failure raises :class:`FmuError` naming ``what`` and what the FMU logged."""
        if self._freed:
            raise FmuError(f"FMU '{self.name}': {what} after the FMU was freed (the app stopped)")
        start = len(self.log)
        try:
            return fn(*args)
        except Exception as exc:  # noqa: BLE001 - FMPy raises FMICallException or plain Exception
            said = [m.split(": ", 1)[1] for m in self.log[start:] if not m.startswith("OK: ")]
            status = getattr(exc, "status", None)
            how = f"returned {_STATUS[status]}" if isinstance(status, int) and 0 <= status < len(_STATUS) else f"failed ({exc})"
            raise FmuError(f"FMU '{self.name}': {what} {how}", said) from None

    def _logger_text(self, status: int, category: bytes | None, message: bytes | None) -> None:
        label = _STATUS[status] if 0 <= status < len(_STATUS) else str(status)
        text = (message or b"").decode("utf-8", "replace")
        self.log.append(f"{label}: {text}" if label != "OK" else f"OK: {text}")
        del self.log[:-200]  # keep the latest messages only

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
            callbacks.logger = fmi2.fmi2CallbackLoggerTYPE(lambda env, inst, status, cat, msg: self._logger_text(status, cat, msg))
            callbacks.allocateMemory = fmi2.fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
            callbacks.freeMemory = fmi2.fmi2CallbackFreeMemoryTYPE(fmpy.free)
            try:
                from fmpy.logging import addLoggerProxy

                addLoggerProxy(byref(callbacks))  # formats the FMU's printf-style messages
            except Exception:  # noqa: BLE001 - FMPy without its logging shim: messages unformatted
                pass
            self._callbacks = callbacks
            self.call("fmi2Instantiate", fmu.instantiate, False, callbacks, False)
        else:
            from fmpy import fmi3

            cls = fmi3.FMU3Slave if cs else fmi3.FMU3Model
            fmu = self.call("loading the binary", lambda: cls(**common))
            self.call(
                "fmi3Instantiate",
                lambda: fmu.instantiate(loggingOn=False, logMessage=lambda env, status, cat, msg: self._logger_text(status, cat, msg)),
            )
        self._fmu = fmu

    # -- values by name -----------------------------------------------------------------------
    def _typed(self, names: Sequence[str]) -> dict[str, list[tuple[int, int]]]:
        """Value references grouped by type: type -> [(position in names, value reference)]."""
        key = tuple(names)
        groups = self._groups.get(key)
        if groups is None:
            groups = {}
            for k, n in enumerate(names):
                v = self.vars[n]
                groups.setdefault(v.type, []).append((k, v.valueReference))
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

    def set_values(self, names: Sequence[str], values: Sequence[Any], what: str = "setting values") -> None:
        """Set FMU variables by name (numbers, booleans or text, by the variable's type)."""
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
            vrs = [vr for _, vr in items]
            vals = [values[k] for k, _ in items]
            if vtype in ("Real", "Float64", "Float32"):
                fn = f.setReal if self.version == 2 else (f.setFloat64 if vtype == "Float64" else f.setFloat32)
                self.call(what, fn, vrs, [float(x) for x in vals])
            elif vtype in ("Integer", "Int32", "Int64", "Int16", "Int8", "UInt32", "UInt64", "UInt16", "UInt8", "Enumeration"):
                fn = f.setInteger if self.version == 2 else getattr(f, f"set{vtype if vtype != 'Enumeration' else 'Int64'}")
                self.call(what, fn, vrs, [int(x) for x in vals])
            elif vtype == "Boolean":
                self.call(what, f.setBoolean, vrs, [bool(x) for x in vals])
            elif vtype == "String":
                self.call(what, f.setString, vrs, [str(x) for x in vals])
            else:
                raise FmuError(f"FMU '{self.name}': cannot set variables of type {vtype}")

    def get_values(self, names: Sequence[str], what: str = "reading outputs") -> list[Any]:
        """The FMU variables' values, in the order of ``names``."""
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
            vrs = [vr for _, vr in items]
            if vtype in ("Real", "Float64", "Float32"):
                fn = f.getReal if self.version == 2 else (f.getFloat64 if vtype == "Float64" else f.getFloat32)
            elif vtype == "Boolean":
                fn = f.getBoolean
            elif vtype == "String":
                fn = f.getString
            else:
                fn = f.getInteger if self.version == 2 else getattr(f, f"get{vtype if vtype != 'Enumeration' else 'Int64'}")
            got = self.call(what, fn, vrs)
            for (k, _), value in zip(items, got):
                out[k] = value.decode() if isinstance(value, bytes) else value
        return out

    # -- lifecycle ----------------------------------------------------------------------------
    def initialize(self, t0: float, set_before: Any, set_during: Any) -> None:
        """Set up at ``t0``: ``set_before()`` (parameters, start values) then initialization
        mode, ``set_during()`` (inputs), and out of it (model exchange: into continuous time)."""
        f = self._fmu
        if self.version == 2:
            self.call("fmi2SetupExperiment", f.setupExperiment, None, t0)
            set_before()
            self.call("fmi2EnterInitializationMode", f.enterInitializationMode)
            set_during()
            self.call("fmi2ExitInitializationMode", f.exitInitializationMode)
        else:
            set_before()
            self.call("fmi3EnterInitializationMode", f.enterInitializationMode, None, t0)
            set_during()
            self.call("fmi3ExitInitializationMode", f.exitInitializationMode)
        if self.kind == "model_exchange":
            self.event_update()
            self.call("EnterContinuousTimeMode", f.enterContinuousTimeMode)

    def event_update(self) -> tuple[bool, float | None]:
        """Event iteration (model exchange, in event mode): (states changed, next time event or None)."""
        f = self._fmu
        changed, next_time = False, None
        for _ in range(1000):
            what = "fmi2NewDiscreteStates" if self.version == 2 else "fmi3UpdateDiscreteStates"
            fn = f.newDiscreteStates if self.version == 2 else f.updateDiscreteStates
            again, terminate, _nominals, values_changed, defined, t_next = self.call(what, fn)
            changed = changed or bool(values_changed)
            next_time = t_next if defined else None
            if terminate:
                raise FmuError(f"FMU '{self.name}' asked to terminate the simulation", [m for m in self.log[-5:] if not m.startswith("OK: ")])
            if not again:
                return changed, next_time
        raise FmuError(f"FMU '{self.name}': its event iteration did not converge in 1000 rounds")

    def do_step(self, t: float, h: float) -> None:
        """Co-simulation: advance the FMU from ``t`` by ``h``."""
        f = self._fmu
        if self.version == 2:
            self.call("fmi2DoStep", f.doStep, t, h)
        else:
            _event, terminate, _early, _last = self.call("fmi3DoStep", f.doStep, t, h)
            if terminate:
                raise FmuError(f"FMU '{self.name}' asked to terminate the simulation at t = {t + h:g}", [m for m in self.log[-5:] if not m.startswith("OK: ")])

    # model exchange
    def set_time(self, t: float) -> None:
        self.call("SetTime", self._fmu.setTime, t)

    def _state_buffers(self) -> tuple[np.ndarray, Any, np.ndarray, Any]:
        """(x, a pointer to it, dx, a pointer to it): the buffers of the state calls, made once."""
        if self._xbufs is None:
            x, dx = np.zeros(self.nx), np.zeros(self.nx)
            self._xbufs = (x, x.ctypes.data_as(_double_p()), dx, dx.ctypes.data_as(_double_p()))
        return self._xbufs

    def set_states(self, x: np.ndarray) -> None:
        buf, ptr, _, _ = self._state_buffers()
        buf[:] = x
        self.call("SetContinuousStates", self._fmu.setContinuousStates, ptr, self.nx)

    def get_states(self) -> np.ndarray:
        buf, ptr, _, _ = self._state_buffers()
        self.call("GetContinuousStates", self._fmu.getContinuousStates, ptr, self.nx)
        return buf.copy()

    def derivatives(self) -> np.ndarray:
        _, _, buf, ptr = self._state_buffers()
        fn = self._fmu.getDerivatives if self.version == 2 else self._fmu.getContinuousStateDerivatives
        self.call("GetDerivatives", fn, ptr, self.nx)
        return buf.copy()

    def event_indicators(self) -> np.ndarray:
        z = np.zeros(self.nz)
        if self.nz:
            self.call("GetEventIndicators", self._fmu.getEventIndicators, z.ctypes.data_as(_double_p()), self.nz)
        return z

    def completed_step(self) -> bool:
        """Model exchange: tell the FMU a step was accepted; True if it asks for event mode."""
        f = self._fmu
        if self.version == 2:
            enter, terminate = self.call("fmi2CompletedIntegratorStep", f.completedIntegratorStep)
        else:
            enter, terminate = self.call("fmi3CompletedIntegratorStep", f.completedIntegratorStep)
        if terminate:
            raise FmuError(f"FMU '{self.name}' asked to terminate the simulation", [m for m in self.log[-5:] if not m.startswith("OK: ")])
        return bool(enter)

    def enter_event_mode(self) -> None:
        self.call("EnterEventMode", self._fmu.enterEventMode)

    def enter_continuous_time_mode(self) -> None:
        self.call("EnterContinuousTimeMode", self._fmu.enterContinuousTimeMode)

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

    @property
    def freed(self) -> bool:
        return self._freed


def _double_p() -> Any:
    from ctypes import POINTER, c_double

    return POINTER(c_double)
