"""The FMI calls of every step, made fast: straight to FMPy's ctypes functions.

FMPy's Python wrappers (``fmu.setReal``, ``fmu.fmi2GetDerivatives``, ...) build their
arguments and check the status in Python at every call; a step of a lab makes a dozen of
them. :class:`FastCalls` (a part of :class:`~ejsrl.fmi._instance.FmuInstance`) gives
closures that call FMPy's ctypes function itself (``fmu._functions[name]``, its argument
types set by FMPy) with value-reference arrays and value buffers made once, and turn an
error status into :class:`~ejsrl.fmi._instance.FmuError` with what the FMU logged. Where
FMPy does not expose its functions, or the variables are not all scalar reals, they fall
back to the generic calls.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["FastCalls", "STATUS"]

#: the FMI status codes' names, by value
STATUS = ("OK", "warning", "discard", "error", "fatal", "pending")


class FastCalls:
    """Fast closures over an instantiated FMU (mixed into ``FmuInstance``, whose attributes
    ``_fmu``, ``vars``, ``version``, ``log``, ``nx`` and methods they use)."""

    _fmu: Any
    _freed: bool
    vars: dict[str, Any]
    version: int
    log: list[str]
    name: str
    nx: int
    # methods of FmuInstance the closures fall back on or read from
    said: Any
    shape: Any
    set_values: Any
    get_values: Any
    set_time: Any
    set_states: Any
    derivatives: Any
    _state_buffers: Any
    completed_step: Any

    def _raw(self, fname: str) -> Any:
        """FMPy's ctypes function ``fname`` itself (its argument types set), or None."""
        functions = getattr(self._fmu, "_functions", None)
        return functions.get(fname) if isinstance(functions, dict) else None

    def _failed(self, what: str, fname: str, status: int, start: int) -> Exception:
        from ejsrl.fmi._instance import FmuError

        label = STATUS[status] if 0 <= status < len(STATUS) else str(status)
        if self._freed:
            return FmuError(f"FMU '{self.name}': {what} after the FMU was freed (the app stopped)")
        return FmuError(f"FMU '{self.name}': {fname} returned {label}" if what == fname else f"FMU '{self.name}': {what}: {fname} returned {label}", self.said(start))

    def _scalar_reals(self, names: Sequence[str]) -> bool:
        return all(self.vars[n].type in ("Real", "Float64") and not self.shape(n) for n in names)

    def setter(self, names: Sequence[str], what: str) -> Any:
        """A function ``set(values)`` setting the variables ``names`` (one value each, in order):
        for scalar reals one call to the FMU's own function with buffers made once."""
        names = tuple(names)
        fname = "fmi2SetReal" if self.version == 2 else "fmi3SetFloat64"
        fn = self._raw(fname)
        if not names or fn is None or not self._scalar_reals(names):
            return lambda values: self.set_values(names, values, what)
        n = len(names)
        from ctypes import c_double, c_uint

        vrs = (c_uint * n)(*[self.vars[x].valueReference for x in names])
        buf = (c_double * n)()
        comp = self._fmu.component
        log = self.log
        extra = () if self.version == 2 else (n,)

        def set_(values: Sequence[Any]) -> None:
            buf[:] = values
            start = len(log)
            if self._freed:
                raise self._failed(what, fname, 3, start)
            status = fn(comp, vrs, n, buf, *extra)
            if status > 1:
                raise self._failed(what, fname, status, start)

        return set_

    def getter(self, names: Sequence[str], what: str = "reading outputs") -> Any:
        """A function ``get() -> list`` of the variables ``names`` (as :meth:`get_values`)."""
        names = tuple(names)
        fname = "fmi2GetReal" if self.version == 2 else "fmi3GetFloat64"
        fn = self._raw(fname)
        if not names or fn is None or not self._scalar_reals(names):
            return lambda: self.get_values(names, what)
        n = len(names)
        from ctypes import c_double, c_uint

        vrs = (c_uint * n)(*[self.vars[x].valueReference for x in names])
        buf = (c_double * n)()
        comp = self._fmu.component
        log = self.log
        extra = () if self.version == 2 else (n,)

        def get() -> list[float]:
            start = len(log)
            if self._freed:
                raise self._failed(what, fname, 3, start)
            status = fn(comp, vrs, n, buf, *extra)
            if status > 1:
                raise self._failed(what, fname, status, start)
            return buf[:]

        return get

    def fast_calls(self) -> tuple[Any, Any, Any]:
        """Model exchange, for every evaluation of the rates: ``set_time(t)``,
        ``set_states(x)`` ((nx,) floats) and ``derivatives() -> (nx,) new array``."""
        v = self.version
        names = ("fmi2SetTime", "fmi2SetContinuousStates", "fmi2GetDerivatives") if v == 2 else ("fmi3SetTime", "fmi3SetContinuousStates", "fmi3GetContinuousStateDerivatives")
        raw = [self._raw(n) for n in names]
        if any(f is None for f in raw):
            return self.set_time, self.set_states, self.derivatives
        f_time, f_states, f_der = raw
        x, px, dx, pdx = self._state_buffers()
        comp, log, nx = self._fmu.component, self.log, self.nx

        def set_time(t: float) -> None:
            start = len(log)
            if self._freed:
                raise self._failed(names[0], names[0], 3, start)
            status = f_time(comp, t)
            if status > 1:
                raise self._failed(names[0], names[0], status, start)

        def set_states(state: np.ndarray) -> None:
            x[:] = state
            start = len(log)
            status = f_states(comp, px, nx)
            if status > 1:
                raise self._failed(names[1], names[1], status, start)

        def derivatives() -> np.ndarray:
            start = len(log)
            if self._freed:
                raise self._failed(names[2], names[2], 3, start)
            status = f_der(comp, pdx, nx)
            if status > 1:
                raise self._failed(names[2], names[2], status, start)
            return dx.copy()

        return set_time, set_states, derivatives

    def fast_completed_step(self) -> Any:
        """A function ``completed() -> (enter event mode, terminate)``: the FMU's
        ``CompletedIntegratorStep`` with its two flags made once."""
        from ctypes import byref, c_bool, c_int

        fname = "fmi2CompletedIntegratorStep" if self.version == 2 else "fmi3CompletedIntegratorStep"
        fn = self._raw(fname)
        if fn is None:
            return self.completed_step
        flag = c_int if self.version == 2 else c_bool  # fmi2Boolean is an int, fmi3Boolean a bool
        enter, terminate = flag(), flag()
        p_enter, p_terminate = byref(enter), byref(terminate)
        comp, log = self._fmu.component, self.log

        def completed() -> tuple[bool, bool]:
            start = len(log)
            if self._freed:
                raise self._failed(fname, fname, 3, start)
            status = fn(comp, 1, p_enter, p_terminate)
            if status > 1:
                raise self._failed(fname, fname, status, start)
            return bool(enter.value), bool(terminate.value)

        return completed
