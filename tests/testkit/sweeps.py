"""Helpers of the sweep tests: build a spec, run ``ejsgen sweep``, read its tables, run a headless reference."""

from __future__ import annotations

import csv
import io
import os
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
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


@contextmanager
def listening() -> Iterator[tuple[int, list[object]]]:
    """A real server on a free port of this machine: yields its port and the connections that
    arrived (a sandboxed hand-in must reach none)."""
    import socket
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(5)
    server.settimeout(0.2)
    arrived: list[object] = []
    stop = threading.Event()

    def accept() -> None:
        while not stop.is_set():
            try:
                arrived.append(server.accept())
            except OSError:
                continue

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    try:
        yield server.getsockname()[1], arrived
    finally:
        stop.set()
        thread.join(5)
        server.close()


def processes_with(marker: str, ancestor: int | None = None, among: list[int] | None = None) -> list[int]:
    """Processes whose command line holds ``marker``: descendants of ``ancestor`` (one test's
    grading or sweep, not another test's running beside it on the other worker), or those
    among ``among`` still alive."""
    pids = []
    for pid in os.listdir("/proc"):
        if not pid.isdigit() or (among is not None and int(pid) not in among):
            continue
        try:
            if marker in (Path("/proc") / pid / "cmdline").read_bytes().decode(errors="replace") and (
                ancestor is None or _descends(int(pid), ancestor)
            ):
                pids.append(int(pid))
        except OSError:
            continue
    return pids


def _descends(pid: int, ancestor: int) -> bool:
    """Whether ``pid`` is ``ancestor`` or one of its descendants (by /proc's parent chain)."""
    while pid > 1:
        if pid == ancestor:
            return True
        try:
            pid = int((Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[1])
        except OSError:
            return False
    return False
