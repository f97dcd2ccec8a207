"""The explicit Runge-Kutta engine: one fixed step of any tableau, and adaptive stepping.

Everything here works on plain float64 1-D arrays. Arrays received are never written to,
and every array returned is freshly allocated, so callers may keep views of them.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from ._tableaus import Tableau

__all__ = ["Rates", "FixedStep", "make_fixed_step", "rk_trial", "AdaptiveRK"]

Rates = Callable[[float, np.ndarray], np.ndarray]
"""``f(t, y) -> dy/dt``: (n,) -> (n,)."""

FixedStep = Callable[[Rates, float, np.ndarray, float, "np.ndarray | None"], np.ndarray]
"""``step(f, t, y, h, k0) -> y(t + h)``; ``k0`` is ``f(t, y)`` if already known, else None."""

SAFETY = 0.9
"""Safety factor of the step-size controller."""
MIN_FACTOR = 0.2
"""Smallest factor by which one rejection shrinks the step."""
MAX_FACTOR = 10.0
"""Largest factor by which one accepted step lets the next one grow."""


def _rk4_step(f: Rates, t: float, y: np.ndarray, h: float, k0: np.ndarray | None = None) -> np.ndarray:
    """Classic fourth-order Runge-Kutta step, written out (the hot path of most apps)."""
    k1 = f(t, y) if k0 is None else k0
    hh = 0.5 * h
    th = t + hh
    k2 = f(th, y + hh * k1)
    k3 = f(th, y + hh * k2)
    k4 = f(t + h, y + h * k3)
    acc = k2 + k3
    acc *= 2.0
    acc += k1
    acc += k4
    acc *= h / 6.0
    acc += y
    return acc


def _euler_step(f: Rates, t: float, y: np.ndarray, h: float, k0: np.ndarray | None = None) -> np.ndarray:
    """Forward Euler step."""
    k1 = f(t, y) if k0 is None else k0
    return y + h * k1


def _midpoint_step(f: Rates, t: float, y: np.ndarray, h: float, k0: np.ndarray | None = None) -> np.ndarray:
    """Euler-Richardson (explicit midpoint) step."""
    k1 = f(t, y) if k0 is None else k0
    hh = 0.5 * h
    k2 = f(t + hh, y + hh * k1)
    return y + h * k2


def _combine(y: np.ndarray, h: float, terms: tuple[tuple[int, float], ...], ks: list[np.ndarray]) -> np.ndarray:
    """``y + h * sum(c * ks[j] for j, c in terms)`` as a new array."""
    if len(terms) == 1:
        j, c = terms[0]
        return y + (h * c) * ks[j]
    j, c = terms[0]
    acc = c * ks[j]
    for j, c in terms[1:]:
        acc += c * ks[j]
    acc *= h
    acc += y
    return acc


def make_fixed_step(tableau: Tableau) -> FixedStep:
    """One step of size h of ``tableau``'s propagated formula, without error control.

    Zero coefficients are skipped; euler, euler_richardson and rk4 use hand-written
    versions of the same formulas (they are the hot path of fixed-step apps).
    """
    special = {"euler": _euler_step, "euler_richardson": _midpoint_step, "rk4": _rk4_step}
    if tableau.name in special:
        return special[tableau.name]
    c = [float(x) for x in tableau.c]
    stage_terms = tableau.stage_terms
    b_terms = tableau.b_terms
    s = tableau.stages

    def step(f: Rates, t: float, y: np.ndarray, h: float, k0: np.ndarray | None = None) -> np.ndarray:
        ks = [f(t, y) if k0 is None else k0]
        for i in range(1, s):
            terms = stage_terms[i]
            ks.append(f(t + c[i] * h, _combine(y, h, terms, ks) if terms else y))
        return _combine(y, h, b_terms, ks)

    step.__doc__ = f"One fixed step of {tableau.name}."
    return step


def rk_trial(
    f: Rates, tableau: Tableau, t: float, y: np.ndarray, h: float, k0: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """One step with all stages kept: returns ``(y_new, K)``.

    K: (s, n), or (s + 1, n) for FSAL tableaus whose last row is ``f(t + h, y_new)``.
    """
    s = tableau.stages
    a = tableau.a
    c = tableau.c
    K = np.empty((s + 1 if tableau.fsal else s, y.size))
    K[0] = k0
    for i in range(1, s):
        K[i] = f(t + c[i] * h, y + h * (a[i, :i] @ K[:i]))
    y_new = y + h * (tableau.b @ K[:s])
    if tableau.fsal:
        K[s] = f(t + h, y_new)
    return y_new, K


def _rms(x: np.ndarray) -> float:
    return float(np.linalg.norm(x)) / math.sqrt(x.size)


class AdaptiveRK:
    """Embedded explicit Runge-Kutta pair with standard step-size control.

    The error of a step is ``err = h * sum_i e_i k_i``; its norm is the RMS over the
    components of ``err / (atol + rtol * max(|y|, |y_new|))`` (Hairer's combined norm for
    DOP853); a step is accepted when the norm is at most 1 and the next step is scaled
    by ``SAFETY * norm ** (-1 / (error_order + 1))`` within ``[MIN_FACTOR, MAX_FACTOR]``.
    The proposed step size is remembered between calls of :meth:`advance`.
    """

    def __init__(self, f: Rates, tableau: Tableau, *, atol: float, rtol: float, max_step: float) -> None:
        if tableau.e is None:
            raise ValueError(f"method {tableau.name!r} has no error estimate")
        self.f = f
        self.tableau = tableau
        self.atol = atol
        self.rtol = rtol
        self.max_step = max_step
        self.exponent = -1.0 / (tableau.error_order + 1)
        self.h: float | None = None
        """Remembered step size for the next step (None: choose one)."""

    def reset(self) -> None:
        """Forget the remembered step size."""
        self.h = None

    def _initial_step(self, t: float, y: np.ndarray, k0: np.ndarray, span: float) -> float:
        """Hairer's starting step size (Solving ODEs I, II.4)."""
        scale = self.atol + self.rtol * np.abs(y)
        d0 = _rms(y / scale)
        d1 = _rms(k0 / scale)
        h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
        h0 = min(h0, span)
        y1 = y + h0 * k0
        k1 = self.f(t + h0, y1)
        d2 = _rms((k1 - k0) / scale) / h0
        if d1 <= 1e-15 and d2 <= 1e-15:
            h1 = max(1e-6, h0 * 1e-3)
        else:
            h1 = (0.01 / max(d1, d2)) ** (1.0 / (self.tableau.order + 1))
        return min(100 * h0, h1)

    def _error_norm(self, K: np.ndarray, h: float, y: np.ndarray, y_new: np.ndarray) -> float:
        scale = self.atol + self.rtol * np.maximum(np.abs(y), np.abs(y_new))
        tab = self.tableau
        if tab.e3 is None:
            return abs(h) * _rms((tab.e @ K) / scale)
        err5 = (tab.e @ K) / scale
        err3 = (tab.e3 @ K) / scale
        n5 = float(err5 @ err5)
        n3 = float(err3 @ err3)
        if n5 == 0.0 and n3 == 0.0:
            return 0.0
        return abs(h) * n5 / math.sqrt((n5 + 0.01 * n3) * err5.size)

    def advance(
        self, t: float, y: np.ndarray, k0: np.ndarray | None, t_end: float
    ) -> tuple[float, np.ndarray, np.ndarray | None]:
        """Take one accepted step from (t, y) towards ``t_end`` (> t), never beyond it.

        k0: ``f(t, y)`` if known. Returns ``(t_new, y_new, k_new)``; ``t_new == t_end``
        exactly when the step reaches it; ``k_new`` is ``f(t_new, y_new)`` for FSAL
        methods (pass it back as the next ``k0``) and None otherwise.
        """
        f = self.f
        tab = self.tableau
        if k0 is None:
            k0 = f(t, y)
        h_abs = self.h
        if h_abs is None:
            h_abs = self._initial_step(t, y, k0, t_end - t)
        h_abs = min(h_abs, self.max_step)
        rejected = False
        while True:
            remaining = t_end - t
            if h_abs >= remaining:
                h, t_new, clipped = remaining, t_end, True
            else:
                h, t_new, clipped = h_abs, t + h_abs, False
            y_new, K = rk_trial(f, tab, t, y, h, k0)
            err = self._error_norm(K, h, y, y_new)
            if err <= 1.0:
                factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err**self.exponent)
                if rejected:
                    factor = min(1.0, factor)
                h_next = h * factor
                if clipped and factor >= 1.0:
                    h_next = max(h_next, h_abs)
                self.h = min(h_next, self.max_step)
                return t_new, y_new, (K[-1] if tab.fsal else None)
            h_abs = h * max(MIN_FACTOR, SAFETY * err**self.exponent)
            rejected = True
            if not h_abs > 10 * np.spacing(max(abs(t), 1.0)):
                raise RuntimeError(
                    f"{tab.name}: the step size became too small at t={t:.17g} "
                    f"(tolerance {self.rtol:g}); the model may be stiff (try method radau or bdf) "
                    "or its rates may be discontinuous or not finite"
                )
