"""Helpers for the browser tests."""

from __future__ import annotations

import io
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

#: where screenshots go (git-ignored)
from testkit import ARTIFACTS


def wait_until(condition: Callable[[], bool], *, timeout: float = 30.0, what: str = "condition") -> None:
    """Poll ``condition`` (state on the server) until it holds, or fail saying what was awaited."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


@contextmanager
def serving(app_dir: Path) -> Iterator[tuple[Any, str]]:
    """Load a built app folder and serve it on a free port: yields ``(app, url)``."""
    from ejsrl.app import load_app

    app = load_app(app_dir)
    server = app.serve("127.0.0.1", 0, block=False)
    try:
        yield app, f"http://127.0.0.1:{server.get_port()}"
    finally:
        app.stop()
        server.stop()


def canvas_pixels(page: Any) -> np.ndarray:
    """The 3D canvas as an (H, W, 3) int array (what the user sees of the scene)."""
    from PIL import Image

    png = page.locator("canvas").first.screenshot()
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
