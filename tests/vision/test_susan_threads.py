"""SUSAN's threads: outside a served class a call on a photograph runs its candidate search (numba's
kernels) and the sub-pixel refinement on two threads; a served class (many sessions in a pool of
threads) keeps every SUSAN call on its calling thread. The corners, responses and sub-pixel
positions are the same either way, bit for bit."""

from __future__ import annotations

import threading
import types

import cv2
import numpy as np
import pytest
from skimage import data

from ejsrl.vision import _susan, susan_corners


def _photo(name: str) -> np.ndarray:
    img = getattr(data, name)()
    grey = img if img.ndim == 2 else cv2.cvtColor(img, cv2.COLOR_RGB2GRAY)
    return cv2.resize(grey, (640, 480), interpolation=cv2.INTER_AREA)


@pytest.fixture
def spy(monkeypatch: pytest.MonkeyPatch) -> dict[str, set[int]]:
    """The numba path, its kernels wrapped to record the threads that run the candidate search and
    the sub-pixel refinement; the thread switch restored afterwards."""
    monkeypatch.setattr(_susan, "BACKEND", "numba")
    kernels = _susan._COMPILED.get(wait=True)
    assert kernels is not None
    # the candidate search (with the side shares), the saddles, the maxima, the refinement
    seen: dict[str, set[int]] = {"search": set(), "saddles": set(), "maxima": set(), "refine": set()}

    def recorded(part, name):
        def run(*args):
            seen[part].add(threading.get_ident())
            return getattr(kernels, name)(*args)

        return run

    proxy = types.SimpleNamespace(**{k: getattr(kernels, k) for k in dir(kernels) if not k.startswith("__")})
    for part, name in (("search", "candidates"), ("search", "share_image"), ("saddles", "saddles"), ("maxima", "lazy_maxima"), ("refine", "refine")):
        setattr(proxy, name, recorded(part, name))
    monkeypatch.setattr(_susan._COMPILED, "module", proxy)
    monkeypatch.setattr(_susan, "THREADS", None)
    monkeypatch.delenv("EJSRL_SUSAN_THREADS", raising=False)
    return seen


def _bits(a: np.ndarray) -> bytes:
    return np.ascontiguousarray(a).tobytes()


@pytest.mark.parametrize("name", ["astronaut", "coins", "camera"])
def test_two_threads_outside_a_served_class_give_the_same_corners(spy, name):
    img = _photo(name)
    assert _susan.susan_threads() == 2  # the default on this (>= 2 core) machine
    p2, r2 = susan_corners(img, return_response=True)
    # (the candidate search's bands go to whichever thread is free: the pool's may take none)
    assert len(spy["search"] | spy["saddles"]) == 2, "the candidates should be judged on two threads"
    # the refinement too, where there are enough corners to share (coins: 701)
    assert len(spy["refine"]) == (2 if len(p2) >= 512 else 1)
    for threads in spy.values():
        threads.clear()
    _susan.set_threads(1)
    p1, r1 = susan_corners(img, return_response=True)
    assert spy["search"] | spy["saddles"] | spy["refine"] == {threading.get_ident()}
    assert len(p1) > 100 and _bits(p1) == _bits(p2) and _bits(r1) == _bits(r2)


def test_the_maxima_on_two_threads_are_those_on_one(spy):
    """Without the response map, the maxima of a texture (14 thousand passing pixels, chains of
    hidden failing ones across the two halves) are found on two threads at once: the same corners
    as on one thread, and as with the response map, every time."""
    img = _photo("grass")
    whole = susan_corners(img, return_response=True)[0]
    for _ in range(20):
        assert _bits(susan_corners(img)) == _bits(whole)
    assert len(spy["maxima"]) == 2
    for threads in spy.values():
        threads.clear()
    _susan.set_threads(1)
    assert _bits(susan_corners(img)) == _bits(whole)
    assert spy["maxima"] == {threading.get_ident()}


def test_the_two_halves_of_the_maxima_race_safely(spy):
    """The two halves of ``lazy_maxima`` share one map, each deciding pixels the other reads. On
    blurred binary noise with a wide window (long chains of hidden failing pixels between close
    corners) and a busy Python thread shifting the timing, every call gives the response map's
    corners. (Before a pixel decided by the other half since it was read counted, about one call
    in five dropped or added a corner here: the new-user trial of session 7 found it.)"""
    img = cv2.GaussianBlur((np.random.default_rng(3).integers(0, 2, (460, 420)) * 200).astype(np.uint8), (0, 0), 0.7)
    kw = {"t": 8.0, "nms_radius": 7, "min_response": 0.9, "subpixel": False}
    whole = _bits(susan_corners(img, return_response=True, **kw)[0])
    stop = threading.Event()

    def busy() -> None:
        x = np.random.default_rng(0).random(200_000)
        while not stop.is_set():
            x.sum()

    spinner = threading.Thread(target=busy, daemon=True)
    spinner.start()
    try:
        wrong = sum(_bits(susan_corners(img, **kw)) != whole for _ in range(150))
    finally:
        stop.set()
        spinner.join()
    assert len(spy["maxima"]) == 2
    assert wrong == 0, f"{wrong} of 150 calls gave other corners"


def test_the_environment_variable_sets_one_thread(spy, monkeypatch):
    monkeypatch.setenv("EJSRL_SUSAN_THREADS", "1")
    assert _susan.susan_threads() == 1
    susan_corners(_photo("coins"))
    assert spy["search"] | spy["saddles"] | spy["refine"] == {threading.get_ident()}


def test_a_bad_thread_count_in_the_environment_is_a_clear_error(monkeypatch):
    monkeypatch.setattr(_susan, "THREADS", None)
    monkeypatch.setenv("EJSRL_SUSAN_THREADS", "two")
    with pytest.raises(ValueError, match=r"EJSRL_SUSAN_THREADS='two': write the number of threads SUSAN may use, 1 or 2"):
        _susan.susan_threads()
    monkeypatch.setenv("EJSRL_SUSAN_THREADS", "8")
    assert _susan.susan_threads() == 2  # (the kernels split their work in two at most)


def test_a_served_class_keeps_susan_on_the_calling_thread(spy):
    from testkit.browser_lab import make_app

    app = make_app()
    server = app.serve("127.0.0.1", 0, block=False, per_client=True, max_sessions=2, grace=1.0)
    try:
        assert _susan.susan_threads() == 1
        img, out = _photo("astronaut"), []
        worker = threading.Thread(target=lambda: out.append(susan_corners(img)))  # as a session's thread would
        worker.start()
        worker.join()
        assert spy["search"] | spy["saddles"] | spy["refine"] == {worker.ident} and len(out[0]) > 100
    finally:
        app.stop()
        server.stop()


@pytest.mark.parametrize("threads", [1, 2])
def test_calls_from_several_threads_at_once_each_get_their_own_images_corners(monkeypatch, threads):
    """A served class's sessions call SUSAN from their own threads at the same time (and, outside a
    class, several callers share the pool's second thread): each call keeps its whole-image
    arrays to its calling thread, so each gets its own image's corners and response, bit for bit."""
    monkeypatch.setattr(_susan, "BACKEND", "numba")
    assert _susan.susan_backend() == "numba"
    monkeypatch.setattr(_susan, "THREADS", threads)
    images = [_photo(name) for name in ("astronaut", "coins", "camera", "coffee")]
    expected = [susan_corners(img, return_response=True) for img in images]
    got: dict[tuple[int, int], tuple] = {}
    start = threading.Barrier(len(images))

    def work(k: int) -> None:
        start.wait()
        for round_ in range(5):
            got[k, round_] = susan_corners(images[(k + round_) % len(images)], return_response=True)

    workers = [threading.Thread(target=work, args=(k,)) for k in range(len(images))]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    assert len(got) == 5 * len(images)
    for (k, round_), (pts, resp) in got.items():
        want_pts, want_resp = expected[(k + round_) % len(images)]
        assert _bits(pts) == _bits(want_pts) and _bits(resp) == _bits(want_resp), (k, round_)
