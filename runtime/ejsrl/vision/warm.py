"""Prepare SUSAN's compiled kernels ahead of use: ``python -m ejsrl.vision.warm``, or on its own
when ``ejsgen build`` (or ``run``) builds a lab that uses SUSAN (``start_in_background``).

The first process on a machine that runs SUSAN with numba compiles its kernels into numba's
cache (17-27 s on a loaded 2-core machine; the NumPy path gives the same corners meanwhile);
later processes load them (1-2 s). Run this once after ``pip install 'ejsgen[fast]'`` (or in a
class server's setup, or a container's build) and the first lab that uses SUSAN loads them
instead of compiling them. It prints what it did and how long it took; exit status 0 when the
kernels are cached, 1 when numba is not installed or cannot compile here, 3 when numba has no
writable cache (every process then compiles for itself; set ``NUMBA_CACHE_DIR``).
"""

from __future__ import annotations

import importlib.util
import sys
import time
from pathlib import Path

__all__ = ["main", "start_in_background", "uses_susan"]


def uses_susan(app_text: str) -> bool:
    """Whether a generated app's code calls SUSAN (``susan_corners``, ``susan``, a ``Pipeline`` step "susan")."""
    return "susan" in app_text.lower()


def start_in_background() -> str:
    """Have a detached process compile SUSAN's kernels into numba's cache, unless they are cached
    already, numba is not installed, or ``EJSRL_SUSAN_CHILD=0``; returns what it did, in words.

    ``ejsgen build`` calls this for a lab that uses SUSAN: the compile (17-27 s on a loaded 2-core
    machine) then runs while the user starts the app, whose first SUSAN call loads the kernels
    (1-2 s: numba's import and its first load) instead of compiling them. Processes take turns
    on the cache (``_susan._warm_cache``'s lock), so an app started meanwhile waits for this
    compile instead of doing its own.
    """
    import os
    import threading

    if os.environ.get("EJSRL_SUSAN_CHILD") == "0" or not hasattr(os, "posix_spawn"):
        return "not started (EJSRL_SUSAN_CHILD=0, or no way to start a child here)"
    if importlib.util.find_spec("numba") is None:
        return "numba is not installed: SUSAN runs its NumPy path"
    from ejsrl.vision import _susan

    try:
        if _susan._cache_mark("done").exists():
            return "SUSAN's kernels are in numba's cache already"
        if _compiling(_susan._cache_mark("lock")):  # another build's (or app's) child is at it: one is enough
            return "SUSAN's kernels are being compiled into numba's cache already"
    except OSError:  # a .pyz: nothing numba could cache
        return "numba cannot cache kernels run from here"
    pid = _susan._spawn_warm_child()
    if pid is None:
        return "could not start the compile"
    # reap it when it ends, so a long-lived caller (``ejsgen run``) leaves no zombie
    threading.Thread(target=os.waitpid, args=(pid, 0), name="ejsrl-susan-warm-reaper", daemon=True).start()
    return f"compiling SUSAN's kernels into numba's cache in the background (process {pid})"


def _compiling(lock: Path) -> bool:
    """Whether a process holds ``lock`` (the compiling child's ``flock``) now."""
    import fcntl

    try:
        with open(lock, "a") as f:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)  # released on close
    except BlockingIOError:
        return True
    return False


def main() -> int:
    if importlib.util.find_spec("numba") is None:
        print("numba is not installed: SUSAN runs its NumPy path (pip install 'ejsgen[fast]' for the compiled one)")
        return 1
    from ejsrl.vision import _susan

    t0 = time.perf_counter()
    try:
        status = _susan._warm_cache()
    except Exception as e:  # noqa: BLE001 - say why, do not crash a setup script
        print(f"SUSAN's kernels could not be compiled here: {type(e).__name__}: {e}")
        return 1
    took = time.perf_counter() - t0
    if status == 3:
        print(f"compiled in {took:.1f} s, but numba has no writable cache here: every process compiles for itself "
              "(set NUMBA_CACHE_DIR to a writable folder)")
        return 3
    print(f"SUSAN's kernels are in numba's cache ({took:.1f} s); later processes load them")
    return 0


if __name__ == "__main__":
    sys.exit(main())
