"""A headless CSV on a full disk or in a read-only folder: one line, a non-zero status, no cut row.

Before, ``--csv`` on a full disk printed a raw traceback and left the last row cut inside a
number (it still parsed: silently wrong). Now the file is cut back to its last whole row and
the app says ``error: cannot write FILE: No space left on device``.
"""

from __future__ import annotations

import csv
import io
import subprocess
from pathlib import Path

from testkit import run_app
from testkit.disk import small_disk


def test_a_full_disk_leaves_whole_rows_equal_to_a_run_that_had_room(built, tmp_path: Path) -> None:
    app = built("lorenz")
    reference = run_app(app, "--headless", "--duration", "20", "--csv", "-", timeout=300)
    assert reference.returncode == 0, reference.stderr
    with small_disk(tmp_path / "disk", "64k") as disk:
        out = disk / "lorenz.csv"
        r = run_app(app, "--headless", "--duration", "20", "--csv", str(out), timeout=300)
        text = out.read_bytes().decode()
    assert r.returncode == 1, r.stderr
    assert "Traceback" not in r.stderr
    assert r.stderr.strip().splitlines()[-1].startswith(f"error: cannot write {out}: No space left on device")
    assert 32_000 < len(text) <= 64 * 1024 and text.endswith("\n")
    rows = list(csv.reader(io.StringIO(text)))
    ref_rows = list(csv.reader(io.StringIO(reference.stdout)))
    assert len(rows) < len(ref_rows)
    # every row kept is whole: the same fields, digit for digit, as the run that had room
    assert rows == ref_rows[: len(rows)]
    assert f"the file keeps its first {len(rows):,} lines" in r.stderr


def test_a_read_only_folder_is_one_line_and_no_file(built, tmp_path: Path) -> None:
    app = built("lorenz")
    with small_disk(tmp_path / "ro", "64k") as disk:
        subprocess.run(["mount", "-o", "remount,ro", str(disk)], check=True)
        r = run_app(app, "--headless", "--duration", "1", "--csv", str(disk / "lorenz.csv"), timeout=120)
        assert not (disk / "lorenz.csv").exists()
    assert r.returncode != 0 and "Traceback" not in r.stderr
    assert r.stderr.strip() == f"error: cannot write {disk / 'lorenz.csv'}: Read-only file system"
