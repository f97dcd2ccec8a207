"""Prepare SUSAN's compiled kernels ahead of use: ``python -m ejsrl.vision.warm``.

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

__all__ = ["main"]


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
