"""``python -m ejsrl.vision.warm`` compiles SUSAN's kernels into numba's cache ahead of use, so a
later process loads them instead of compiling (the cold start moved to setup time)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path


def test_warm_fills_numbas_cache_for_later_processes(tmp_path: Path) -> None:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    r = subprocess.run([sys.executable, "-m", "ejsrl.vision.warm"], capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "SUSAN's kernels are in numba's cache" in r.stdout
    cached = {p.suffix for p in tmp_path.rglob("*")}
    assert {".nbi", ".nbc"} <= cached  # numba's index and compiled code
    # a later process finds them cached: it loads, and numba writes nothing new
    before = {p: p.stat().st_mtime_ns for p in tmp_path.rglob("*.nbc")}
    code = "from ejsrl.vision import _susan; _susan.BACKEND = 'numba'; print(_susan.susan_backend())"
    r2 = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=600)
    assert r2.returncode == 0 and r2.stdout.split()[-1] == "numba", r2.stderr
    assert {p: p.stat().st_mtime_ns for p in tmp_path.rglob("*.nbc")} == before
