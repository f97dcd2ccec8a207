"""SUSAN corners and edges (Smith and Brady, 1997), vectorised over the image.

For each pixel (the *nucleus*) the 37-pixel circular mask (radius 3.4) is laid on the
image and every mask pixel is compared with the nucleus brightness with the smooth test
``c = exp(-((I - I0) / t) ** 6)``; ``n``, the sum of ``c`` over the mask, is the area of
the USAN ("univalue segment assimilating nucleus"). A corner or an edge is where the USAN
is small: the response is ``g - n`` where ``n < g``, with the geometric threshold ``g``
half the mask area for corners and three quarters for edges.

The whole-image USAN (``usan_area``, edges) is computed with OpenCV operations over the 18
offset pairs (d, -d) (the brightness test is symmetric). Corners need it only where it is
small: a lower bound on it, summed with OpenCV's saturating uint8 operations (much cheaper
than the look-up), leaves the few pixels that may have a response; their 37 mask pixels
are gathered once, and the exact USAN and every test work on those rows with NumPy
indexing. The result is the same as testing every pixel of the image.

Corners in anti-aliased (or slightly blurred) images need one addition to the original:
a pixel inside an edge has an in-between grey, so its own USAN is tiny and means nothing.
Such a pixel is judged as the side it belongs to: each mask pixel counts by its share of
that side, and the response is what that side falls short of the half-plane a straight
edge would leave (see ``susan_corners``). This finds obtuse corners, whose only small
USAN is at the anti-aliased apex, and gives true sub-pixel output (``_refine``: Foerstner's corner);
X-junctions (checkerboard corners) are recognised by their brighter and darker pixels
lying in opposite quadrants around the nucleus. (So an X-junction needs in-between pixels:
hard-edged checkerboards, with two grey levels only, give none, and blur beyond about
1 px sigma loses most; polygon vertices hold up better. Measured in session 7's trial.)

Speed: with numba installed (``pip install 'ejsgen[fast]'``), ``susan_corners`` runs its loops
compiled (``_susan_numba``: the same corners, response and sub-pixel positions, bit for bit,
3x as fast on one thread, 5x on two, outside the GIL). Outside a served class a call runs them on two
threads (``set_threads``; a served class sets one, its sessions already sharing the cores). On
one thread each in CPU time (a served class; bench/vision.py, 2026-11-27, load 0.9 on the
2-core machine) it takes 1.47x the time of ``cv2.goodFeaturesToTrack`` at the median over 40
photographs at 640x480 and 4.5x at worst (textures: page, a forest slope, grass, gravel: 8
of 40 over 3x; the bench prints where the time goes, stage by stage); on two threads in wall
time 1.2x and 3.0x. The NumPy path: 4.7x at the
median, 16x at worst. Blurred pictures: ``blur=`` (``_susan_scale``).
Without numba, this NumPy/OpenCV code. The kernels are compiled (a child process writes
numba's cache, once per machine) or loaded in the background from the first call, this code
running until they are ready (``_Compiled``).
``EJSRL_SUSAN=numpy`` (or ``_susan.BACKEND = "numpy"``) forces the NumPy path, ``numba`` the
compiled one (waiting for it; an ``ImportError`` with the install hint without numba).

Features are ``(x, y)`` = (column, row) pixel coordinates, as in OpenCV.
"""

from __future__ import annotations

import collections
import functools
import importlib.util
import os
import sys
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from types import ModuleType
from typing import NamedTuple

import cv2
import numpy as np
from numpy.typing import NDArray

from ejsrl.vision._util import as_gray, choice, image_function

__all__ = ["SUSAN_MASK", "usan_area", "susan_corners", "susan_edges", "susan"]

#: the (dx, dy) offsets of the 37-pixel circular mask, nucleus included
SUSAN_MASK: NDArray[np.int64] = np.array(
    [(dx, dy) for dy in range(-3, 4) for dx in range(-3, 4) if dx * dx + dy * dy <= 11.56], dtype=np.int64
)
_R = 3  # mask radius in whole pixels
_CHORD = 6.8  # the mask's diameter in pixels
_MID_SLACK = 1.0  # in-between pixels kept for the test as the side they belong to: whole-image estimate >= min_response - this
_SCALE = 100  # c is stored as round(100 c) in a uint8 look-up table, as in the original code

#: which implementation ``susan_corners`` runs: "auto" (the numba kernels when numba can be
#: imported, else NumPy), "numpy" or "numba"; from ``EJSRL_SUSAN``, read at each call
BACKEND: str = os.environ.get("EJSRL_SUSAN", "auto")
#: threads one ``susan_corners`` call runs numba's kernels on: None for the
#: default, 2 on a machine with at least 2 cores (``EJSRL_SUSAN_THREADS`` overrides it). A served
#: class sets 1 (``set_threads``): its sessions already run side by side in a pool of threads
THREADS: int | None = None
_MIN_SPLIT = 1 << 16  # images with fewer pixels stay on one thread (handing work over costs ~50 us)
FAST_HINT = "SUSAN's compiled kernels need numba: pip install 'ejsgen[fast]' (or: pip install numba)"


class _Compiled:
    """numba's kernels, compiled (or loaded from numba's cache) once per process in a thread.

    The first process on a machine compiles them (10-11 s on an idle 2-core machine, 17-29 s on
    a loaded one); later ones load them from numba's cache (0.5 s idle, 1.1-2.3 s loaded,
    numba's import included). With
    ``BACKEND = "auto"`` no SUSAN call waits for that: until the kernels are ready the NumPy
    path runs (the same corners).

    The compile runs in a child process (``_warm_cache``, where the system can start one
    detached: POSIX), which writes numba's cache; this process then loads the kernels from it.
    numba's type inference is Python code holding the GIL: compiled in this process, it made
    the NumPy path's calls 2-3x slower for the compile's 12 s, and a short script that ended
    before the compile did left no cache, so every run started over. The child outlives a
    short script, finishes the cache for the next run, and runs one at a time across
    processes that would write the same cache (a lock file: a served class's workers start
    together), the others then loading what it wrote. Without a cache numba can write (no writable place), or where the
    child fails, the kernels compile in this process as before (``EJSRL_SUSAN_CHILD=0``: always).
    """

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.thread: threading.Thread | None = None
        self.module: ModuleType | None = None
        self.error: BaseException | None = None
        self.disc_sums_match = False  # the kernels' sums over the mask are OpenCV's filter2D's
        self.child: int | None = None  # the compiling child's pid, while it runs

    def get(self, wait: bool) -> ModuleType | None:
        if self.module is not None:
            return self.module
        with self.lock:
            if self.thread is None:
                if importlib.util.find_spec("numba") is None:  # not installed: the NumPy path, silently
                    self.error = ImportError(FAST_HINT)
                    return None
                self.thread = threading.Thread(target=self._compile, name="ejsrl-susan-numba", daemon=True)
                self.thread.start()
        if wait:
            self.thread.join()
        return self.module

    def _compile(self) -> None:
        try:
            self._compile_in_child()
            from ejsrl.vision import _susan_numba

            self.disc_sums_match = _disc_sums_match(_susan_numba)
            _warm_up(_susan_numba)
        except Exception as e:  # noqa: BLE001 - numba that cannot run here: the NumPy path
            self.error = e
            return
        self.module = _susan_numba

    def _compile_in_child(self) -> bool:
        """Have a detached child process compile the kernels into numba's cache (or find them
        there) and wait for it: True when it did. False where no child can be started this way
        (not POSIX), or it failed, or numba has no cache here: the caller compiles."""
        if not hasattr(os, "posix_spawn") or os.environ.get("EJSRL_SUSAN_CHILD") == "0":
            return False
        try:
            if _cache_mark("done").exists():  # a child cached these kernels already: load them here
                return True
        except OSError:  # the source is no file (a .pyz): numba cannot cache it, nothing for a child to do
            return False
        pid = _spawn_warm_child()
        if pid is None:  # no interpreter to start (an embedded Python): compile here
            return False
        self.child = pid
        try:
            _, status = os.waitpid(pid, 0)  # outside the GIL
        finally:
            self.child = None
        return os.waitstatus_to_exitcode(status) == 0


def _spawn_warm_child() -> int | None:
    """Start the detached child that writes numba's cache (``_warm_cache``, in a session of its own:
    a Ctrl+C in this terminal does not stop it half-way through the cache, and it outlives a short
    script); its pid, or None where no interpreter can be started so."""
    import ejsrl

    root = str(Path(ejsrl.__file__).resolve().parent.parent)  # the folder (or .pyz) this ejsrl is in
    code = f"import sys; sys.path.insert(0, {root!r}); from ejsrl.vision._susan import _warm_cache; sys.exit(_warm_cache())"
    actions = [(os.POSIX_SPAWN_OPEN, fd, os.devnull, os.O_RDWR, 0) for fd in (0, 1, 2)]
    try:
        return os.posix_spawn(sys.executable, [sys.executable, "-P", "-c", code], os.environ, file_actions=actions, setsid=True)
    except OSError:
        return None


def _cache_mark(kind: str) -> Path:
    """A file in the temporary directory for these kernels' cache ("lock": the child compiling
    them holds it; "done": a child cached them): one per source (its file, as changed last)
    and numba cache directory, so only processes writing the same cache take turns. (A cache
    deleted after its "done" only costs a compile in the process, as without a child.)"""
    import hashlib
    import tempfile

    src = Path(importlib.util.find_spec("ejsrl.vision._susan_numba").origin)
    where = [os.environ.get(k, "") for k in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME", "HOME")]  # numba's user-wide cache follows them
    key = hashlib.sha1(f"{src.resolve()}|{src.stat().st_mtime_ns}|{where}".encode()).hexdigest()[:16]
    return Path(tempfile.gettempdir()) / f"ejsrl-susan-numba-{os.getuid()}-{key}.{kind}"


def _warm_cache() -> int:
    """A child process's work (``_Compiled._compile_in_child``): compile numba's kernels into its
    cache, or load them from it, one process at a time; 0 when they are cached (and marked
    so: later processes skip the child), 3 when numba has no cache here (nothing to gain from
    a child)."""
    import fcntl

    with open(_cache_mark("lock"), "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)  # released when this process ends
        from ejsrl.vision import _susan_numba

        _disc_sums_match(_susan_numba)
        _warm_up(_susan_numba)
        if type(getattr(_susan_numba.candidates, "_cache", None)).__name__ == "NullCache":
            return 3
        _cache_mark("done").touch()
        return 0


_COMPILED = _Compiled()


def _warm_up(kernels: ModuleType) -> None:
    """Run every kernel once (with the argument types of real calls) on a small scene that takes
    every branch of ``_corners_compiled``: anti-aliased polygons and an X-junction in noise."""
    big = np.full((768, 768), 40, np.uint8)  # 8x supersampled, averaged down: anti-aliased edges
    cv2.fillPoly(big, [np.array([[60, 80], [400, 130], [150, 420]], np.int32)], 200)
    big[480:600, 480:600] = big[600:720, 600:720] = 230  # an X-junction
    img = cv2.resize(big, (96, 96), interpolation=cv2.INTER_AREA)
    noisy = np.clip(img + np.random.default_rng(0).normal(0, 4, img.shape), 0, 255).astype(np.uint8)
    for g in (img, noisy):
        t, g100, floor = 25.0, 1850.0, 150.0
        below = np.nextafter(np.float32(floor), np.float32(-np.inf))
        for whole in (True, False):
            _, ci = _corners_compiled(kernels, g, t, g100, floor, below, floor - _MID_SLACK * _SCALE, _lut(t), _bound_limit(t, g100 - floor + 1.0), 3, whole)
        _refine(g, np.column_stack([ci % g.shape[1], ci // g.shape[1]]).astype(np.float64), kernels)


def _kernels() -> ModuleType | None:
    """The compiled kernels module for this call, or None for the NumPy path (``BACKEND``:
    "auto" takes the kernels once they are ready, "numba" waits for them)."""
    which = choice(BACKEND, ("auto", "numpy", "numba"), "SUSAN backend (EJSRL_SUSAN)")
    if which == "numpy":
        return None
    mod = _COMPILED.get(wait=which == "numba")
    if mod is None and which == "numba":
        raise ImportError(f"{FAST_HINT} ({_COMPILED.error})") from _COMPILED.error
    return mod


def finish_compile() -> None:
    """Wait for the compile of numba's kernels if a SUSAN call has started it (a served
    lab calls this before its class comes: a compile in a busy server is slow)."""
    thread = _COMPILED.thread
    if thread is not None:
        thread.join()


def susan_backend(wait: bool = False) -> str:
    """"numba" or "numpy": the implementation ``susan_corners`` runs now (``BACKEND``); with
    ``wait``, once numba's kernels are compiled (where numba is installed)."""
    if wait and BACKEND == "auto":
        _COMPILED.get(wait=True)
    return "numpy" if _kernels() is None else "numba"


def set_threads(n: int | None) -> None:
    """Run each ``susan_corners`` call on ``n`` threads at most (1: the calling thread only, as a
    served class needs; None: the default, ``susan_threads``). The result is the same either way."""
    global THREADS
    THREADS = None if n is None else max(1, int(n))


def susan_threads() -> int:
    """The threads a ``susan_corners`` call uses now (1 or 2; only numba's path uses a second)."""
    if THREADS is not None:
        return THREADS
    env = os.environ.get("EJSRL_SUSAN_THREADS", "").strip()
    if env:
        if not env.isdigit():
            raise ValueError(f"EJSRL_SUSAN_THREADS={env!r}: write the number of threads SUSAN may use, 1 or 2")
        return min(2, max(1, int(env)))
    return 2 if (os.cpu_count() or 1) >= 2 else 1


_POOL: ThreadPoolExecutor | None = None
_POOL_LOCK = threading.Lock()


def _pool() -> ThreadPoolExecutor:
    global _POOL
    if _POOL is None:
        with _POOL_LOCK:
            if _POOL is None:
                _POOL = ThreadPoolExecutor(max_workers=1, thread_name_prefix="ejsrl-susan")
    return _POOL


def _two(split: bool, fn, first: tuple, second: tuple):
    """``fn(*first), fn(*second)``: the second in the pool's thread at the same time when ``split``
    (numba's kernels and OpenCV release the GIL)."""
    if not split:
        return fn(*first), fn(*second)
    fut = _pool().submit(fn, *second)
    return fn(*first), fut.result()


def _shared(tasks: list) -> list:
    """The results of the callables ``tasks``, run by this thread from the first and the pool's
    thread from the last, each taking the next one left until none is (whichever is faster takes more)."""
    results: list = [None] * len(tasks)
    left = collections.deque(range(len(tasks)))

    def run(take) -> None:
        while True:
            try:
                i = take()
            except IndexError:
                return
            results[i] = tasks[i]()

    fut = _pool().submit(run, left.pop)
    try:
        run(left.popleft)
    finally:
        fut.result()
    return results


_BANDS = 6  # the candidate search's bands of rows on two threads


def _lut(t: float) -> NDArray[np.uint8]:
    d = np.arange(256, dtype=np.float64)
    return np.rint(_SCALE * np.exp(-((d / float(t)) ** 6))).astype(np.uint8)


@image_function
def usan_area(img: NDArray, t: float = 20.0) -> NDArray[np.float32]:
    """The USAN area ``n`` (H, W) float32 in mask pixels (0..37) of each pixel of a grey image.

    ``t``: brightness threshold (grey levels). Pixels closer than 3 to the border see a
    replicated border.
    """
    n, _, _ = _usan(as_gray(img), t)
    return n.astype(np.float32) / _SCALE


def _usan(gray: NDArray[np.uint8], t: float) -> tuple[NDArray[np.uint16], NDArray[np.uint8], NDArray[np.uint8]]:
    """USAN area scaled by 100 (H, W) uint16, the padded image and the LUT.

    The brightness test is symmetric, ``c(p, p + d) = c(p + d, p)``, so each of the 18
    offset pairs (d, -d) needs one difference image and one look-up: over the pixels q of
    the image and of the image shifted by -d, ``E(q) = c(|I(q) - I(q + d)|)``; pixel p gets
    ``E(p)`` for offset d and ``E(p - d)`` for offset -d, added in uint16 (at most 3700).
    """
    H, W = gray.shape
    pad = cv2.copyMakeBorder(gray, _R, _R, _R, _R, cv2.BORDER_REPLICATE)
    lut = _lut(t)
    lut16 = lut.astype(np.uint16)  # the look-up writes uint16: the sums stay in OpenCV's 16-bit adds
    acc = np.full((H, W), _SCALE, dtype=np.uint16)  # the nucleus itself
    diff = np.empty((H + _R, W + 2 * _R), np.uint8)
    E16 = np.empty((H + _R, W + 2 * _R), np.uint16)
    for dx, dy in SUSAN_MASK:
        if dy < 0 or (dy == 0 and dx <= 0):
            continue  # one offset of each pair (d, -d)
        # q spans rows -dy .. H-1 and columns min(0, -dx) .. max(W, W - dx) - 1 of the image
        r0, c0 = _R - dy, _R + min(0, -dx)
        h, w = H + dy, W + abs(dx)
        a = pad[r0 : r0 + h, c0 : c0 + w]
        b = pad[r0 + dy : r0 + dy + h, c0 + dx : c0 + dx + w]
        E = E16[:h, :w]
        cv2.LUT(cv2.absdiff(a, b, dst=diff[:h, :w]), lut16, dst=E)
        py, px = dy, -min(0, -dx)  # where the image's pixel (0, 0) sits in E
        cv2.add(acc, E[py : py + H, px : px + W], dst=acc)
        cv2.add(acc, E[py - dy : py - dy + H, px - dx : px - dx + W], dst=acc)
    return acc, pad, lut


def _local_max(resp: NDArray[np.float32], radius: int, ys: NDArray, xs: NDArray) -> NDArray[np.bool_]:
    """Which of the pixels (ys, xs) are maxima of ``resp`` in their (2r+1)^2 window.

    On a plateau only the first pixel in raster order is kept: a pixel must be >= every
    neighbour and > those before it (rows above, or to its left on its row).
    """
    if len(ys) == 0:
        return np.zeros(0, bool)
    r = int(radius)
    dy, dx = np.mgrid[-r : r + 1, -r : r + 1]
    dy, dx = dy.ravel(), dx.ravel()
    centre = (dy == 0) & (dx == 0)
    before = (dy < 0) | ((dy == 0) & (dx < 0))
    H, W = resp.shape
    if r <= min(ys.min(), xs.min(), H - 1 - ys.max(), W - 1 - xs.max()):  # every window inside the image
        win = resp.ravel().take((ys * W + xs)[:, None] + (dy * W + dx)[None, :])
    else:
        rp = cv2.copyMakeBorder(resp, r, r, r, r, cv2.BORDER_CONSTANT, value=0.0)
        win = rp[(ys + r)[:, None] + dy[None, :], (xs + r)[:, None] + dx[None, :]]
    v = resp[ys, xs][:, None]
    ok_after = (win <= v) | centre[None, :]
    ok_before = (win < v) | ~before[None, :]
    return (v[:, 0] > 0) & ok_after.all(axis=1) & ok_before.all(axis=1)


def _gather(pad: NDArray[np.uint8], gray: NDArray[np.uint8], lut: NDArray[np.uint8], ys: NDArray, xs: NDArray):
    """c (K, 37) uint8 in [0, 100] of the mask pixels around the candidate pixels (ys, xs)."""
    Wp = pad.shape[1]
    offs = SUSAN_MASK[:, 1] * Wp + SUSAN_MASK[:, 0]
    base = (ys + _R) * Wp + (xs + _R)
    vals = pad.ravel()[base[:, None] + offs[None, :]].astype(np.int16)
    diff = np.abs(vals - gray.ravel()[ys * gray.shape[1] + xs].astype(np.int16)[:, None])
    return np.take(lut, diff)


def _candidates(gray: NDArray[np.uint8], t: float, g100: float):
    """Pixels whose USAN area (x100) is below ``g100``: rows, columns, their c (K, 37) and n (K,).

    Only pixels whose 7x7 neighbourhood spans enough grey levels can have a small USAN:
    with every difference at most ``r``, ``n >= 37 exp(-(r / t)^6)``. Those few pixels are
    evaluated by gathering their 37 neighbours; if they are many (a busy or noisy image),
    the whole-image pass of ``_usan`` is cheaper and is used instead. Same result either way.
    """
    H, W = gray.shape
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, len(SUSAN_MASK))), np.zeros(0))
    pad = cv2.copyMakeBorder(gray, _R, _R, _R, _R, cv2.BORDER_REPLICATE)
    lut = _lut(t)
    if H <= 2 * _R + 2 or W <= 2 * _R + 2:
        return (*empty, pad, lut)
    nmax = len(SUSAN_MASK) * _SCALE
    if g100 >= nmax:
        maybe = np.ones((H, W), bool)
    else:
        need = 0.9 * float(t) * np.log(nmax / g100) ** (1.0 / 6.0)
        k = np.ones((2 * _R + 1, 2 * _R + 1), np.uint8)
        spread = cv2.subtract(cv2.dilate(gray, k), cv2.erode(gray, k))
        maybe = spread > need
    _clear_border(maybe, _R + 1)
    if maybe.mean() > 0.25:
        acc, _, _ = _usan(gray, t)
        maybe &= acc < g100
    ys, xs = np.divmod(np.flatnonzero(maybe), W)
    c8 = _gather(pad, gray, lut, ys, xs)
    n = c8.sum(axis=1, dtype=np.int32)
    small = np.flatnonzero(n < g100)
    return ys[small], xs[small], c8[small].astype(np.float64), n[small].astype(np.float64), pad, lut


def _clear_border(resp: NDArray, b: int) -> None:
    resp[:b] = 0
    resp[-b:] = 0
    resp[:, :b] = 0
    resp[:, -b:] = 0


#: (37, 3) float32: each mask pixel's 1, dx, dy (a matrix product gives the sum, x and y moments)
_MOMENTS = np.column_stack([np.ones(len(SUSAN_MASK)), SUSAN_MASK[:, 0], SUSAN_MASK[:, 1]]).astype(np.float32)
#: rows per matrix product: OpenCV's gemm hands large products to its bundled OpenBLAS, whose
#: threads then spin for a while after each call (on a shared 2-core machine that takes a core
#: from everything running next); OpenBLAS stays on one thread below m n k = 4 * 65536
_GEMM_ROWS = 2000


def _moments(c: NDArray) -> NDArray[np.float64]:
    """(K, 3): the sum, x and y moments over the mask of each row of ``c`` (K, 37), float32 or float64.

    Exact either way, whatever order the matrix product sums in: float32 holds integers (the
    c of the smooth test) below 2^24; float64 holds the coverage test's float32 shares (in
    [0.25, 100] or 0, multiples of 2^-25) and their sums over the mask (below 2^14) exactly.
    So the compiled kernels (``_susan_numba``) and any BLAS give the same moments, bit for bit.
    """
    out = np.empty((len(c), 3), c.dtype)
    mom = _MOMENTS if c.dtype == np.float32 else _MOMENTS64
    for i in range(0, len(c), _GEMM_ROWS):
        cv2.gemm(c[i : i + _GEMM_ROWS], mom, 1.0, None, 0.0, dst=out[i : i + _GEMM_ROWS])
    return out.astype(np.float64)


_MOMENTS64 = _MOMENTS.astype(np.float64)


def _corner_tests(pf: NDArray[np.uint8], Wp: int, base: NDArray, c: NDArray, brighter, similar, *, return_saddle: bool = False, contig: float = 2.9 * _SCALE):
    """The false-positive tests on the nuclei at flat indices ``base`` of the padded image
    (``pf``, rows ``Wp`` wide); returns which pass and their USAN areas n (x100).

    ``c`` (K, 37) float32: the similarity (x100, at most 100) of each mask pixel to its nucleus;
    ``brighter(rows)`` (k, 37) bool: which of them, for the nuclei ``rows`` (indices), are
    brighter than the nucleus (a pixel with c = 100 counts as alike, whatever it says), or
    None where the unlike pixels cannot be split (all of them on one side: test 3 cannot
    fail); ``similar(values, rows)``: c (k, 3) of the grey values (k, 3) uint8 of three
    pixels around each nucleus of ``rows`` (indices).

    1. (Smith and Brady) the USAN centroid lies more than 1/sqrt(2) pixel from the nucleus;
    2. (Smith and Brady) the three pixels from the nucleus towards the centroid are in the USAN;
    3. (one-sided) the pixels unlike the nucleus are not split into brighter ones on one side
       and darker ones on the other, as around a nucleus inside an anti-aliased edge.

    All K pixels are tested at once: the sums and moments over the mask are matrix products
    (``_moments``); the mask is symmetric, so the unlike pixels' moments follow from the USAN's.
    """
    K = len(base)
    if K == 0:
        return (np.zeros(0, bool), np.zeros(0), np.zeros(0, bool)) if return_saddle else (np.zeros(0, bool), np.zeros(0))
    m = _moments(c)
    n, sx, sy = m[:, 0], m[:, 1], m[:, 2]
    ok = sx * sx + sy * sy > 0.5 * n * n  # far enough
    # the other two tests only where they can still change the answer (most pixels inside an
    # edge already fail this one); the saddle test needs the unlike pixels' moments everywhere
    rows = np.arange(K) if return_saddle else np.flatnonzero(ok)
    if len(rows) == 0:
        return ok, n
    if len(rows) < K:
        base, n, sx, sy = base[rows], n[rows], sx[rows], sy[rows]
    ax, ay = np.abs(sx), np.abs(sy)
    along_x = ay < ax
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.where(along_x, sy / np.where(ax > 0, ax, 1), sx / np.where(ay > 0, ay, 1))
    sgn = np.where(along_x, np.sign(sx), np.sign(sy)).astype(np.int64)
    # the three pixels from the nucleus towards the centroid, as flat offsets (k = 1, 2, 3),
    # rounded half away from zero
    ks = _K123[None, :] * slope[:, None]
    off = np.trunc(ks + np.copysign(0.5, ks)).astype(np.int64)
    along = _K123.astype(np.int64)[None, :] * sgn[:, None]
    step = np.where(along_x[:, None], off * Wp + along, along * Wp + off)
    total = similar(pf.take(base[:, None] + step), rows).sum(axis=1, dtype=np.float64)
    contiguous = total > contig
    if brighter is None:
        ok[rows] &= contiguous
        return ok, m[:, 0]
    # the moments of the unlike pixels (weights 100 - c), split into brighter and darker ones
    bright = np.subtract(np.float32(_SCALE), c[rows] if len(rows) < K else c)
    np.multiply(bright, brighter(rows), out=bright)
    bright_m = _moments(bright)
    mb, bx, by = bright_m[:, 0], bright_m[:, 1], bright_m[:, 2]
    md, dx_, dy_ = _SCALE * len(SUSAN_MASK) - n - mb, -sx - bx, -sy - by
    opposite = bx * dx_ + by * dy_ < 0
    balanced = np.minimum(mb, md) > 0.25 * (mb + md)
    two_sided = opposite & balanced
    ok[rows] &= contiguous & ~two_sided
    if not return_saddle:
        return ok, m[:, 0]
    # an X-junction (a saddle: the corner of a checkerboard) is two-sided too, but its brighter
    # and its darker pixels each lie in two opposite quadrants, centred on the nucleus
    with np.errstate(divide="ignore", invalid="ignore"):
        off_b = np.hypot(bx, by) / np.where(mb > 0, mb, 1)
        off_d = np.hypot(dx_, dy_) / np.where(md > 0, md, 1)
    saddle = (np.minimum(mb, md) > 0.3 * (mb + md)) & (mb + md > 0.35 * _SCALE * len(SUSAN_MASK)) & (off_b < 0.8) & (off_d < 0.8)
    return ok, n, saddle


_K123 = np.arange(1, 4, dtype=np.float64)


def _smooth_test(pf: NDArray[np.uint8], Wp: int, base: NDArray, vals: NDArray, c8: NDArray, lut: NDArray[np.uint8], which: NDArray | None = None, **kw):
    """``_corner_tests`` with SUSAN's test ``c = exp(-((I - I0) / t)^6)`` (the LUT, ``c8`` its
    values for the mask pixels ``vals``) around the nuclei's own grey levels; on the rows
    ``which`` (indices) of these arrays, or all."""
    if which is None:
        which = np.arange(len(base))
    g0 = vals[which, _NUCLEUS][:, None]

    def similar(v: NDArray, rows: NDArray) -> NDArray:
        return cv2.LUT(cv2.absdiff(v, np.repeat(g0[rows], v.shape[1], axis=1)), lut)

    def brighter(rows: NDArray) -> NDArray:
        return vals[which[rows]] > g0[rows]

    return _corner_tests(pf, Wp, base[which], c8[which].astype(np.float32), brighter, similar, **kw)


def _coverage_test(pf: NDArray[np.uint8], Wp: int, base: NDArray, vals: NDArray, lo: NDArray, hi: NDArray, dark: NDArray):
    """``_corner_tests`` for nuclei inside an anti-aliased edge between grey levels lo and hi,
    judged as the dark side (where ``dark``) or the bright one: each pixel counts by its share
    of that side, ``(hi - I) / (hi - lo)`` clipped to [0, 1] for the dark side (x100); for
    the dark side the pixels unlike it are brighter, for the bright side darker."""
    lo8 = np.ascontiguousarray(lo, dtype=np.uint8)[:, None]
    span8 = np.maximum(np.subtract(hi, lo, dtype=np.uint8), np.uint8(1))[:, None]  # hi >= lo: the max and min of one window
    spanf = span8.astype(np.float32)
    d = dark[:, None]

    def side(v: NDArray, rows: NDArray | slice = slice(None)) -> NDArray:
        # (I - lo) clipped to [0, span] in uint8, then divided: the same float32 share as
        # clip((I - lo) / span, 0, 1), with three of its passes over the values in uint8
        x = np.maximum(v, lo8[rows])
        np.subtract(x, lo8[rows], out=x)
        np.minimum(x, span8[rows], out=x)
        share = np.divide(x, spanf[rows], dtype=np.float32)
        np.subtract(np.float32(1.0), share, out=share, where=d[rows])
        # float64 (the float32 values): their sums over the mask are then exact (see _moments)
        return np.multiply(share, np.float32(_SCALE), out=share).astype(np.float64)

    # the pixels unlike the side are all on the other side (brighter than the dark side,
    # darker than the bright one), never split into two: the one-sided test cannot fail
    return _corner_tests(pf, Wp, base, side(vals), None, side, contig=_SIDE_CONTIG)


#: the column of SUSAN_MASK that is the nucleus
_NUCLEUS = int(np.flatnonzero((SUSAN_MASK[:, 0] == 0) & (SUSAN_MASK[:, 1] == 0))[0])
_MAX_MARGIN = 14  # the widest ramp of _ramp_bound: 36 neighbours of at most 14 fit in uint8 below the threshold


@functools.lru_cache(maxsize=16)
def _ramp_bound(t: float) -> tuple[int, int, float]:
    """``(T, m, s)`` with ``s min((T - d)+, m) <= c(d)`` (the LUT, x100) for every difference d.

    A lower bound on SUSAN's test that OpenCV's saturating uint8 arithmetic computes much
    faster than the look-up: the largest such ramp (its area) of at most ``_MAX_MARGIN`` steps.
    """
    lut = _lut(t).astype(np.float64)
    d = np.arange(256)
    zero = np.flatnonzero(lut == 0)
    top = int(zero[0]) + 1 if len(zero) else 256  # a ramp reaching a zero of the LUT has s = 0
    T = np.arange(1, top)[:, None, None]
    m = np.arange(1, _MAX_MARGIN + 1)[None, :, None]
    r = np.minimum(np.maximum(T - d, 0), m)  # (T, m, d)
    s = np.where(r > 0, lut / np.maximum(r, 1), np.inf).min(axis=2)
    area = s * r.sum(axis=2)
    i, j = np.unravel_index(int(np.argmax(area)), area.shape)
    return int(T[i, 0, 0]), int(m[0, j, 0]), float(s[i, j])


def _bound_limit(t: float, n_max: float) -> int | None:
    """The largest ramp sum L of ``_candidates_by_bound`` that may still have ``n <= n_max``; None
    when the bound cannot tell in uint8 (a large ``g``): then the exact whole-image pass is used."""
    s = _ramp_bound(float(t))[2]
    if n_max < _SCALE:
        return -1
    L_max = int(np.floor((n_max - _SCALE) / s))
    return L_max if L_max < 255 else None


def _candidates_by_bound(gray: NDArray[np.uint8], t: float, L_max: int, y0: int, y1: int) -> NDArray[np.int64]:
    """Flat image indices (raster order) of the pixels of rows ``y0 .. y1 - 1`` (at least ``_R + 1``
    from the border) whose USAN area may be small enough: a ramp sum ``L <= L_max`` (``_bound_limit``).

    With ``s min((T - d)+, m) <= c(d)`` (``_ramp_bound``), ``n >= 100 + s L`` where
    ``L = sum min((T - d)+, m)`` over the 36 neighbours: only pixels with ``L <= (n_max - 100) / s``
    can have ``n <= n_max``. L is summed in uint8 with OpenCV's saturating operations (at 255
    it stops, above any threshold it is compared with), five cheap whole-image operations per
    offset pair instead of the look-up; the exact USAN of the few candidates follows by gathering.
    """
    T, m, _ = _ramp_bound(float(t))
    H, W = gray.shape
    b = _R + 1
    Hi, Wi = y1 - y0, W - 2 * b
    if L_max < 0 or Hi <= 0 or Wi <= 0:
        return np.zeros(0, np.int64)
    acc = np.zeros((Hi, Wi), np.uint8)
    Tm = np.full((Hi + _R, Wi + _R), T, np.uint8)  # an array, not a scalar: OpenCV reads a scalar beside a tiny image as an array
    buf = np.empty((Hi + _R, Wi + _R), np.uint8)
    for dx, dy in SUSAN_MASK:
        if dy < 0 or (dy == 0 and dx <= 0):
            continue  # one offset of each pair (d, -d): E(q) = e(|I(q) - I(q + d)|) serves p = q and p = q + d
        qx, qy = b - max(dx, 0), y0 - dy
        w = Wi + abs(dx)
        e = buf[: Hi + dy, :w]
        cv2.absdiff(gray[qy : y1, qx : qx + w], gray[qy + dy : y1 + dy, qx + dx : qx + dx + w], dst=e)
        cv2.subtract(Tm[: Hi + dy, :w], e, dst=e)  # (T - d)+
        cv2.threshold(e, m, 0, cv2.THRESH_TRUNC, dst=e)  # min(., m)
        ex = max(dx, 0)
        cv2.add(acc, e[dy : dy + Hi, ex : ex + Wi], dst=acc)  # offset d of p: q = p
        ex = max(-dx, 0)
        cv2.add(acc, e[0:Hi, ex : ex + Wi], dst=acc)  # offset -d of p: q = p - d
    nz = cv2.findNonZero(np.less_equal(acc, np.uint8(L_max)).view(np.uint8))
    if nz is None:
        return np.zeros(0, np.int64)
    xy = nz.reshape(-1, 2).astype(np.int64)
    return (xy[:, 1] + y0) * W + (xy[:, 0] + b)


def _hidden_failures(resp: NDArray[np.float32], r: int, passing: NDArray[np.int64], failing: NDArray[np.int64], fv: NDArray) -> None:
    """Zero, in ``resp`` (H, W), the failing pixels (flat indices ``failing``, values ``fv``) that are
    not hidden: a failing pixel stays when a larger pixel that stays (passing, or failing and
    hidden itself) lies in its (2r+1)^2 window.

    Found from the passing pixels down: the windows of the pixels just found to stay are
    searched for smaller failing pixels, which stay in turn, until none is found.
    """
    H, W = resp.shape
    if len(failing) == 0:
        return
    rf = resp.ravel()
    rf[failing] = 0
    Wp = W + 2 * r
    undecided = np.full((H + 2 * r) * Wp, np.inf, np.float32)  # padded: the value of each failing pixel not yet found hidden
    to_pad = lambda i: (i // W + r) * Wp + i % W + r  # noqa: E731
    undecided[to_pad(failing)] = fv
    dy, dx = np.mgrid[-r : r + 1, -r : r + 1]
    offs = (dy * Wp + dx).ravel()
    slot = np.zeros(len(undecided), np.int64)  # to keep each pixel found once (the last of its entries)
    # the first step at once: failing pixels under a larger passing one (one dilation of the passing pixels)
    first = cv2.dilate(resp, np.ones((2 * r + 1, 2 * r + 1), np.uint8)).ravel().take(failing) > fv
    front, front_v = to_pad(failing[first]), fv[first]
    undecided[front] = np.inf
    rf[failing[first]] = front_v
    while len(front):
        where = front[:, None] + offs[None, :]
        found = where[undecided.take(where) < front_v[:, None]]
        slot[found] = np.arange(len(found))
        found = found[slot[found] == np.arange(len(found))]
        front_v = undecided[found]
        undecided[found] = np.inf
        front = found
        rf[(found // Wp - r) * W + found % Wp - r] = front_v


def _window_max(img: NDArray[np.float32], r: int, idx: NDArray[np.int64]) -> NDArray[np.float32]:
    """The largest value of ``img`` in the (2r+1)^2 window of each pixel (flat indices ``idx``, at
    least ``_R + 1`` from the border; outside the image counts as 0)."""
    if len(idx) * (2 * r + 1) ** 2 > img.size // 2:  # many: one whole-image dilation is cheaper
        return cv2.dilate(img, np.ones((2 * r + 1, 2 * r + 1), np.uint8)).ravel().take(idx)
    H, W = img.shape
    dy, dx = np.mgrid[-r : r + 1, -r : r + 1]
    if r <= _R + 1:  # SUSAN's pixels are at least _R + 1 from the border: their windows are inside
        return img.ravel().take(idx[:, None] + (dy * W + dx).ravel()[None, :]).max(axis=1)
    padded = cv2.copyMakeBorder(img, r, r, r, r, cv2.BORDER_CONSTANT, value=0.0)
    Wp = W + 2 * r
    offs = (dy * Wp + dx).ravel()
    centre = (idx // W + r) * Wp + idx % W + r
    return padded.ravel().take(centre[:, None] + offs[None, :]).max(axis=1)


@image_function
def susan_corners(
    img: NDArray,
    t: float | str = 25.0,
    *,
    g: float | None = None,
    nms_radius: int = 3,
    quality: float = 0.0,
    min_response: float = 1.5,
    max_corners: int | None = None,
    subpixel: bool = True,
    return_response: bool = False,
    blur: float | str | None = None,
) -> NDArray[np.float64] | tuple[NDArray[np.float64], NDArray[np.float32]]:
    """SUSAN corner detector (Smith and Brady 1997).

    ``img``: grey (H, W) or RGB (H, W, 3) image (uint8, or another type read as
    ``help(ejsrl.vision)`` says). ``t``: brightness threshold in grey levels (lower finds
    weaker corners, higher resists noise), or ``"auto"``: read from the image (half the step
    of its weaker edges, at most 25, at least 10 and 4.5 times its noise:
    ``_susan_scale.auto_threshold``), for rendered scenes and dim pictures whose regions differ
    by fewer than 25 grey levels (a dimly lit box's faces). ``g``: geometric threshold in mask pixels
    (default half the mask, 18.5). ``nms_radius``: non-maximum suppression window radius
    (3: 7x7, as in the original code). ``min_response``: drop corners whose response
    ``g - n`` is below this many mask pixels (a straight edge gives about 0, a 150-degree
    corner about 3; noise on edges gives up to about 1). ``quality``: also drop corners
    below this fraction of the strongest one (as ``cv2.goodFeaturesToTrack``'s quality
    level; 0: off). ``max_corners``: keep at most this many, strongest first.
    ``subpixel``: refine each corner to sub-pixel accuracy (``_refine``: the point where the
    edges through a 7x7 window meet, by least squares on the grey gradients, the model of
    ``cv2.cornerSubPix``: the true vertex of an L corner, the saddle of an X-junction), kept
    when it stays within 3 pixels; the pixel found otherwise is the one just inside the
    corner, up to about 1.5 px from the vertex.

    ``blur``: the image's blur, for blurred pictures (a defocused or moving camera, a
    virtual camera's ``blur`` option): None (default) searches the image as it is; a number
    is the camera's blur sigma in pixels; ``"auto"`` reads it from the image
    (``_susan_scale.estimate_blur``, ~1.5 ms at 640x480). When it reads above 0.9 px the mask
    is widened in proportion (the image averaged down by 1.7 sigma, the corners refined there,
    brought back and refined on the full image in a window widened alike: see
    ``ejsrl.vision._susan_scale``, with the recall it measures); sharper images are searched
    as with None.

    The response is ``g - n`` where the USAN area ``n < g``. The false-positive tests
    (see ``_corner_tests``: the centroid and contiguity tests of the original, and a test
    that rejects pixels inside anti-aliased edges) are applied to every pixel with a
    response, all at once (as in the original); a pixel that fails is removed where it is
    the largest in its window, and otherwise stays, hidden under a larger pixel, and still
    suppresses weaker ones around it (as when local maxima are tested and the windows of
    the rejected ones searched again until every maximum passes). Every peak of the
    returned response is then a corner.

    How it is computed (the result is the same as testing every pixel of the image): a
    cheap lower bound on the USAN area (``_candidates_by_bound``) leaves the few pixels
    that may have a response; their 37 mask pixels are gathered once, and the exact USAN,
    the in-between-grey test, the side's coverage and the false-positive tests all work
    on those rows.

    Returns the corners (N, 2) float64 as ``(x, y)`` pixel coordinates, strongest first
    (ties in raster order); with ``return_response`` also the response map (H, W) float32
    (after the tests: 0 where a maximum was rejected).
    """
    gray = np.ascontiguousarray(as_gray(img))  # (numba's kernels are compiled for C order)
    t = _threshold(gray, t)
    if not 0.0 <= float(quality) <= 1.0:
        raise ValueError(f"susan_corners: quality is a fraction of the strongest corner's response, in [0, 1] (0: off), got {quality}")
    if int(nms_radius) != nms_radius or nms_radius < 0:
        raise ValueError(f"susan_corners: nms_radius must be a whole number of pixels >= 0 (3: a 7 x 7 window), got {nms_radius}")
    if max_corners is not None and (int(max_corners) != max_corners or max_corners < 0):
        raise ValueError(f"susan_corners: max_corners must be a whole number >= 0, or None for no limit, got {max_corners}")
    if blur is not None:
        from ejsrl.vision import _susan_scale

        _sigma, f = _susan_scale.blur_scale(gray, blur)
        if f > 1.0 and min(gray.shape) / f < 16 and isinstance(blur, str):  # read from a small image: as far as it goes
            f = max(1.0, min(gray.shape) / 16)
        if f > 1.0 and min(gray.shape) / f < 16:
            raise ValueError(f"susan_corners: a blur of {blur:g} px widens the mask {f:.3g} times, which leaves "
                             f"{max(1, round(gray.shape[1] / f))} x {max(1, round(gray.shape[0] / f))} pixels of this "
                             f"{gray.shape[1]} x {gray.shape[0]} image to search (at least 16 on a side): give the "
                             "camera's real blur, or a larger image")
        if f > 1.0:
            opts = dict(g=g, nms_radius=nms_radius, quality=quality, min_response=min_response, max_corners=max_corners)
            # refined where they were found, brought back, and refined again on the full image in
            # the refinement's window widened by f (a 7 x 7 one sees only the middle of a blurred
            # corner: boards at 1.5 px 0.38 px off, 0.10 so; rendered cubes 0.44 -> 0.27 px)
            pts, resp = _susan_scale.scaled_corners(
                gray, f, lambda small: susan_corners(small, t, subpixel=subpixel, return_response=True, **opts), None,
            )
            if subpixel and len(pts):  # and on the full image, in a window widened as the mask was
                pts = _refine(gray, np.floor(pts + 0.5), _kernels(), w=int(round(_REFINE_W * f)))
            return (pts, resp) if return_response else pts
    H, W = gray.shape
    gthr = 0.5 * len(SUSAN_MASK) if g is None else float(g)
    g100 = gthr * _SCALE
    r = int(nms_radius)
    if H <= 2 * _R + 2 or W <= 2 * _R + 2:
        pts = np.zeros((0, 2))
        return (pts, np.zeros((H, W), np.float32)) if return_response else pts
    floor = float(min_response) * _SCALE
    # keep what reaches the floor: the largest float32 below it is what a response must exceed
    below = np.float32(floor)
    if below >= floor:
        below = np.nextafter(below, np.float32(-np.inf))
    lut = _lut(t)
    mid_slack = floor - _MID_SLACK * _SCALE
    # 1. the pixels that may have a response (n <= g - floor), from a cheap bound over the image
    L_max = _bound_limit(t, g100 - floor + 1.0)
    # the kernels keep responses >= 0 (a floor below 0, or a g the bound cannot use: the NumPy path)
    kernels = _kernels() if L_max is not None and floor >= 0 else None
    if kernels is not None:
        found = _corners_compiled(kernels, gray, float(t), g100, floor, below, mid_slack, lut, L_max, r, whole=return_response)
    else:
        found = _corners_numpy(gray, t, g100, floor, below, mid_slack, lut, L_max, r)
    if found is None:
        pts = np.zeros((0, 2))
        return (pts, np.zeros((H, W), np.float32)) if return_response else pts
    resp, ci = found
    py, px = np.divmod(ci, W)
    strength = resp[py, px] / _SCALE
    if len(strength) and quality > 0:
        strong = strength >= quality * strength.max()
        py, px, strength = py[strong], px[strong], strength[strong]
    order = np.lexsort((py * W + px, -strength))
    pts = np.column_stack([px[order], py[order]]).astype(np.float64)
    if max_corners is not None:
        pts = pts[: int(max_corners)]
    if subpixel and len(pts):
        pts = _refine(gray, pts, kernels)
    return (pts, resp / _SCALE) if return_response else pts


def _threshold(gray: NDArray[np.uint8], t: float | str) -> float:
    """The brightness threshold ``t`` in grey levels: as given (> 0), or ``"auto"``: from the image's
    noise (``_susan_scale.auto_threshold``)."""
    if isinstance(t, str):
        if t != "auto":
            raise ValueError(f"susan_corners: t is a brightness threshold in grey levels (> 0) or 'auto', got {t!r}")
        from ejsrl.vision import _susan_scale

        return _susan_scale.auto_threshold(gray)
    if isinstance(t, (bool, np.bool_)) or not isinstance(t, (int, float, np.integer, np.floating)):
        raise ValueError(f"susan_corners: t is a brightness threshold in grey levels, a number in (0, 255] (25: the paper's), "
                         f"or 'auto', got {t!r}")
    if not 0 < float(t) <= 255:
        raise ValueError(f"susan_corners: t is a brightness threshold in grey levels, in (0, 255] (25: the paper's), "
                         f"or 'auto', got {t}" + (" (above 255 every pixel is as similar as any other: no corner)" if float(t) > 255 else ""))
    return float(t)


def _corners_numpy(gray, t, g100: float, floor: float, below, mid_slack: float, lut, L_max: int | None, r: int):
    """Steps 1-5 of ``susan_corners`` with NumPy and OpenCV: the response map (x100, float32)
    and the corners' flat indices, or None when no pixel has a response."""
    H, W = gray.shape
    b = _R + 1
    if L_max is not None:
        idx = _candidates_by_bound(gray, t, L_max, b, H - b)
    else:  # a geometric threshold so large that the bound cannot tell: the exact pass
        idx = _exact_candidates(gray, t, g100, below)
    if len(idx) == 0:
        return None
    pad = cv2.copyMakeBorder(gray, _R, _R, _R, _R, cv2.BORDER_REPLICATE)
    pf, Wp = pad.ravel(), W + 2 * _R
    # 2-3. each pixel judged on its own: its USAN, the in-between-grey test, the false-positive tests
    k3 = np.ones((3, 3), np.uint8)
    j = _judge(pf, Wp, W, lut, float(t), g100, floor, below, mid_slack, lambda where: _coverage_response(gray, g100, where), cv2.erode(gray, k3), cv2.dilate(gray, k3), idx)
    idx = j.idx
    # X-junctions (saddles: the corner of a checkerboard) have an in-between centre pixel with a
    # small USAN of its own, its brighter and darker neighbours in opposite quadrants
    # (and, being half dark and half bright, no corner by the side it belongs to)
    wf = np.flatnonzero(j.flat)
    own_mid = np.zeros((H, W), np.float32)
    own_mid.ravel()[idx[wf]] = j.rv[wf]
    ws = wf[j.rv[wf] >= cv2.dilate(own_mid, k3).ravel().take(idx[wf])]
    base = idx[ws] + (idx[ws] // W) * (2 * _R) + (_R * Wp + _R)
    vals = pf.take(base[:, None] + (SUSAN_MASK[:, 1] * Wp + SUSAN_MASK[:, 0])[None, :])
    c8 = cv2.LUT(cv2.absdiff(vals, np.repeat(vals[:, _NUCLEUS : _NUCLEUS + 1], len(SUSAN_MASK), axis=1)), lut) if len(ws) else vals
    ws = ws[_smooth_test(pf, Wp, base, vals, c8, lut, return_saddle=True)[2]]
    # 4. a pixel that fails is dropped where it is the largest in its window, as a maximum that
    # fails is; where a larger pixel that stays is in its window, it stays too (hidden under
    # that maximum, not a corner) and still suppresses the weaker pixels around it. Which
    # stay is found from the passing pixels down, through the windows of those just found
    resp = np.zeros((H, W), np.float32)
    rf = resp.ravel()
    wt = np.flatnonzero(~j.flat)
    rf[idx[ws]] = j.rv[ws]
    rf[idx[wt]] = j.value[wt]
    ok = j.ok[wt]
    passing = np.concatenate([idx[ws], idx[wt[ok]]])
    _hidden_failures(resp, r, passing, idx[wt[~ok]], j.value[wt[~ok]])
    # 5. the corners: the passing pixels that are maxima in their window
    ci = passing[rf[passing] >= _window_max(resp, r, passing)] if len(passing) else passing
    cy, cx = np.divmod(ci, W)
    keep = _local_max(resp, r, cy, cx)
    return resp, ci[keep]


def _corners_compiled(kernels: ModuleType, gray, t: float, g100: float, floor: float, below, mid_slack: float, lut, L_max: int, r: int, whole: bool = True):
    """``_corners_numpy`` with numba's kernels (``_susan_numba``): the same steps, arithmetic and
    result (``_refine`` follows in ``susan_corners`` for both).

    1. ``candidates``: the pixels with a response, their USAN's moments and 3x3 range, beside
       ``_share_image`` (the side shares of the in-between pixels' estimate);
    2. ``judge``: each of them judged on its own (the side estimate, the tests, the side's
       coverage test), writing its value, pass and flatness in place;
    3. ``saddles`` among the flat ones (``judge`` wrote their own response into the map), then
       ``settle`` writes every candidate's value into the map (negated where it failed);
    4. the hidden failures put back (``put_back``, from one dilation) and the window maxima; or,
       without ``whole`` (the response map is not returned), ``lazy_maxima``: the same maxima,
       deciding only the failing pixels that could hide one (grass: 14 of its 59 thousand
       failing pixels; 3.4 ms became 2.4 on one thread).

    On two threads (``_shared``, ``_two``) each step runs on parts of its pixels (bands of
    rows, ranges of candidates) side by side: the same arithmetic on each pixel, the results
    joined in order, so the same output (``lazy_maxima``'s two halves each in their own copy
    of the map).
    """
    H, W = gray.shape
    T, m, _ = _ramp_bound(float(t))
    gray = np.ascontiguousarray(gray)
    buf = _buffers(H, W)
    split = H * W >= _MIN_SPLIT and susan_threads() > 1
    args = (gray, lut, _MDX, _MDY, T, m, L_max, g100, below)
    if split:  # bands of rows (their pixels in raster order, one after the other) and the side shares
        ys = [H * i // _BANDS for i in range(_BANDS + 1)]
        tasks = [functools.partial(_search, kernels, args, ys[i], ys[i + 1]) for i in range(_BANDS)]
        *bands, share = _shared(tasks + [functools.partial(_share_image, gray, kernels, buf)])
        idx, rv, v0, lo3, hi3, mom = (np.concatenate(part) for part in zip(*bands))
    else:
        idx, rv, v0, lo3, hi3, mom = _search(kernels, args, 0, H)
        share = _share_image(gray, kernels, buf)
    K = len(idx)
    if K == 0:
        return None
    given = not _COMPILED.disc_sums_match  # a numba whose float32 sums are not filter2D's: the estimate from OpenCV
    r_dark = _side_estimate(gray, g100, idx, v0, lo3, hi3, t, share) if given else np.zeros(0, np.float32)
    consts = np.array([0.5 * t, g100, floor, _CHORD * _SCALE, _CONTIG, _FULL, g100, mid_slack, _SCALE, given, _SIDE_CONTIG], np.float64)
    value, ok, flat = np.empty(K, np.float32), np.empty(K, bool), np.empty(K, bool)
    resp = buf.resp
    resp.fill(0.0)
    judged = functools.partial(kernels.judge, gray, share, lut, _share_table(), idx, rv, v0, lo3, hi3, mom, r_dark)
    if split:
        cuts = [K * i // _BANDS for i in range(_BANDS + 1)]
        _shared([functools.partial(judged, cuts[i], cuts[i + 1], consts, value, ok, flat, resp) for i in range(_BANDS)])
    else:
        judged(0, K, consts, value, ok, flat, resp)
    # the saddles among the flat pixels, then the map of every candidate's value: on two halves of the rows
    half, two = K // 2, split and K >= 4096
    ws = np.concatenate(_two(two, kernels.saddles, *[(gray, lut, idx, rv, mom, flat, resp, a, b, _CONTIG, _SADDLE_AREA, _FULL) for a, b in ((0, half), (half, K))]))
    _two(two, kernels.settle, (resp, idx, value, ok, flat, 0, half), (resp, idx, value, ok, flat, half, K))
    resp.ravel()[idx[ws]] = rv[ws]
    if not whole:  # only the failing pixels that could hide a corner are decided (the response map is left half-done)
        keep = np.empty(K, bool)

        def maxima(a: int, b: int, fmap: NDArray[np.float32]) -> None:
            depth = 256
            while not kernels.lazy_maxima(fmap, r, idx, a, b, np.empty((4, depth), np.int64), np.empty(depth * 16, np.int64), keep):
                depth *= 4  # (chains this long are rare: the first call's decisions hold, the next one goes on from them)

        # the candidates (the passing pixels among them) in two halves, about the top and bottom of
        # the image, side by side, each deciding what it needs in its own copy of the map (neither
        # reads what the other writes: the same maxima, whatever the timing; 0.1 ms to copy)
        other = resp
        if two:
            other = buf.grown
            np.copyto(other, resp)
        _two(two, maxima, (0, half, resp), (half, K, other))
        return resp, idx[keep]
    passing, failing, fv = kernels.assemble(idx, value, ok, flat, ws)
    # the failing pixels under a larger passing one stay for certain (one dilation of the passing pixels, as in _hidden_failures)
    seed = cv2.dilate(resp, np.ones((2 * r + 1, 2 * r + 1), np.uint8), dst=buf.grown).ravel().take(failing) > fv
    kernels.put_back(resp, r, failing, fv, seed)
    return resp, passing[kernels.window_maxima(resp, r, passing)]


def _search(kernels: ModuleType, args: tuple, y0: int, y1: int) -> tuple[NDArray, ...]:
    """``kernels.candidates`` on the rows ``y0 .. y1 - 1``, with room for every pixel of them: the
    candidates' flat indices, responses, grey levels, 3x3 minima and maxima, and moments."""
    W = args[0].shape[1]
    n = max(min(y1, args[0].shape[0] - _R - 1) - max(y0, _R + 1), 0) * (W - 2 * _R - 2)
    out = (np.empty(n, np.int64), np.empty(n, np.float32), np.empty(n, np.uint8), np.empty(n, np.uint8), np.empty(n, np.uint8), np.empty((n, 3), np.int32))
    K = kernels.candidates(*args, y0, y1, *out)
    return tuple(a[:K] for a in out)


def _side_estimate(gray, g100: float, idx, v0, lo3, hi3, t: float, share) -> NDArray[np.float32]:
    """(K,) float32: ``_coverage_response`` (OpenCV's ``filter2D``) at the in-between pixels, 0 elsewhere."""
    v16 = v0.astype(np.int16)
    mid = (v16 - lo3 > 0.5 * t) & (hi3 - v16 > 0.5 * t)
    r_dark = np.zeros(len(idx), np.float32)
    if mid.any():
        r_dark[mid] = _coverage_response(gray, g100, idx[mid], share)
    return r_dark


_MDX = np.ascontiguousarray(SUSAN_MASK[:, 0])
_MDY = np.ascontiguousarray(SUSAN_MASK[:, 1])
_CONTIG = 2.9 * _SCALE  # the contiguity test: the three pixels towards the centroid sum to more
# the same for an in-between pixel judged as its side, its pixels counting by their shares: noise
# widens the 3x3 range the shares are taken from, so a pixel well inside the side counts about 0.9
# (2.9 missed a quarter of the 120-150 degree vertices of small, faint polygons in noise 4;
# bench/susan_recall.py: 0.77 -> 0.94 of them, all vertices 0.93 -> 0.98, precision 0.997 -> 0.97)
_SIDE_CONTIG = 2.8 * _SCALE
_SADDLE_AREA = 0.35 * _SCALE * len(SUSAN_MASK)  # the saddle test: the unlike pixels cover more
_FULL = float(_SCALE * len(SUSAN_MASK))  # the mask's area, x100


@functools.lru_cache(maxsize=1)
def _share_table() -> NDArray[np.uint32]:
    """(2, 256, 256) uint32: ``[dark, span, x]``, the coverage test's share (x100) of a pixel ``x``
    grey levels above the low one (clipped to ``span``), for the bright side and the dark one
    (the float32 operations of ``_coverage_test``'s ``side``), times 2^25: exact integers, as
    the shares are 0 or in [0.25, 100], multiples of 2^-25 (at most 100 * 2^25 < 2^32)."""
    span = np.maximum(np.arange(256), 1).astype(np.uint8)[:, None]
    x = np.minimum(np.arange(256)[None, :], span).astype(np.uint8)
    share = np.divide(x, span.astype(np.float32), dtype=np.float32)
    dark = np.subtract(np.float32(1.0), share)
    table = (np.stack([share, dark]) * np.float32(_SCALE)).astype(np.float64) * 2.0**25
    fixed = table.astype(np.uint32)
    assert (fixed == table).all()
    return fixed


class _Judged(NamedTuple):
    """The pixels with a response, each judged on its own (``_judge``), one row each."""

    idx: NDArray  # flat image indices, raster order
    rv: NDArray  # float32: their own response g - n (x100)
    flat: NDArray  # bool: an in-between grey that is no corner by the side it belongs to (a saddle, at most)
    value: NDArray  # float32: the response after the tests (their own, or as the side they belong to)
    ok: NDArray  # bool: passed the tests (False where flat)


def _exact_candidates(gray: NDArray[np.uint8], t: float, g100: float, below: np.float32) -> NDArray[np.int64]:
    """Flat indices of the pixels (at least ``_R + 1`` from the border) whose response exceeds ``below``, from the exact whole-image USAN."""
    some = (np.float32(g100) - _usan(gray, t)[0].astype(np.float32)) > below
    _clear_border(some, _R + 1)
    return np.flatnonzero(some)


def _judge(pf, Wp: int, W: int, lut, t: float, g100: float, floor: float, below, mid_slack: float, cover, lo3img: NDArray, hi3img: NDArray, idx: NDArray) -> _Judged:
    """Judge the candidate pixels ``idx`` (flat image indices) each on its own: their exact USAN
    from their 37 mask pixels (gathered once for every test), and those with a response
    through the in-between-grey test and the false-positive tests.

    ``pf``/``Wp``: the padded image, flat, and its width; ``cover(idx)``: ``_coverage_response``;
    ``lo3img``/``hi3img``: the image's 3x3 minimum and maximum.
    """
    base = idx + (idx // W) * (2 * _R) + (_R * Wp + _R)  # flat indices in the padded image
    vals = pf.take(base[:, None] + (SUSAN_MASK[:, 1] * Wp + SUSAN_MASK[:, 0])[None, :])
    v0 = vals[:, _NUCLEUS]
    c8 = cv2.LUT(cv2.absdiff(vals, np.repeat(v0[:, None], len(SUSAN_MASK), axis=1)), lut)
    n = cv2.reduce(c8, 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel()
    rv = np.float32(g100) - n.astype(np.float32)  # g - n, x100
    kk = np.flatnonzero(rv > below)  # the rows with a response (vals, c8 and base keep all, unread elsewhere)
    idx, v0, rv = idx[kk], v0[kk], rv[kk]
    K = len(idx)
    # pixels with an in-between grey (inside an anti-aliased or blurred edge) have a tiny USAN of
    # their own that means nothing: they are judged as the side they belong to would be. Those
    # that cannot be a corner that way (a straight edge: the estimate of _coverage_response)
    # are dropped at once (only a saddle may be among them); the others are judged below
    lo3, hi3 = lo3img.ravel().take(idx), hi3img.ravel().take(idx)
    v16 = v0.astype(np.int16)
    half_t = 0.5 * t
    mid = (v16 - lo3 > half_t) & (hi3 - v16 > half_t)
    r_dark = np.zeros(K, np.float32)
    if mid.any():
        r_dark[mid] = cover(idx[mid])
    flat = mid & (np.abs(r_dark) < mid_slack)
    # every other pixel with a response is tested at once (as Smith and Brady test every pixel
    # before the suppression); those that fail are removed, or, inside an anti-aliased edge,
    # judged again as the side they belong to
    wt = np.flatnonzero(~flat)
    value = rv.copy()
    ok = np.zeros(K, bool)
    ok[wt] = _smooth_test(pf, Wp, base, vals, c8, lut, kk[wt])[0]
    sel = np.flatnonzero(mid & ~flat & ~ok)
    if len(sel):
        got, r_mid = _judge_mid(pf, Wp, base[kk[sel]], vals[kk[sel]], lo3[sel], hi3[sel], v0[sel], r_dark[sel], g100, floor)
        value[sel[got]] = r_mid[got].astype(np.float32)
        ok[sel[got]] = True
    return _Judged(idx, rv, flat, value, ok)


def _judge_mid(pf, Wp: int, base: NDArray, vals: NDArray, lo: NDArray, hi: NDArray, v: NDArray, r_dark: NDArray, g100: float, floor: float):
    """In-between pixels that failed the tests on their own, judged as the side they belong to:
    which are corners that way (bool) and their response (x100, float64)."""
    dark = r_dark > 0
    return _mid_response(*_coverage_test(pf, Wp, base, vals, lo, hi, dark), dark, lo, hi, v, g100, floor)


def _mid_response(ok_m: NDArray, n_m: NDArray, dark: NDArray, lo: NDArray, hi: NDArray, v: NDArray, g100: float, floor: float):
    """``_judge_mid``'s answer from the coverage test's result (which pass, and their USAN as the side)."""
    # judged as the side that falls short of its share (the sign of the estimate): a
    # straight edge cutting the nucleus pixel so that a share a of it lies on one side
    # leaves about g + 6.8 (a - 1/2) of the mask on that side (the disc's chord is 6.8
    # pixels long); only what falls short of that is a corner
    a_dark = (hi.astype(np.float64) - v) / np.maximum(hi.astype(np.float64) - lo, 1.0)
    a_side = np.where(dark, a_dark, 1.0 - a_dark)
    r_mid = np.where(ok_m, g100 + _CHORD * _SCALE * (a_side - 0.5) - n_m, 0.0)
    got = r_mid >= floor
    got &= r_mid > 0
    return got, r_mid


def _coverage_response(gray: NDArray[np.uint8], g100: float, idx: NDArray[np.int64], share: NDArray[np.float32] | None = None) -> NDArray[np.float32]:
    """The corner response (x100) of the pixels at flat indices ``idx`` judged as the dark side
    of their 7x7 neighbourhood (negative: the bright side's, of that size), from the pixels' dark shares.

    ``share = (max7 - I) / (max7 - min7)`` (the part of the pixel covered by the darker region,
    for two grey levels and an anti-aliased edge); the darker side's USAN of a nucleus is the
    sum of the shares over the mask. A straight edge cutting the nucleus pixel so that a share
    a of it is dark leaves about ``g + 6.8 (a - 1/2)`` of the mask dark (the mask's chord is
    6.8 pixels long); the response is what the side falls short of that, on the side that
    falls short (the other side then has more than its share).

    Whole-image OpenCV operations in float32 (``max7 - I`` saturates at 0: a share below 0 is
    clipped to 0 anyway); the same shares as NumPy's float32 arithmetic, bit for bit
    (``_susan_numba.judge`` computes the same float32 sums and operations). ``share``:
    ``_share_image``'s, computed already.
    """
    if share is None:
        share = _share_image(gray, None)
    n_dark = cv2.filter2D(share, cv2.CV_32F, _DISC, borderType=cv2.BORDER_REPLICATE).ravel().take(idx)
    own = share.ravel().take(idx)
    return (np.float32(g100) + np.float32(_CHORD * _SCALE) * (own - np.float32(0.5))) - np.float32(_SCALE) * n_dark


def _share_image(gray: NDArray[np.uint8], kernels: ModuleType | None, buf: _Buffers | None = None) -> NDArray[np.float32]:
    """(H, W) float32: each pixel's dark share ``(max7 - I) / (max7 - min7)`` (``_coverage_response``);
    in ``buf``'s arrays when given."""
    k7 = np.ones((7, 7), np.uint8)
    levels = cv2.medianBlur(gray, 3, dst=None if buf is None else buf.levels)  # the two grey levels, without the noise's extremes
    lo = cv2.erode(levels, k7, dst=None if buf is None else buf.lo)
    hi = cv2.dilate(levels, k7, dst=None if buf is None else buf.hi)
    if kernels is not None:  # the same shares: a float32 division of the same integers (OpenCV's is slow here)
        share = kernels.share_image(gray, lo, hi, np.empty(gray.shape, np.float32) if buf is None else buf.share, 0, gray.shape[0])
    else:
        share = cv2.divide(cv2.subtract(hi, gray), cv2.max(cv2.subtract(hi, lo), 1.0), dtype=cv2.CV_32F)
        cv2.threshold(share, 1.0, 0.0, cv2.THRESH_TRUNC, dst=share)
    return share


class _Buffers(NamedTuple):
    """The whole-image arrays of one ``_corners_compiled`` call (``_buffers``)."""

    levels: NDArray[np.uint8]
    lo: NDArray[np.uint8]
    hi: NDArray[np.uint8]
    share: NDArray[np.float32]
    resp: NDArray[np.float32]
    grown: NDArray[np.float32]


_KEPT = threading.local()
_KEEP_MAX = 1 << 21  # pixels: the buffers of larger images are not kept between calls


def _buffers(H: int, W: int) -> _Buffers:
    """The calling thread's whole-image arrays for an (H, W) image, kept between its calls.

    Fresh arrays of this size are fresh pages from the system on every call (glibc maps
    large blocks and returns them when freed), and the first write to each page faults: on
    this 2-core VM that cost about 1.5 ms of a 640x480 call's 7, and more or less from one
    call to the next as the allocator's thresholds moved. The calling thread's own (not the
    pool thread's: two callers may share it), so concurrent calls never share one.
    """
    kept = getattr(_KEPT, "buffers", None)
    if kept is not None and kept.share.shape == (H, W):
        return kept
    u8 = lambda: np.empty((H, W), np.uint8)  # noqa: E731
    f32 = lambda: np.empty((H, W), np.float32)  # noqa: E731
    buf = _Buffers(u8(), u8(), u8(), f32(), f32(), f32())
    if H * W <= _KEEP_MAX:
        _KEPT.buffers = buf
    return buf


_DISC = np.zeros((2 * _R + 1, 2 * _R + 1), np.float32)  # the mask as a filter
_DISC[SUSAN_MASK[:, 1] + _R, SUSAN_MASK[:, 0] + _R] = 1.0


def _disc_sums_match(kernels: ModuleType) -> bool:
    """Whether the kernels' float32 sums over the mask are OpenCV's ``filter2D``'s, bit for bit, on
    random shares (OpenCV adds the taps in raster order from 0; a build that sums otherwise
    keeps the filter, so both paths stay identical)."""
    rng = np.random.default_rng(0)
    share = np.minimum(rng.integers(0, 256, (64, 80)) / rng.integers(1, 256, (64, 80)), 1.0).astype(np.float32)
    idx = (np.arange(3, 61)[:, None] * 80 + np.arange(3, 77)[None, :]).ravel()
    ref = cv2.filter2D(share, cv2.CV_32F, _DISC, borderType=cv2.BORDER_REPLICATE).ravel().take(idx)
    return bool(np.array_equal(ref.view(np.uint32), kernels.disc_sums(share, idx).view(np.uint32)))


_REFINE_W = 3  # the refinement's window: 7x7 pixels around the estimate
_REFINE_MOVES = 4  # at most this many moves of the window (measured: none of the photographs' corners takes more)
_REFINE_D = np.arange(-_REFINE_W, _REFINE_W + 1)
#: the window's weights, as cornerSubPix's Gaussian exp(-(dx/w)^2 - (dy/w)^2), in whole 64ths: the
#: sums are integers, exact in any order, so both paths give the same positions to the bit
_REFINE_WQ = np.rint(64 * np.exp(-((_REFINE_D[:, None] / _REFINE_W) ** 2) - (_REFINE_D[None, :] / _REFINE_W) ** 2)).astype(np.int64)


@functools.lru_cache(maxsize=8)
def _refine_weights(w: int) -> NDArray[np.int64]:
    """(2w+1, 2w+1) int64: the refinement window's weights (``_REFINE_WQ`` for w = 3)."""
    d = np.arange(-w, w + 1)
    return np.rint(64 * np.exp(-((d[:, None] / w) ** 2) - (d[None, :] / w) ** 2)).astype(np.int64)


def _refine(gray: NDArray[np.uint8], pts: NDArray[np.float64], kernels: ModuleType | None, w: int = _REFINE_W) -> NDArray[np.float64]:
    """Sub-pixel corners (N, 2) from the whole-pixel corners ``pts`` (N, 2), ``(x, y)``, in windows of
    (2w+1)^2 pixels (w = 3: 7 x 7; a blurred image's search widens it: ``susan_corners(blur=)``).

    Each corner moves to the point that best meets the lines through its window's pixels
    along their edges (Foerstner's corner: the least-squares point ``c`` with ``g . (p - c) = 0``
    for the grey gradient ``g`` at each pixel ``p``, weighted by a Gaussian; the model of
    ``cv2.cornerSubPix``): the true vertex of an anti-aliased L corner, the saddle of an
    X-junction. The 7x7 window then moves to the pixel nearest that point and the point is
    found again, until the window stays (at most ``_REFINE_MOVES`` moves). A corner whose
    point lies more than 3 px from its pixel (no corner there: a straight edge, a texture)
    keeps its pixel.

    ``cornerSubPix`` resamples its window at the sub-pixel point on every step, and on
    textures takes its 20 steps on half the corners before it gives them up: 3.7 us a corner.
    Whole-pixel windows need no resampling, their gradients are exact integer differences
    (of neighbours, as cornerSubPix's), and they stop moving after one or two steps:
    about 0.2 us. Tests: vertices of polygons and X-junctions to a fifth of a pixel, as
    ``cornerSubPix`` (tests/vision/test_susan_accuracy.py).
    """
    out = np.empty_like(pts)
    wq = _REFINE_WQ if w == _REFINE_W else _refine_weights(int(w))
    if kernels is not None:
        h = len(pts) // 2
        halves = [(gray, part, wq, _REFINE_MOVES, into) for part, into in ((pts[:h], out[:h]), (pts[h:], out[h:]))]
        _two(h >= 256 and susan_threads() > 1, kernels.refine, *halves)  # each corner on its own: the same either way
        return out
    H, W = gray.shape
    d = np.arange(-w, w + 1)
    f = gray.ravel().astype(np.int32)  # int32 products (at most 64 * 255^2 * w), int64 sums
    offs = (d[:, None] * W + d[None, :]).ravel()
    m = wq.ravel().astype(np.int32)
    dx, dy = np.tile(d, 2 * w + 1).astype(np.int32), np.repeat(d, 2 * w + 1).astype(np.int32)
    x0, y0 = pts[:, 0].astype(np.int64), pts[:, 1].astype(np.int64)
    cx, cy = x0.copy(), y0.copy()
    out[:] = pts
    live = np.arange(len(pts))
    for _ in range(_REFINE_MOVES + 1):
        x, y = cx[live], cy[live]
        live = live[(x >= w + 1) & (y >= w + 1) & (x <= W - w - 2) & (y <= H - w - 2)]
        p = (cy[live] * W + cx[live])[:, None] + offs[None, :]
        gx, gy = f[p + 1] - f[p - 1], f[p + W] - f[p - W]
        xx, xy, yy = m * gx * gx, m * gx * gy, m * gy * gy
        a, b, c = xx.sum(axis=1, dtype=np.int64), xy.sum(axis=1, dtype=np.int64), yy.sum(axis=1, dtype=np.int64)
        bx, by = (xx * dx + xy * dy).sum(axis=1, dtype=np.int64), (xy * dx + yy * dy).sum(axis=1, dtype=np.int64)
        det = a * c - b * b
        ok = det > 0
        live, a, b, c, bx, by, det = live[ok], a[ok], b[ok], c[ok], bx[ok], by[ok], det[ok]
        out[live, 0] = cx[live] + (c * bx - b * by).astype(np.float64) / det.astype(np.float64)
        out[live, 1] = cy[live] + (a * by - b * bx).astype(np.float64) / det.astype(np.float64)
        nx, ny = np.floor(out[live, 0] + 0.5).astype(np.int64), np.floor(out[live, 1] + 0.5).astype(np.int64)
        moved = (nx != cx[live]) | (ny != cy[live])
        cx[live], cy[live] = nx, ny
        live = live[moved]
        if len(live) == 0:
            break
    far = (out[:, 0] - x0) ** 2 + (out[:, 1] - y0) ** 2 > 9.0
    out[far] = pts[far]
    return out


@image_function
def susan_edges(
    img: NDArray,
    t: float = 20.0,
    *,
    g: float | None = None,
    return_response: bool = False,
) -> tuple[NDArray[np.uint8], NDArray[np.float64]] | tuple[NDArray[np.uint8], NDArray[np.float64], NDArray[np.float32]]:
    """SUSAN edge detector (Smith and Brady 1997) with non-maximum suppression across the edge.

    ``img``: grey or RGB uint8; ``t``: brightness threshold; ``g``: geometric threshold in
    mask pixels (default three quarters of the mask, 27.75). The edge normal comes from the
    USAN centroid where the USAN is large and off-centre (an edge between pixels), and from
    the USAN's second moments otherwise (an edge through the nucleus); a pixel is kept when
    its response is a maximum along that normal.

    Returns ``edges`` (H, W) uint8 (255 on edges) and the edge points (N, 2) ``(x, y)`` in
    raster order; with ``return_response`` also the response (H, W) float32.
    """
    gray = as_gray(img)
    H, W = gray.shape
    gthr = 0.75 * len(SUSAN_MASK) if g is None else float(g)
    g100 = gthr * _SCALE
    ys, xs, c, n, pad, lut = _candidates(gray, t, g100)
    resp = np.zeros((H, W), np.float32)
    resp[ys, xs] = ((g100 - n) / _SCALE).astype(np.float32)
    edges = np.zeros((H, W), np.uint8)
    if len(ys):
        dx, dy = SUSAN_MASK[:, 0].astype(np.float64), SUSAN_MASK[:, 1].astype(np.float64)
        sx, sy = c @ dx, c @ dy
        mxx, myy, mxy = c @ (dx * dx), c @ (dy * dy), c @ (dx * dy)
        inter = (n > 6 * _SCALE) & (sx * sx + sy * sy > n * n)  # centroid more than 1 px away
        theta_normal = np.where(
            inter,
            np.arctan2(sy, sx),
            0.5 * np.arctan2(2 * mxy, mxx - myy) + np.pi / 2,  # the USAN's minor axis
        )
        # quantise the normal to 0, 45, 90, 135 degrees and compare with both neighbours
        q = np.mod(np.rint(theta_normal / (np.pi / 4)).astype(np.int64), 4)
        steps = np.array([[1, 0], [1, 1], [0, 1], [-1, 1]])
        ox, oy = steps[q, 0], steps[q, 1]
        r0 = resp[ys, xs]
        r_plus = resp[np.clip(ys + oy, 0, H - 1), np.clip(xs + ox, 0, W - 1)]
        r_minus = resp[np.clip(ys - oy, 0, H - 1), np.clip(xs - ox, 0, W - 1)]
        keep = (r0 > r_plus) & (r0 >= r_minus)
        edges[ys[keep], xs[keep]] = 255
    ey, ex = np.nonzero(edges)
    pts = np.column_stack([ex, ey]).astype(np.float64)
    if return_response:
        return edges, pts, resp
    return edges, pts


@image_function
def susan(img: NDArray, t: float = 20.0, *, kind: str = "corners", **options):
    """SUSAN in one call: ``kind="corners"`` -> ``susan_corners``; ``kind="edges"`` -> ``susan_edges``.

    ``t``: brightness threshold; other options go to the chosen detector.
    """
    if choice(kind, ("corners", "edges"), "SUSAN kind") == "corners":
        return susan_corners(img, t, **options)
    return susan_edges(img, t, **options)
