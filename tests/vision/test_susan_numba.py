"""SUSAN's numba kernels (the ``[fast]`` extra) against its NumPy/OpenCV path: the same corners,
responses and sub-pixel positions, bit for bit, on scikit-image's photographs, anti-aliased
polygons in noise, a checkerboard and a parameter grid; the kernels run outside the GIL; without
numba (or without a writable cache) SUSAN still runs, silently; the backend switch.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
import threading
import time

import cv2
import numpy as np
import pytest
from skimage import data
from test_susan_accuracy import polygons_image

from ejsrl.vision import _susan, susan_corners


def _grey(name: str) -> np.ndarray:
    im = getattr(data, name)()
    if im.ndim == 3:
        im = cv2.cvtColor(im, cv2.COLOR_RGB2GRAY)
    return cv2.resize(im, (640, 480), interpolation=cv2.INTER_AREA)


def _both(img: np.ndarray, monkeypatch: pytest.MonkeyPatch, **kw):
    """Each path's corners and response; the numba path's corners also as found without the
    response map (``lazy_maxima``, which decides only the failing pixels that could hide one)."""
    out = {}
    for be in ("numpy", "numba"):
        monkeypatch.setattr(_susan, "BACKEND", be)
        assert _susan.susan_backend() == be
        out[be] = susan_corners(img, return_response=True, **kw)
        _same_bits(susan_corners(img, **kw), out[be][0])
    return out["numpy"], out["numba"]


def _same_bits(a: np.ndarray, b: np.ndarray) -> None:
    np.testing.assert_array_equal(a, b)
    assert a.dtype == b.dtype and a.tobytes() == b.tobytes()  # -0.0 and 0.0 too


SCENES = {
    **{name: (lambda name=name: _grey(name)) for name in ("camera", "astronaut", "coins", "brick", "text")},
    "polygons noise 4": lambda: polygons_image(3, 4.0)[0],
    "polygons clean": lambda: polygons_image(4, 0.0)[0],
    "checkerboard": lambda: data.checkerboard(),
    # every pixel a candidate, long chains of failing pixels hidden under larger ones
    "blurred noise": lambda: cv2.GaussianBlur(np.random.default_rng(7).integers(0, 256, (240, 320), dtype=np.uint8), (0, 0), 1.0),
}


@pytest.mark.parametrize("scene", list(SCENES))
def test_the_numba_kernels_give_the_numpy_paths_corners_bit_for_bit(scene, monkeypatch):
    img = SCENES[scene]()
    (pa, ra), (pb, rb) = _both(img, monkeypatch)
    assert len(pa) > 10
    _same_bits(pb, pa)  # sub-pixel positions too
    _same_bits(rb, ra)  # every response value, float32 bit for bit


@pytest.mark.parametrize(
    "kw",
    [
        {"t": 8.0},
        {"t": 12.0, "subpixel": False},
        {"t": 40.0, "nms_radius": 5},
        {"t": 25.0, "nms_radius": 1, "min_response": 0.0},
        {"t": 20.0, "g": 22.0, "min_response": 3.0},
        {"t": 25.0, "quality": 0.2, "max_corners": 50},
        {"t": 25.0, "min_response": -1.0},
        {"t": 25.0, "g": 36.0},
    ],
)
def test_the_same_on_a_parameter_grid(kw, monkeypatch):
    for img in (_grey("camera"), polygons_image(5, 2.0)[0]):
        (pa, ra), (pb, rb) = _both(img, monkeypatch, **kw)
        _same_bits(pb, pa)
        _same_bits(rb, ra)


@pytest.mark.parametrize("shape", [(9, 9), (12, 13), (40, 71), (33, 72), (50, 73), (64, 136), (260, 300), (300, 263)])
def test_the_same_on_images_of_any_width(shape, monkeypatch):
    """The bound works on rows padded to a whole number of 64 pixels (its SIMD width): images whose
    rows are shorter than that, just one pixel over or under it, and large enough to be split into
    bands on two threads give the NumPy path's corners and responses, bit for bit."""
    H, W = shape
    big = cv2.GaussianBlur(np.random.default_rng(H * W).integers(0, 256, (4 * H, 4 * W), dtype=np.uint8), (0, 0), 6.0)
    img = cv2.normalize(cv2.resize(big, (W, H), interpolation=cv2.INTER_AREA), None, 0, 255, cv2.NORM_MINMAX)
    (pa, ra), (pb, rb) = _both(img, monkeypatch)
    if H * W > 3000:
        assert len(pa) > 0
    _same_bits(pb, pa)
    _same_bits(rb, ra)


def test_the_same_when_numbas_sums_over_the_mask_are_not_opencvs(monkeypatch):
    """Where numba's float32 sums over the mask would differ from OpenCV's ``filter2D`` (checked once
    at load, ``_disc_sums_match``), the kernels take the in-between pixels' side estimate from
    OpenCV: the corners and responses are still the NumPy path's, bit for bit."""
    assert _susan.susan_backend(wait=True) == "numba"  # compiled first: the compile sets the flag this test replaces
    monkeypatch.setattr(_susan._COMPILED, "disc_sums_match", False)
    for img in (_grey("astronaut"), polygons_image(3, 4.0)[0]):
        (pa, ra), (pb, rb) = _both(img, monkeypatch)
        _same_bits(pb, pa)
        _same_bits(rb, ra)


def test_the_kernels_sum_over_the_mask_as_opencv_does_here():
    """On this machine numba's sums are OpenCV's (so the kernels compute the side estimate themselves)."""
    assert _susan.susan_backend(wait=True) == "numba"
    assert _susan._COMPILED.disc_sums_match


def test_the_kernels_run_outside_the_gil(monkeypatch):
    """While one thread runs the candidate search on a large image, another keeps running Python."""
    monkeypatch.setattr(_susan, "BACKEND", "numba")
    assert _susan.susan_backend() == "numba"
    from ejsrl.vision import _susan_numba as K

    for name in ("candidates", "judge", "saddles", "assemble", "smooth_tests", "side_tests", "put_back", "window_maxima", "share_image", "disc_sums", "refine", "lazy_maxima", "settle"):
        assert getattr(K, name).targetoptions.get("nogil") is True, name
    big = np.random.default_rng(0).integers(0, 256, (3000, 4000)).astype(np.uint8)
    t = 25.0
    args = (big, _susan._lut(t), _susan._MDX, _susan._MDY, *_susan._ramp_bound(t)[:2], 200, 1850.0, np.float32(150.0))
    started, done = threading.Event(), threading.Event()

    def work():
        started.set()
        _susan._search(K, args, 0, big.shape[0])
        done.set()

    th = threading.Thread(target=work)
    th.start()
    started.wait()
    t0, count = time.perf_counter(), 0
    while not done.is_set():
        count += 1
        time.sleep(0)
    took = time.perf_counter() - t0
    th.join()
    # with the GIL held for the whole call this thread would not run at all until it returned
    assert took > 0.02 and count > 20, (took, count)


def test_the_side_shares_are_opencvs_for_every_grey_level(monkeypatch):
    """The kernels' float32 shares ``(hi - I)+ / max(hi - lo, 1)``, clipped to 1, against OpenCV's
    divide (as the NumPy path computes them) for every grey level, high level and several low ones."""
    monkeypatch.setattr(_susan, "BACKEND", "numba")
    assert _susan.susan_backend() == "numba"
    from ejsrl.vision import _susan_numba as K

    grey = np.repeat(np.arange(256, dtype=np.uint8), 256).reshape(256, 256)
    hi = np.ascontiguousarray(grey.T)
    for low in (0, 1, 7, 64, 100, 200, 254):
        lo = np.minimum(low, hi).astype(np.uint8)
        ref = cv2.divide(cv2.subtract(hi, grey), cv2.max(cv2.subtract(hi, lo), 1.0), dtype=cv2.CV_32F)
        cv2.threshold(ref, 1.0, 0.0, cv2.THRESH_TRUNC, dst=ref)
        _same_bits(K.share_image(grey, lo, hi, np.empty(grey.shape, np.float32), 0, 256), ref)


def test_the_side_judgement_is_the_numpy_paths(monkeypatch):
    """The kernel that judges in-between pixels as the side they belong to (``side_tests``) against
    the NumPy path's ``_judge_mid`` (the coverage test, then ``_mid_response``), bit for bit, on
    every inner pixel of noisy anti-aliased polygons with random 3x3-like grey ranges, sides and
    floors (0 and above): which are corners that way, and their response."""
    monkeypatch.setattr(_susan, "BACKEND", "numba")
    assert _susan.susan_backend() == "numba"
    from ejsrl.vision import _susan_numba as K

    rng = np.random.default_rng(5)
    gray = polygons_image(3, 2.0)[0]
    H, W = gray.shape
    R = _susan._R
    ys, xs = np.mgrid[R + 1 : H - R - 1, R + 1 : W - R - 1]
    idx = (ys * W + xs).ravel()
    k3 = np.ones((3, 3), np.uint8)
    lo = np.minimum(cv2.erode(gray, k3).ravel()[idx], rng.integers(0, 256, len(idx))).astype(np.uint8)
    hi = np.maximum(cv2.dilate(gray, k3).ravel()[idx], lo).astype(np.uint8)
    v = gray.ravel()[idx]
    r_dark = rng.normal(0, 300, len(idx)).astype(np.float32)
    pf, Wp = cv2.copyMakeBorder(gray, R, R, R, R, cv2.BORDER_REPLICATE).ravel(), W + 2 * R
    base = idx + (idx // W) * (2 * R) + (R * Wp + R)
    vals = pf.take(base[:, None] + (_susan.SUSAN_MASK[:, 1] * Wp + _susan.SUSAN_MASK[:, 0])[None, :])
    rows = np.arange(len(idx))
    for floor in (0.0, 150.0, 300.0):
        got_n, r_n = _susan._judge_mid(pf, Wp, base, vals, lo, hi, v, r_dark, 1850.0, floor)
        got_k, r_k = K.side_tests(gray, _susan._share_table(), idx, rows, lo, hi, v, r_dark > 0, _susan._SIDE_CONTIG, 1850.0, floor, _susan._CHORD * _susan._SCALE)
        assert 100 < got_n.sum() < len(idx) // 2
        _same_bits(got_k, got_n)
        _same_bits(r_k[got_k], r_n[got_n])


def _child(code: str, env: dict[str, str | None] | None = None) -> subprocess.CompletedProcess:
    import os

    full = {k: v for k, v in {**os.environ, **(env or {})}.items() if v is not None}
    return subprocess.run([sys.executable, "-P", "-W", "error", "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=600, env=full)


def test_without_numba_susan_runs_the_numpy_path_silently():
    code = """
        import sys
        sys.modules["numba"] = None  # as if numba were not installed
        import numpy as np, cv2
        from skimage import data
        from ejsrl.vision import susan_corners, _susan
        img = cv2.resize(data.camera(), (640, 480), interpolation=cv2.INTER_AREA)
        pts = susan_corners(img)
        print(_susan.susan_backend(wait=True), len(pts), float(pts.sum()))
        _susan.BACKEND = "numba"
        try:
            susan_corners(img)
        except ImportError as e:
            print("ImportError:", e)
    """
    r = _child(code, {"EJSRL_SUSAN": "auto"})
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""  # no warnings (they would be errors here), nothing printed
    first, second = r.stdout.splitlines()
    backend, n, total = first.split()
    img = _grey("camera")
    expect = susan_corners(img)
    assert backend == "numpy" and int(n) == len(expect) and float(total) == float(expect.sum())
    assert "pip install 'ejsgen[fast]'" in second


def test_the_kernels_cache_in_numbas_user_dir_when_the_package_dir_is_read_only(tmp_path):
    """A wheel in a read-only site-packages: numba caches in its user-wide directory; with no
    writable place at all the kernels are compiled in each process and still run."""
    code = """
        import os, numba.core.caching as caching
        mode = os.environ["TEST_MODE"]
        real = caching._CacheLocator.ensure_cache_path
        in_tree = getattr(caching, "InTreeCacheLocator", None) or caching._InTreeCacheLocator
        def ensure(self):
            if isinstance(self, in_tree) or mode == "none":
                raise PermissionError("read-only")
            return real(self)
        caching._CacheLocator.ensure_cache_path = ensure
        from ejsrl.vision import _susan, _susan_numba as K
        _susan.BACKEND = "numba"
        print(_susan.susan_backend(), K.candidates._cache.__class__.__name__, getattr(K.candidates._cache, "_cache_path", ""))
    """
    home = tmp_path / "home"
    env = {"HOME": str(home), "XDG_CACHE_HOME": str(home / ".cache"), "NUMBA_CACHE_DIR": None}
    r = _child(code, {**env, "TEST_MODE": "user"})
    assert r.returncode == 0, r.stderr
    backend, cache, path = r.stdout.split()
    assert backend == "numba" and cache == "FunctionCache" and path.startswith(str(home / ".cache" / "numba")), r.stdout
    assert any((home / ".cache" / "numba").rglob("*.nbi"))  # the index of the compiled kernels
    r = _child(code, {**env, "TEST_MODE": "none"})
    assert r.returncode == 0, r.stderr
    assert r.stdout.split()[:2] == ["numba", "NullCache"], r.stdout


def test_a_short_script_does_not_compile_and_leaves_the_kernels_for_the_next_run(tmp_path):
    """With numba and an empty cache, a script that calls SUSAN once and ends neither compiles in
    its own process (numba's type inference holds the GIL: its calls would crawl) nor waits: a
    detached child compiles into numba's cache and finishes after the script has ended, so the
    next run only loads the kernels (no compile in its process, whatever the timing: the
    children take turns)."""
    env = {"NUMBA_CACHE_DIR": str(tmp_path / "numba-cache"), "EJSRL_SUSAN": "auto"}
    first = """
        import sys, time
        t0 = time.perf_counter()
        import cv2
        from skimage import data
        from ejsrl.vision import susan_corners
        pts = susan_corners(cv2.resize(data.camera(), (640, 480), interpolation=cv2.INTER_AREA))
        print(len(pts), "numba" in sys.modules)
    """
    t0 = time.perf_counter()
    r = _child(first, env)
    took = time.perf_counter() - t0
    assert r.returncode == 0 and r.stderr == "", r.stderr
    n, numba_here = r.stdout.split()
    assert int(n) > 100 and numba_here == "False"
    assert took < 10, f"the script took {took:.1f} s: it waited for the compile"
    second = """
        from ejsrl.vision import _susan, _susan_numba as K
        _susan.BACKEND = "numba"
        assert _susan.susan_backend() == "numba"
        kernels = [getattr(K, k) for k in dir(K) if hasattr(getattr(K, k), "stats")]
        print(sum(sum(k.stats.cache_misses.values()) for k in kernels), sum(sum(k.stats.cache_hits.values()) for k in kernels))
    """
    r = _child(second, env)
    assert r.returncode == 0, r.stderr
    misses, hits = (int(x) for x in r.stdout.split())
    assert misses == 0 and hits >= 5, r.stdout


def test_a_bundled_app_runs_susan_compiled_though_numba_cannot_cache_it(tmp_path):
    """In a .pyz bundle the kernels' source is inside a zip: numba can write no cache for it and a
    compiling child would have nothing to leave, so the kernels compile in the process (the
    child's cache key once failed on the zip's path and turned the compiled path off)."""
    from ejsgen.cli import build
    from testkit import EXAMPLES

    app = build(EXAMPLES / "paper" / "visual_servoing_eih.ejs.yaml", tmp_path / "servo", bundle=True)
    pyz = next(app.glob("*.pyz"))
    code = f"""
        import sys
        sys.path.insert(0, {str(pyz)!r})
        from ejsrl.vision import _susan
        assert ".pyz" in _susan.__file__, _susan.__file__
        _susan.BACKEND = "numba"
        print(_susan.susan_backend(), _susan._COMPILED.error)
    """
    r = _child(code)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["numba", "None"], r.stdout


def test_an_unknown_backend_is_a_clear_error(monkeypatch):
    monkeypatch.setattr(_susan, "BACKEND", "numbaa")
    with pytest.raises(ValueError, match=r"EJSRL_SUSAN.*did you mean 'numba'"):
        susan_corners(_grey("camera"))


def test_the_lazy_maxima_go_on_when_their_room_runs_out(monkeypatch):
    """``lazy_maxima`` given too little room for its chains says so, and called again with more
    (as ``_corners_compiled`` does) finds the maxima ``put_back`` and ``window_maxima`` find."""
    monkeypatch.setattr(_susan, "BACKEND", "numba")
    kernels = _susan._COMPILED.get(wait=True)
    img = SCENES["blurred noise"]()
    H, W = img.shape
    t, g100, floor = 25.0, 1850.0, 150.0
    below = np.nextafter(np.float32(floor), np.float32(-np.inf))
    args = (kernels, img, t, g100, floor, below, floor - 100.0, _susan._lut(t), _susan._bound_limit(t, g100 - floor + 1.0), 3)
    resp, whole = _susan._corners_compiled(*args, whole=True)
    assert len(whole) > 100
    # the map before the failing pixels are decided, and the passing pixels, from the same steps
    seen = {}
    real = kernels.lazy_maxima

    def record(resp, r, passing, a, b, *room):
        seen.setdefault("resp", resp.copy())
        seen["passing"] = passing  # the candidates
        return real(resp, r, passing, a, b, *room)

    proxy = type("K", (), {k: staticmethod(getattr(kernels, k)) for k in dir(kernels) if not k.startswith("__")})
    proxy.lazy_maxima = staticmethod(record)
    _, lazy = _susan._corners_compiled(proxy, *args[1:], whole=False)
    np.testing.assert_array_equal(np.sort(lazy), np.sort(whole))  # (in raster order; the other with the saddles first)
    passing = seen["passing"]
    keep = np.empty(len(passing), bool)
    calls, room = 0, 1
    while not real(seen["resp"], 3, passing, 0, len(passing), np.empty((4, room), np.int64), np.empty(room, np.int64), keep):
        calls, room = calls + 1, room * 2
    assert calls >= 3  # it ran out, and went on from what it had decided
    np.testing.assert_array_equal(np.sort(passing[keep]), np.sort(whole))
