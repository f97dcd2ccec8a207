"""The numbers of a lab's page against the native app's: its headless CSV run in a process of its
own, compared cell by cell (tests/web)."""

from __future__ import annotations

import csv
import io
import subprocess
import sys
from pathlib import Path

import pytest


def native_csv(app_dir: Path, duration: float) -> str:
    """The CSV the built app in ``app_dir`` writes with ``--headless --duration DURATION`` (seconds
    of simulated time), run by this Python in a process of its own."""
    out = app_dir / "native.csv"
    subprocess.run([sys.executable, str(app_dir / "app.py"), "--headless", "--duration", f"{duration:g}", "--csv", str(out)],
                   check=True, capture_output=True)
    return out.read_text()


def assert_same_csv(got: str, expected: str, *, more_rows_than: int, tol: float = 1e-12) -> None:
    """``got`` has ``expected``'s header and as many rows (more than ``more_rows_than``); each
    number within ``tol`` (relative and absolute), each other cell (text) equal."""
    web = list(csv.reader(io.StringIO(got)))
    native = list(csv.reader(io.StringIO(expected)))
    assert web[0] == native[0] and len(web) == len(native) > more_rows_than
    for w, n in zip(web[1:], native[1:]):
        for a, b in zip(w, n):
            try:
                fa, fb = float(a), float(b)
            except ValueError:
                assert a == b
                continue
            assert fa == pytest.approx(fb, rel=tol, abs=tol)
