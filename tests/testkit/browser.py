"""Helpers for the browser tests."""

from __future__ import annotations

import io
import os
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

#: where screenshots go (git-ignored)
from testkit import ARTIFACTS


#: the seconds a wait on the page or the server may take by default: what a machine busy with
#: two other CPU-bound processes (and the suite's other worker) needs, with room to spare
WAIT_SECONDS = float(os.environ.get("EJSGEN_TEST_WAIT_SECONDS", "90"))


def wait_until(condition: Callable[[], bool], *, timeout: float | None = None, what: str = "condition") -> None:
    """Poll ``condition`` (state on the server) until it holds, or fail saying what was awaited.

    ``timeout``: seconds (default ``WAIT_SECONDS``)."""
    timeout = WAIT_SECONDS if timeout is None else timeout
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return
        time.sleep(0.05)
    if condition():  # a last look: the process may have been descheduled past the deadline
        return
    raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")


def settled(grab: Callable[[], Any], *, quiet: float = 0.5, timeout: float | None = None, what: str = "the page to settle") -> Any:
    """What ``grab()`` returns once it has stayed the same for ``quiet`` seconds (the 3D view's
    pixels after its first frames, a plot after a pause): a wait on the page's state instead
    of a fixed sleep, which a busy machine outlasts. Values compare with ``numpy.array_equal``."""
    timeout = WAIT_SECONDS if timeout is None else timeout
    deadline = time.monotonic() + timeout
    last = grab()
    since = time.monotonic()
    while time.monotonic() < deadline:
        time.sleep(0.1)
        now = grab()
        if not _same(now, last):
            last, since = now, time.monotonic()
        elif time.monotonic() - since >= quiet:
            return now
    raise AssertionError(f"timed out after {timeout:g} s waiting for {what} (it kept changing)")


def _same(a: Any, b: Any) -> bool:
    try:
        return bool(np.array_equal(a, b)) if isinstance(a, np.ndarray) or isinstance(b, np.ndarray) else a == b
    except (TypeError, ValueError):
        return False


@contextmanager
def serving(app_dir: Path, **serve: Any) -> Iterator[tuple[Any, str]]:
    """Load a built app folder and serve it on a free port: yields ``(app, url)``; ``serve``:
    ``App.serve``'s options (``per_client``, ``max_sessions``, ``grace``, ...)."""
    from ejsrl.app import load_app

    app = load_app(app_dir)
    server = app.serve("127.0.0.1", 0, block=False, **serve)
    try:
        yield app, f"http://127.0.0.1:{server.get_port()}"
    finally:
        app.stop()
        server.stop()


#: milliseconds a lab's page may take to show its first drawn panel (a busy machine's first load)
LAB_LOAD_MS = 120_000


@contextmanager
def serving_example(name: str) -> Iterator[tuple[Any, str]]:
    """The example ``examples/<name>.ejs.yaml`` built into a temporary folder and served with a
    simulation per tab (two at most): yields ``(app, url)``; stopped and removed after."""
    import tempfile

    from ejsgen.cli import build
    from testkit import EXAMPLES

    with tempfile.TemporaryDirectory() as tmp:
        app_dir = build(EXAMPLES / f"{name}.ejs.yaml", Path(tmp) / "app")
        with serving(app_dir, per_client=True, max_sessions=2, grace=30.0) as served:
            yield served


def open_lab_tab(context: Any, url: str, *, ready: str = "canvas.ejs2d-c[data-drawn]", state: str = "visible") -> Any:
    """A new tab in front on ``url`` (waits of :data:`LAB_LOAD_MS`), once ``ready`` (a selector,
    in ``state``; by default a drawn 2D panel) is on the page and the tab has its session address."""
    page = context.new_page()
    page.bring_to_front()
    page.set_default_timeout(LAB_LOAD_MS)
    page.goto(url)
    page.wait_for_selector(ready, state=state, timeout=LAB_LOAD_MS)
    wait_until(lambda: "/s/" in page.evaluate("location.href"), what="the tab's session address")
    return page


def tab_lab(app: Any, page: Any) -> Any:
    """The simulation (an app) of the tab ``page``: the one its ``/s/<token>/`` address names."""
    import re

    token = re.search(r"/s/([A-Za-z0-9_-]+)/", page.evaluate("location.href")).group(1)
    return app.classroom.sessions[token].app


def panel_point(page: Any, x: float, y: float, box: dict[str, float] | None = None) -> tuple[float, float]:
    """Where the world point (x, y) of the page's first 2D panel is on the page (CSS px), by the
    panel's own mapping; ``box``: the panel canvas's bounding box, if already read."""
    box = box or page.locator("canvas.ejs2d-c").first.bounding_box()
    px, py = page.evaluate(f"window.__ejs2d.toPx(Object.keys(window.__ejs2d.panels)[0], {x}, {y})")
    return box["x"] + px, box["y"] + py


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
