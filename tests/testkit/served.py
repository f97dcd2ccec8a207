"""A built app served in its own process as a teacher runs it (``python app.py``), and the
processes it runs as."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

__all__ = ["Served", "cpu_seconds", "alive"]


class Served:
    """``python app.py --port 0 ...`` in its own process; ``port`` once it serves."""

    def __init__(self, app_dir: Path, tmp: Path, *args: str) -> None:
        self.out, self.err = tmp / "out.txt", tmp / "err.txt"
        env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
        self.proc = subprocess.Popen([sys.executable, "-P", str(app_dir / "app.py"), "--port", "0", *args],
                                     stdout=self.out.open("w"), stderr=self.err.open("w"), env=env)
        deadline = time.monotonic() + 180
        while (m := re.search(r"serving on http://127\.0\.0\.1:(\d+)", self.out.read_text())) is None:
            if self.proc.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"the app did not serve:\n{self.out.read_text()}\n{self.err.read_text()}")
            time.sleep(0.1)
        self.port = int(m.group(1))

    def children(self) -> list[int]:
        path = Path(f"/proc/{self.proc.pid}/task/{self.proc.pid}/children")
        return [int(p) for p in path.read_text().split()] if path.exists() else []

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                self.proc.kill()


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False
