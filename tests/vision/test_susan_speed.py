"""SUSAN's cost against OpenCV's goodFeaturesToTrack, and what it leaves behind.

The target (SUSAN at most 3x GFTT on scikit-image's photographs at 640x480) is measured by
bench/vision.py. Here, two guards that a shared, loaded machine cannot make flaky:

- SUSAN leaves no threads busy: OpenCV's gemm hands large matrix products to its bundled
  OpenBLAS, whose threads then spin for a while; on a 2-core machine that took a core from
  whatever ran next (an app's other work, or the GFTT call the benchmark timed next, which
  made the ratio look better than it was).
- SUSAN stays within a generous multiple of GFTT in CPU time (one OpenCV thread each, best of
  several interleaved runs: load stretches wall-clock times, CPU time much less): a change
  that makes it grossly slower fails here. Measured 5.3-5.7x on this image (it was 7-8x); with
  numba's kernels (``[fast]``) on one thread 0.9-2.5x, guarded at 4x (the NumPy path's speed fails it).
- On two threads (outside a served class) the numba path takes clearly less wall-clock time
  than on one, and no more CPU time to speak of.
Both SUSAN paths are checked for busy threads.

And the one shortcut the speed rests on is sound: the cheap lower bound on the USAN that
picks the pixels SUSAN looks at never leaves out a pixel with a response.
"""

from __future__ import annotations

import time

import cv2
import numpy as np
import pytest
from skimage import data

from ejsrl.vision import susan_corners, usan_area


@pytest.fixture(scope="module")
def camera() -> np.ndarray:
    return cv2.resize(data.camera(), (640, 480), interpolation=cv2.INTER_AREA)


def _cpu_over_wall() -> float:
    """CPU time over wall time of a one-thread NumPy loop: about 1 (less on a loaded machine),
    more when other threads of this process are busy at the same time."""
    x = np.random.default_rng(0).random(300_000).astype(np.float32)
    c0, w0 = time.process_time(), time.perf_counter()
    for _ in range(40):
        x.sum()
    return (time.process_time() - c0) / (time.perf_counter() - w0)


def test_susan_leaves_no_threads_busy(camera, susan_path):
    susan_corners(camera)
    after = _cpu_over_wall()  # right after: spinning threads would count here (about 2 on 2 cores)
    # one thread alone reaches at most 1 (a loaded machine gives it less, never more): a
    # comparison with a measurement before the call failed when load took half of that one
    assert after < 1.3, after


def _cpu_ratio(camera) -> tuple[float, float, float]:
    """SUSAN's CPU time over GFTT's (one OpenCV thread each, best of 7 interleaved runs), and both in ms."""
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        susan_corners(camera), cv2.goodFeaturesToTrack(camera, 100, 0.01, 5)
        ts, tg = [], []
        for _ in range(7):
            t0 = time.process_time()
            susan_corners(camera)
            ts.append(time.process_time() - t0)
            t0 = time.process_time()
            cv2.goodFeaturesToTrack(camera, 100, 0.01, 5)
            tg.append(time.process_time() - t0)
    finally:
        cv2.setNumThreads(threads)
    return min(ts) / min(tg), min(ts) * 1e3, min(tg) * 1e3


def test_susan_is_not_grossly_slower_than_goodfeaturestotrack(camera, monkeypatch):
    from ejsrl.vision import _susan

    monkeypatch.setattr(_susan, "BACKEND", "numpy")
    ratio, ms, mg = _cpu_ratio(camera)
    assert ratio <= 10.0, f"SUSAN took {ratio:.1f}x goodFeaturesToTrack's CPU time ({ms:.1f} ms vs {mg:.2f} ms)"


def test_susan_compiled_with_numba_keeps_its_lead(camera, monkeypatch):
    """The numba kernels on one thread: measured 0.9-2.5x GFTT's CPU time on this image (GFTT's own
    time varies with what ran before it, 2 to 6 ms: the page faults of fresh memory; the NumPy path 5.2-6x); 4x leaves room for a loaded machine and fails on a fall back to the NumPy path's speed."""
    from ejsrl.vision import _susan

    monkeypatch.setattr(_susan, "BACKEND", "numba")
    monkeypatch.setattr(_susan, "THREADS", 1)
    assert _susan.susan_backend() == "numba"
    ratio, ms, mg = _cpu_ratio(camera)
    assert ratio <= 4.0, f"SUSAN (numba) took {ratio:.1f}x goodFeaturesToTrack's CPU time ({ms:.1f} ms vs {mg:.2f} ms)"


def test_susan_on_two_threads_hands_a_real_share_of_the_work_to_the_second(monkeypatch):
    """Outside a served class a call runs on two threads. They were measured at 0.62-0.66
    of the one-thread wall-clock time on astronaut (the slowest photograph against GFTT),
    but wall time depends on a free second core, which a loaded machine (CI's two test
    workers) does not have. The work shared does not depend on that. With two threads the
    calling thread's own CPU time is at most 0.85 of the whole call's on one thread (the
    other thread did the rest: it stops if the second thread stops helping), and the two
    threads together waste no CPU time: at most 1.35x one thread's (measured 1.07).
    Best of 9 interleaved runs each."""
    from ejsrl.vision import _susan

    monkeypatch.setattr(_susan, "BACKEND", "numba")
    monkeypatch.setattr(_susan, "THREADS", None)
    monkeypatch.delenv("EJSRL_SUSAN_THREADS", raising=False)
    assert _susan.susan_backend() == "numba" and _susan.susan_threads() == 2
    img = cv2.resize(cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2GRAY), (640, 480), interpolation=cv2.INTER_AREA)
    mine: dict[int, list[float]] = {1: [], 2: []}
    cpu: dict[int, list[float]] = {1: [], 2: []}
    for n in (1, 2):
        _susan.set_threads(n)
        susan_corners(img)
    for _ in range(9):
        for n in (1, 2):
            _susan.set_threads(n)
            t0, c0 = time.thread_time(), time.process_time()
            susan_corners(img)
            mine[n].append(time.thread_time() - t0)
            cpu[n].append(time.process_time() - c0)
    share = min(mine[2]) / min(mine[1])
    assert share <= 0.85, f"the calling thread still did {share:.2f} of the work ({min(mine[2]) * 1e3:.2f} vs {min(mine[1]) * 1e3:.2f} ms)"
    waste = min(cpu[2]) / min(cpu[1])
    assert waste <= 1.35, f"two threads took {waste:.2f}x one thread's CPU time"


@pytest.mark.parametrize("t", [5.0, 12.0, 25.0, 40.0])
@pytest.mark.parametrize("scene", ["camera", "noise"])
def test_the_cheap_bound_keeps_every_pixel_with_a_response(t, scene, camera):
    """SUSAN corners look only at the pixels a lower bound on the USAN leaves; every pixel whose
    exact USAN (``usan_area``, the whole-image pass) gives a response must be among them."""
    from ejsrl.vision._susan import _bound_limit, _candidates_by_bound

    img = camera if scene == "camera" else np.random.default_rng(1).integers(0, 256, (120, 160)).astype(np.uint8)
    H, W = img.shape
    g, floor = 18.5, 1.5
    L_max = _bound_limit(t, 100 * (g - floor) + 1.0)
    assert L_max is not None
    kept = np.zeros(H * W, bool)
    kept[_candidates_by_bound(img, t, L_max, 4, H - 4)] = True
    response = (g - usan_area(img, t)).ravel() >= floor - 1e-4
    inner = np.zeros((H, W), bool)
    inner[4:-4, 4:-4] = True
    need = response & inner.ravel()
    assert need.sum() > 100
    assert kept[need].all(), f"{(~kept[need]).sum()} pixels with a response left out"
    assert kept.sum() < 2.5 * need.sum() or scene == "noise"  # and it is a useful filter on a photograph
