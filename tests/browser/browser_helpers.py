"""Helpers for the browser tests."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

#: where screenshots go (git-ignored)
ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts"


def wait_until(condition: Callable[[], bool], *, timeout: float = 30.0, what: str = "condition") -> None:
    """Poll ``condition`` (state on the server) until it holds, or fail saying what was awaited."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")
