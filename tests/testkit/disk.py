"""A small, real file system that fills up: a tmpfs of a few KB mounted for one test (root only)."""

from __future__ import annotations

import os
import subprocess
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["small_disk"]


@contextmanager
def small_disk(where: Path, size: str = "64k") -> Iterator[Path]:
    """Mount a tmpfs of ``size`` on ``where`` (made if missing) and unmount it afterwards.

    Writing more than ``size`` there fails with ENOSPC ("No space left on device"), as on
    a full disk. Needs root (the test machines run as root; ``mount`` refuses otherwise).
    """
    where.mkdir(parents=True, exist_ok=True)
    assert os.geteuid() == 0, "a full-disk test mounts a tmpfs and needs root"
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)], check=True)
    try:
        yield where
    finally:
        subprocess.run(["umount", "-l", str(where)], check=False)
