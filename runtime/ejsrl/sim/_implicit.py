"""Implicit methods for stiff models: SciPy's Radau IIA (order 5) and BDF (orders 1-5).

The SciPy solver object is kept alive between steps (building it estimates the Jacobian,
which is the expensive part) and is allowed to run past the end of a step; the state at
the end of the step is read from its dense output.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

__all__ = ["ImplicitStepper"]


class ImplicitStepper:
    """A running ``scipy.integrate.Radau`` or ``BDF`` solver with a movable position.

    The position ``t`` lies within the solver's last step ``[t_old, t_solver]``.
    """

    def __init__(
        self,
        f: Callable[[float, np.ndarray], np.ndarray],
        method: str,
        *,
        atol: float,
        rtol: float,
        max_step: float,
    ) -> None:
        from scipy.integrate import BDF, Radau

        self._cls = {"radau": Radau, "bdf": BDF}[method]
        self.method = method
        self.f = f
        self.atol = atol
        self.rtol = rtol
        self.max_step = max_step
        self._solver = None
        self._dense = None

    @property
    def running(self) -> bool:
        """Whether a solver object exists (i.e. :meth:`restart` was called since :meth:`reset`)."""
        return self._solver is not None

    def reset(self) -> None:
        """Drop the solver (and its Jacobian); the next :meth:`restart` builds a new one."""
        self._solver = None
        self._dense = None

    def restart(self, t: float, y: np.ndarray) -> None:
        """Build a new solver starting at (t, y)."""
        self._solver = self._cls(
            self.f,
            t,
            np.array(y, dtype=float),
            math.inf,
            rtol=self.rtol,
            atol=self.atol,
            max_step=self.max_step,
        )
        self._dense = None

    def advance(self, t: float, t_end: float) -> tuple[float, np.ndarray]:
        """Move from position ``t`` to the end of the solver's current step or ``t_end``,
        whichever comes first, taking one solver step if the solver is not ahead of ``t``.

        Returns ``(t_new, y_new)`` with ``t_new == t_end`` exactly when it is reached.
        """
        s = self._solver
        if s.t <= t:
            s.step()
            if s.status == "failed":
                raise RuntimeError(
                    f"{self.method}: the solver failed at t={s.t:.12g} ({s.message}); "
                    "the rates may be discontinuous or not finite"
                )
            self._dense = None
        if s.t < t_end:
            return s.t, np.array(s.y, dtype=float)
        if s.t == t_end:
            return t_end, np.array(s.y, dtype=float)
        return t_end, self.state_at(t_end)

    def state_at(self, x: float) -> np.ndarray:
        """State at time x within the solver's last step (dense output)."""
        if self._dense is None:
            self._dense = self._solver.dense_output()
        return np.asarray(self._dense(x), dtype=float)

    @property
    def nfev(self) -> int:
        """Rate evaluations of the current solver object (0 if none)."""
        return 0 if self._solver is None else self._solver.nfev
