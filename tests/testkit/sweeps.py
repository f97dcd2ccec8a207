"""Helpers of the sweep tests: build a spec, run ``ejsgen sweep``, read its tables, run a headless reference."""

from __future__ import annotations

import csv
import io
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

SPECS = Path(__file__).resolve().parents[1] / "sweeps" / "specs"


def ejsgen(*args: str, timeout: float = 600, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    """``ejsgen ARGS`` in a fresh interpreter (the installed package, not the checkout)."""
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    return subprocess.run([sys.executable, "-P", "-m", "ejsgen", *args], capture_output=True, text=True, timeout=timeout, env=env, cwd=cwd)


def read(path: Path) -> dict[str, list[Any]]:
    """A table written by a sweep (Parquet or CSV) as columns of Python values."""
    if path.suffix == ".csv":
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
        return {name: [row[i] for row in rows[1:]] for i, name in enumerate(rows[0])}
    import pyarrow.parquet as pq

    return pq.read_table(path).to_pydict()


def headless_csv(app_dir: Path, duration: float, *settings: str, variables: str | None = None) -> dict[str, list[str]]:
    """The CSV of ``app.py --headless`` with ``--set`` settings: the reference a sweep's run must equal."""
    args = [sys.executable, str(app_dir / "app.py"), "--headless", "--duration", str(duration), "--csv", "-"]
    if variables:
        args += ["--vars", variables]
    for s in settings:
        args += ["--set", s]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    rows = list(csv.reader(io.StringIO(proc.stdout)))
    return {name: [row[i] for row in rows[1:]] for i, name in enumerate(rows[0])}


def rows_of(table: dict[str, list[Any]], run: int) -> dict[str, list[Any]]:
    """The rows of one run of a results table."""
    keep = [i for i, r in enumerate(table["run"]) if r == run]
    return {name: [values[i] for i in keep] for name, values in table.items()}
