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


#: the examples gallery's pictures (written by save_shot with EJSGEN_GALLERY=1)
from testkit import ROOT  # noqa: E402

GALLERY = ROOT / "examples" / "gallery"


def close_notifications(page: Any) -> None:
    """Close the 'software WebGL' notice of a GPU-less browser, so it does not cover the scene."""
    buttons = page.locator(".mantine-Notification-closeButton")
    for i in range(buttons.count()):
        try:
            buttons.nth(i).click(timeout=2_000)
        except Exception:  # noqa: BLE001 - it may close by itself meanwhile
            pass


def hide_notifications(page: Any) -> None:
    """Hide the 'software WebGL' notice for good (it may come back after being closed): in a lab
    with no 3D scene it sits at the window's bottom-left, over the panel's plots and drawings."""
    page.add_style_tag(content=".mantine-Notification-root { display: none !important; }")


def panel_image(page: Any) -> Any:
    """The camera picture in the panel (viser sends it as a blob: URL)."""
    return page.locator("img[src^='blob:']").first


def save_shot(page: Any, name: str) -> bytes:
    """A screenshot, kept in test-artifacts/ and, with EJSGEN_GALLERY=1, as the gallery's 640x400 picture."""
    import os

    from PIL import Image

    # hide the GPU-less browser's notice (it may come back after being closed) for the picture
    page.add_style_tag(content=".mantine-Notification-root { display: none !important; }")
    png = page.screenshot()
    ARTIFACTS.mkdir(exist_ok=True)
    (ARTIFACTS / f"lab_{name}.png").write_bytes(png)
    if os.environ.get("EJSGEN_GALLERY"):
        GALLERY.mkdir(parents=True, exist_ok=True)
        Image.open(io.BytesIO(png)).convert("RGB").resize((640, 400), Image.LANCZOS).save(GALLERY / f"{name}.png", optimize=True)
    return png


def project(camera, points: np.ndarray) -> np.ndarray:
    """Normalised device coordinates (N, 2) of world points seen by a viser client's camera
    (``client.camera``: its position, look-at point, up direction, vertical field of view and aspect)."""
    eye = np.asarray(camera.position, dtype=float)
    target = np.asarray(camera.look_at, dtype=float)
    up = np.asarray(camera.up_direction, dtype=float)
    f = (target - eye) / np.linalg.norm(target - eye)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    rel = points - eye
    depth = rel @ f
    assert np.all(depth > 0), "part of the content is behind the camera"
    tan_v = np.tan(float(camera.fov) / 2.0)
    tan_h = tan_v * float(camera.aspect)
    return np.column_stack(((rel @ r) / depth / tan_h, (rel @ u) / depth / tan_v))
