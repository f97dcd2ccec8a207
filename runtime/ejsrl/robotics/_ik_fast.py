"""Where ``ikine``'s LM searches run compiled (private): loading :mod:`._ik_numba` without
making anyone wait, and one arm's constants for it.

numba (the ``[fast]`` extra) compiles the searches once per machine into its on-disk cache;
the first compile takes seconds, so it is done by a child process (outside this process's
GIL, as ``ejsrl.vision``'s SUSAN kernels are) started by a background thread at the first
LM search, and the searches run in Python until the compiled code is loaded (about 0.3 s
from the cache). ``EJSRL_IK`` (or :data:`BACKEND`): ``auto`` (that), ``python`` (never
compiled), ``numba`` (wait for the compiled code; an ``ImportError`` without numba).
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
import threading
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from .robot import Robot

#: "auto", "python" or "numba" (see the module text); read at each call
BACKEND = os.environ.get("EJSRL_IK", "auto").strip().lower() or "auto"

FAST_HINT = "compiled inverse kinematics needs numba: pip install 'ejsgen[fast]'"


class _Loader:
    """Loads :mod:`._ik_numba` in a background thread (see the module text)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.thread: threading.Thread | None = None
        self.module: ModuleType | None = None
        self.error: BaseException | None = None
        self.done = threading.Event()

    def get(self, wait: bool = False) -> ModuleType | None:
        """The compiled module if loaded (starting the load on the first call); with
        ``wait``, once the load has finished (None if it failed)."""
        if self.module is not None:
            return self.module
        with self.lock:
            if self.thread is None:
                if importlib.util.find_spec("numba") is None:
                    self.error = ImportError(FAST_HINT)
                    self.done.set()
                    return None
                self.thread = threading.Thread(target=self._load, name="ejsrl-ik-numba", daemon=True)
                self.thread.start()
        if wait:
            self.done.wait()
        return self.module

    def _load(self) -> None:
        try:
            _compile_in_child()
            from . import _ik_numba

            _ik_numba.warm_up()  # loads from numba's cache (compiles here if the child could not)
            self.module = _ik_numba
        except BaseException as exc:  # noqa: BLE001 - reported by get()'s caller as the Python path
            self.error = exc
        finally:
            self.done.set()


def _compile_in_child() -> None:
    """Have a child process compile the kernels into numba's cache (or find them there)."""
    try:
        import ejsrl

        root = str(Path(ejsrl.__file__).resolve().parent.parent)
        if not Path(root).is_dir():  # a .pyz: numba cannot cache its files
            return
        code = (f"import sys; sys.path.insert(0, {root!r}); "
                "from ejsrl.robotics._ik_numba import warm_up; warm_up()")
        subprocess.run([sys.executable, "-P", "-c", code], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, timeout=600, start_new_session=True, check=False)
    except (OSError, subprocess.SubprocessError):
        return


LOADER = _Loader()


def module() -> ModuleType | None:
    """The compiled searches for this call per :data:`BACKEND`, or None for Python."""
    which = BACKEND
    if which == "python":
        return None
    if which not in ("auto", "numba"):
        raise ValueError(f"EJSRL_IK must be auto, python or numba, not {which!r}")
    mod = LOADER.get(wait=which == "numba")
    if mod is None and which == "numba":
        raise ImportError(f"{FAST_HINT} ({LOADER.error})") from LOADER.error
    return mod


class Compiled:
    """An arm's constants for :func:`._ik_numba.search` (see :func:`._ik_numba.chain_constants`)."""

    def __init__(self, mod: ModuleType, robot: "Robot", lo: list[float], hi: list[float],
                 qmin: list[float], qmax: list[float]) -> None:
        self.search = mod.search
        self.C, self.prism, self.offset = mod.chain_constants(robot)
        self.lo, self.hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
        self.qmin, self.qmax = np.array(qmin, dtype=float), np.array(qmax, dtype=float)
        self.ok = self._agrees(mod, robot)

    def _agrees(self, mod: ModuleType, robot: "Robot") -> bool:
        """The compiled chain's pose and Jacobian equal the robot's at a few configurations."""
        n = robot.n
        T, J, Z, P = np.empty((4, 4)), np.empty((6, n)), np.empty((n, 3)), np.empty((n, 3))
        rng = np.random.default_rng(1)
        for _ in range(3):
            q = rng.uniform(self.lo, self.hi)
            mod.fkine_jacob(self.C, self.prism, self.offset, q, T, J, Z, P)
            if not (np.allclose(T, robot.fkine(q), rtol=0, atol=1e-9)
                    and np.allclose(J, robot.jacob0(q), rtol=0, atol=1e-9)):
                return False
        return True

    def run(self, Tg: np.ndarray, q0: list[float], w: np.ndarray, tol: float, lam: float, ilimit: int,
            slimit: int, seed: int | None, clamp: bool) -> tuple[bool, int, int, float, list[float], list[float]]:
        """``(converged, iterations, searches, E, q, e)`` of the searches from ``q0``."""
        if seed is None:
            seed = int(np.random.SeedSequence().entropy)
        q_out = np.empty(len(q0))
        e_out = np.empty(6)
        ok, total, searches, E = self.search(
            self.C, self.prism, self.offset, np.ascontiguousarray(Tg, dtype=float), np.array(q0, dtype=float),
            self.lo, self.hi, self.qmin, self.qmax, np.ascontiguousarray(w, dtype=float), float(tol), float(lam),
            int(ilimit), int(slimit), int(seed) & 0x7FFFFFFFFFFFFFFF, bool(clamp), q_out, e_out)
        return bool(ok), int(total), int(searches), float(E), q_out.tolist(), e_out.tolist()


def compiled_for(setup: Any) -> Compiled | None:
    """The arm's :class:`Compiled` (cached on its IK setup once the module is loaded)."""
    if BACKEND == "python":
        return None
    c = setup.__dict__.get("_compiled", False)
    if c is not False:
        return c
    mod = module()
    if mod is None:
        return None
    c = Compiled(mod, setup.robot, setup.lo, setup.hi, setup.qmin, setup.qmax)
    c = c if c.ok else None
    setup.__dict__["_compiled"] = c
    return c
