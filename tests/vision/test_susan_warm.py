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


def test_building_a_lab_that_uses_susan_compiles_its_kernels_in_the_background(tmp_path: Path) -> None:
    """``ejsgen build`` of the servoing lab starts the compile, and returns before it ends; the app
    started afterwards loads the kernels it cached. A lab without SUSAN starts none."""
    import time

    root = Path(__file__).resolve().parents[2]
    cache, tmp = tmp_path / "numba", tmp_path / "tmp"
    tmp.mkdir()
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "TMPDIR": str(tmp)}  # a fresh cache and fresh marks
    env.pop("EJSRL_SUSAN_CHILD", None)

    def build(spec: Path, out: Path) -> float:
        t0 = time.perf_counter()
        r = subprocess.run([sys.executable, "-m", "ejsgen", "build", str(spec), "-o", str(out)], capture_output=True, text=True, env=env, timeout=300,
                           cwd=tmp_path)  # the installed ejsgen and ejsrl, as the -c below (from the checkout's root, -m ejsgen runs the checkout's)
        assert r.returncode == 0, r.stderr
        return time.perf_counter() - t0

    build(root / "examples" / "pendulum.ejs.yaml", tmp_path / "pendulum")
    time.sleep(0.5)
    assert not list(tmp.glob("ejsrl-susan-numba-*")) and not cache.exists()  # no SUSAN: nothing started
    took = build(root / "examples" / "paper" / "visual_servoing_eih.ejs.yaml", tmp_path / "servo")
    assert not list(tmp.glob("ejsrl-susan-numba-*.done"))  # the build returned before the compile (12 s or more) ended
    # another build meanwhile leaves the compile to the child at it (once it holds the cache's lock)
    from ejsrl.vision.warm import _compiling

    deadline = time.monotonic() + 120
    while not (list(tmp.glob("ejsrl-susan-numba-*.lock")) and _compiling(next(tmp.glob("ejsrl-susan-numba-*.lock")))):
        assert time.monotonic() < deadline, "the child never took the cache's lock"
        time.sleep(0.05)
    ask = "from ejsrl.vision.warm import start_in_background; print(start_in_background())"
    r = subprocess.run([sys.executable, "-c", ask], capture_output=True, text=True, env=env, timeout=300, cwd=tmp_path)
    assert "being compiled into numba's cache already" in r.stdout, r.stdout + r.stderr
    deadline = time.monotonic() + 600
    while not list(tmp.glob("ejsrl-susan-numba-*.done")):
        assert time.monotonic() < deadline, "the background compile did not finish"
        time.sleep(0.5)
    assert {".nbi", ".nbc"} <= {p.suffix for p in cache.rglob("*")}
    assert took < 60  # the build did not wait for the compile
    before = {p: p.stat().st_mtime_ns for p in cache.rglob("*.nbc")}
    code = "from ejsrl.vision import _susan; _susan.BACKEND = 'numba'; print(_susan.susan_backend())"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 0 and r.stdout.split()[-1] == "numba", r.stderr
    assert {p: p.stat().st_mtime_ns for p in cache.rglob("*.nbc")} == before  # loaded, not compiled again
