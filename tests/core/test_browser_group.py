"""The suite's browser tests run on one xdist worker (``-n 2 --dist loadgroup``, the CI command):
one Chromium at a time, as tests/conftest.py promises. pytest-xdist 3.8 groups by renaming the
test's ``_nodeid``, which pytest 9.2 no longer reads (it keeps ``_id``): its tests then ran on
both workers with two Chromiums. pyproject.toml's test extra keeps pytest below 9.1."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]

MARKED = '''
import os, pytest
pytestmark = pytest.mark.browser

@pytest.mark.parametrize("i", range(6))
def test_where(i, tmp_path_factory):
    (WHERE / f"{os.environ['PYTEST_XDIST_WORKER']}-{i}").touch()
'''


def test_browser_marked_tests_share_one_worker_under_loadgroup(tmp_path: Path) -> None:
    where = tmp_path / "where"
    where.mkdir()
    (tmp_path / "test_marked.py").write_text(f"from pathlib import Path\nWHERE = Path({str(where)!r})\n" + MARKED)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(TESTS), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run(
        [sys.executable, "-P", "-m", "pytest", "-q", "-p", "conftest", "-n", "2", "--dist", "loadgroup",
         "-c", os.devnull, "--rootdir", str(tmp_path), str(tmp_path / "test_marked.py")],
        capture_output=True, text=True, env=env, timeout=300, cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    workers = {p.name.split("-")[0] for p in where.iterdir()}
    assert len(list(where.iterdir())) == 6
    assert len(workers) == 1, f"browser-marked tests ran on {sorted(workers)}"
