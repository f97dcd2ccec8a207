"""The OpenGL back end in a served class's threads (issue #30): each stepper thread that
renders at the same time gets a context of its own, so a session's camera never waits
for another's render, and every thread's picture is its own scene's (the NumPy back end's
picture, pixel for pixel, on these flat faces away from edges)."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from ejsrl.vision import CameraModel
from ejsrl.world import _gl
from ejsrl.world.rendering import render_triangles


@pytest.fixture(autouse=True)
def require_gl():
    if not _gl.available():
        pytest.fail(f"{_gl.describe()} (scripts/setup.sh installs what the OpenGL tests need)")


def _triangle(z: float) -> np.ndarray:
    """One face (1, 3, 3) at distance ``z`` m in front of a camera at the origin looking along +z."""
    return np.array([[[-0.3, -0.2, z], [0.4, -0.1, z], [0.0, 0.3, z]]])


def _both(z: float, cam: CameraModel) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """(gl, numpy) renders of the triangle at ``z``."""
    kw = dict(camera=cam, T_world_camera=np.eye(4), cull_backfaces=False)
    return (render_triangles(_triangle(z), [[1, 0, 0]], backend="gl", **kw),
            render_triangles(_triangle(z), [[1, 0, 0]], backend="numpy", **kw))


def _assert_same_picture(gl: tuple[np.ndarray, np.ndarray], ref: tuple[np.ndarray, np.ndarray], z: float) -> None:
    seen_gl, seen_ref = np.isfinite(gl[1]), np.isfinite(ref[1])
    assert seen_ref.sum() > 10, "the reference sees the triangle"
    # the same pixels covered, up to a few along the triangle's edges
    assert np.count_nonzero(seen_gl != seen_ref) <= 0.05 * seen_ref.sum()
    both = seen_gl & seen_ref
    assert np.allclose(gl[1][both], z, rtol=1e-4), f"depth of the triangle at {z} m"
    assert np.array_equal(gl[0][both], ref[0][both])


def _in_thread(fn, timeout: float = 60.0):
    """Run ``fn`` in a new thread; its result, or what it raised; None if it did not finish."""
    out: list = []

    def run() -> None:
        try:
            out.append(fn())
        except BaseException as exc:  # noqa: BLE001 - handed to the test
            out.append(exc)

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(timeout)
    if not out:
        return None
    if isinstance(out[0], BaseException):
        raise out[0]
    return out[0]


def test_a_render_does_not_wait_for_another_threads_render():
    """While one thread holds a context (a session's render in progress), another thread's
    render finishes, with its own picture: with one context per process it waited."""
    cam = CameraModel(80, 60, fov_deg=50)
    with _gl._pool().renderer():
        done = _in_thread(lambda: _both(3.0, cam), timeout=60.0)
        assert done is not None, "the second thread's render waited for the first's context"
    _assert_same_picture(*done, 3.0)


def test_a_context_made_by_a_live_thread_renders_in_others_at_new_sizes():
    """A context made on one thread (still alive: this one) draws in another thread, at an
    image size it never drew (its buffers made there): moderngl leaves a new context current
    on the thread that made it, where no other could use it ('cannot create texture')."""
    assert _gl.available()  # made (or taken) on this thread
    for size in ((73, 41), (120, 90)):
        cam = CameraModel(*size, fov_deg=60)
        _assert_same_picture(*_in_thread(lambda cam=cam: _both(4.0, cam)), 4.0)
    _assert_same_picture(*_both(2.0, CameraModel(50, 40, fov_deg=50)), 2.0)  # and still here


def test_threads_rendering_at_once_each_get_their_own_scene():
    """Four threads, each drawing its own distance twenty times at once: no picture is another's."""
    cam = CameraModel(64, 48, fov_deg=50)
    errors: list[str] = []
    start = threading.Barrier(4)

    def worker(z: float) -> None:
        start.wait()
        for _ in range(20):
            gl, ref = _both(z, cam)
            try:
                _assert_same_picture(gl, ref, z)
            except AssertionError as exc:
                errors.append(f"z={z}: {exc}")
                return

    threads = [threading.Thread(target=worker, args=(z,)) for z in (1.5, 2.5, 3.5, 4.5)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert not any(t.is_alive() for t in threads), "a thread's renders never finished"
    assert not errors, errors
    assert 1 <= _gl._pool().size() <= _gl.context_limit()


def test_no_more_contexts_than_the_limit(monkeypatch):
    """EJSRL_GL_CONTEXTS=1: a second thread waits for the one context and then draws."""
    monkeypatch.setenv("EJSRL_GL_CONTEXTS", "1")
    monkeypatch.setattr(_gl, "_the_pool", None)  # a fresh pool for this process, with the limit
    cam = CameraModel(64, 48, fov_deg=50)
    result: list = []
    with _gl._pool().renderer():
        t = threading.Thread(target=lambda: result.append(_both(2.0, cam)), daemon=True)
        t.start()
        t.join(1.0)
        assert t.is_alive() and not result, "the second thread drew without a context"
    t.join(60)
    assert result, "the second thread never got the context back"
    _assert_same_picture(*result[0], 2.0)
    assert _gl._pool().size() == 1


def test_each_render_starts_from_its_own_background_and_an_empty_depth():
    """The clears (through ctypes, without the GIL): a render after another, with the triangle
    moved and another background, shows nothing of the one before: its own background where
    nothing is seen, depth inf there, and the NumPy back end's picture where the triangle is."""
    cam = CameraModel(96, 72, fov_deg=50)
    kw = dict(camera=cam, T_world_camera=np.eye(4), cull_backfaces=False)
    near = render_triangles(_triangle(0.7), [[0, 1, 0]], backend="gl", background=(0.9, 0.1, 0.1), **kw)
    assert np.isfinite(near[1]).sum() > 0.25 * near[1].size, "the near triangle covers much of the picture"
    for bg in ((0.1, 0.2, 0.8), (1.0, 1.0, 1.0)):
        gl = render_triangles(_triangle(5.0), [[1, 0, 0]], backend="gl", background=bg, **kw)
        ref = render_triangles(_triangle(5.0), [[1, 0, 0]], backend="numpy", background=bg, **kw)
        _assert_same_picture(gl, ref, 5.0)
        empty = ~np.isfinite(gl[1])
        assert empty.sum() > 0.5 * empty.size
        assert np.array_equal(gl[0][empty], ref[0][empty]), "the background is this render's"
        assert np.array_equal(np.unique(gl[0][empty], axis=0), np.round(np.array([bg]) * 255).astype(np.uint8))
        assert not np.any((gl[0] == (0, 255, 0)).all(axis=-1)), "nothing of the earlier picture is left"
