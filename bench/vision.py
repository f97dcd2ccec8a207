"""Benchmark of the vision runtime, measured side by side in one run.

    python bench/vision.py [--repeat N] [--rounds R] [--only susan|camera]

1. SUSAN corners (``susan_corners`` at its defaults) against ``cv2.goodFeaturesToTrack``
   (100 corners, quality 0.01, 5 px apart) on every real photograph scikit-image bundles
   (``PHOTOGRAPHS``) resized to 640x480 grey, on 22 more the bench never tuned on
   (``extra_photographs``: both halves of viser's ten HDRI panoramas, real photographs of
   streets, rooms, a forest, a studio, and scikit-image's microaneurysms and right
   motorcycle image), and on a rendered scene of a few objects (flat,
   mostly empty: the easy case) (target: SUSAN at most 3x its time on the photographs), for
   both SUSAN paths side by side: the NumPy/OpenCV one and numba's compiled kernels (the
   ``[fast]`` extra; same corners; on two threads, as outside a served class:
   ``_susan.susan_threads()``); and numba's asked for the 100 strongest corners, as GFTT is
   (``numba@100``): at its defaults SUSAN returns every corner, thousands on a texture, and
   refines each to sub-pixel.
   They are timed interleaved, call for call, and medians reported, so a shared machine's
   load hits all alike; the whole measurement is repeated in rounds and the rounds' spread of
   each ratio printed; then CPU time with one thread each (SUSAN as a served class runs it:
   the honest figure for a class), median and worst for the 18, the 22 and all 40; and
   numba's compile time (first call in a new process, with an empty and with a warm cache).
   Each table is printed with the load average beside it: the machine may be shared.
   (Testing only the local maxima, then the maxima of failing ones' windows, was measured
   1.1-1.8x slower than the shipped order: its code and bench are in commit 2fa4817.)
2. Virtual-camera rendering, frames per second at 320x240 and 640x480, for a ~200-triangle
   and a ~20,000-triangle scene, with each back end that works here side by side: the
   NumPy rasterizer and, where moderngl and EGL work, OpenGL (target: at least 30
   frames/s at 640x480 for 20,000 triangles with the NumPy rasterizer); then how far the
   two agree, and where the NumPy back end's time goes; then the frame rate with each of
   the realistic camera's options (anti-aliasing, smooth shading, distortion, blur, noise).
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import cv2
import numpy as np
import trimesh

from ejsrl.robotics.transforms import r2t, rotx, roty, rotz, transl
from ejsrl.vision import CameraModel, add_gaussian_noise, look_at, susan_corners, to_gray
from ejsrl.world import World, render
from ejsrl.world.scene import Box, Cylinder, MeshNode, Part, Sphere


def timeit(fn: Callable[[], object], repeat: int) -> tuple[float, float]:
    """(median, best) seconds over ``repeat`` runs after one warm-up."""
    fn()
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts), min(ts)


def small_scene() -> World:
    w = World()
    w.add(Box("floor", size=(3, 3, 0.02), color="gray", T_parent_local=transl(0, 0, -0.01)))
    m = trimesh.creation.icosphere(subdivisions=1, radius=0.2)
    w.add(MeshNode("ball", mesh_parts=(Part(m.vertices, m.faces, (0.9, 0.1, 0.1)),), T_parent_local=transl(-0.2, 0.1, 0.2)))
    for i in range(4):
        w.add(Box(f"crate{i}", size=(0.15, 0.15, 0.15), color="blue", T_parent_local=transl(0.3, -0.3 + 0.2 * i, 0.075) @ r2t(rotz(0.3 * i))))
    w.add(Cylinder("can", radius=0.08, height=0.3, color="green", T_parent_local=transl(0.1, 0.35, 0.15)))
    return w


def big_scene() -> World:
    w = World()
    w.add(Box("floor", size=(3, 3, 0.02), color="gray", T_parent_local=transl(0, 0, -0.01)))
    m = trimesh.creation.icosphere(subdivisions=5, radius=0.45)
    w.add(MeshNode("blob", mesh_parts=(Part(m.vertices, m.faces, (0.2, 0.7, 0.3)),), T_parent_local=transl(0, 0, 0.45)))
    return w


def count_tris(w: World) -> int:
    return len(w.triangles()[0])


def rendered_image() -> np.ndarray:
    """A 640x480 rendered view: a tilted white square and a few objects, with mild noise (mostly flat)."""
    w = World()
    V = np.array([[-0.1, -0.1, 0], [0.1, -0.1, 0], [0.1, 0.1, 0], [-0.1, 0.1, 0]])
    w.add(MeshNode("square", mesh_parts=(Part(V, [[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]], (1, 1, 1)),), T_parent_local=r2t(rotx(0.4) @ roty(-0.3))))
    w.add(Box("crate", size=(0.08, 0.08, 0.08), color="orange", T_parent_local=transl(0.17, 0.12, 0.04)))
    w.add(Sphere("ball", radius=0.05, color="red", T_parent_local=transl(-0.17, -0.12, 0.05)))
    cam = CameraModel(640, 480, fov_deg=50)
    T = r2t(rotx(np.pi), [0.01, 0.0, 0.6])
    rgb, _ = render(w, cam, T, background=(0.15, 0.15, 0.18))
    return add_gaussian_noise(to_gray(rgb), 3.0, seed=0)


#: every real photograph (or scan) scikit-image bundles (the others are drawn, binary or 3D, or
#: need a download; ``cat`` is ``chelsea``); the textures (grass, gravel, page) are SUSAN's worst case
PHOTOGRAPHS = ("camera", "astronaut", "coffee", "chelsea", "brick", "coins", "rocket", "text", "cell", "clock", "grass",
               "gravel", "hubble_deep_field", "immunohistochemistry", "moon", "page", "retina", "stereo_motorcycle")


def photographs() -> dict[str, np.ndarray]:
    """scikit-image's bundled photographs as 640x480 grey (scikit-image is in the bench and test extras)."""
    try:
        from skimage import data
    except ImportError:
        raise SystemExit("bench/vision.py times SUSAN on scikit-image's photographs: python3 -m pip install -e '.[bench]'") from None

    out = {}
    for name in PHOTOGRAPHS:
        im = getattr(data, name)()
        if isinstance(im, tuple):  # the stereo pair: its left image
            im = im[0]
        if im.ndim == 3:
            im = cv2.cvtColor(im, cv2.COLOR_RGB2GRAY)
        out[name.removeprefix("stereo_")] = cv2.resize(im, (640, 480), interpolation=cv2.INTER_AREA)
    return out


def extra_photographs() -> dict[str, np.ndarray]:
    """22 more real photographs as 640x480 grey: the left and right halves (the middle 384 rows
    of each 512-pixel half, 4:3) of viser's ten 1024x512 HDRI panoramas, and scikit-image's
    microaneurysms (a retina) and the right image of its stereo motorcycle."""
    from pathlib import Path

    import viser
    from skimage import data

    out = {}
    for f in sorted((Path(viser.__file__).parent / "_assets" / "hdri").glob("*.jpg")):
        im = cv2.cvtColor(cv2.imread(str(f)), cv2.COLOR_BGR2GRAY)
        h, w = im.shape
        top = (h - (w // 2) * 3 // 4) // 2
        for side, x0 in (("L", 0), ("R", w // 2)):
            crop = im[top : top + (w // 2) * 3 // 4, x0 : x0 + w // 2]
            out[f"{f.stem.removesuffix('_1k')[:14]}.{side}"] = cv2.resize(crop, (640, 480), interpolation=cv2.INTER_CUBIC)
    for name, im in (("microaneurysms", data.microaneurysms()), ("motorcycle_right", data.stereo_motorcycle()[1])):
        if im.ndim == 3:
            im = cv2.cvtColor(im, cv2.COLOR_RGB2GRAY)
        out[name] = cv2.resize(im, (640, 480), interpolation=cv2.INTER_AREA)
    return out


def _summary(label: str, names: list[str], ratios: dict[str, float]) -> str:
    r = [ratios[n] for n in names]
    worst = max(names, key=lambda n: ratios[n])
    over = sum(x > 3 for x in r)
    return f"{label}: median {statistics.median(r):.2f}x, worst {max(r):.2f}x ({worst}), {over} of {len(r)} over 3x"


def busy_threads_after(fn: Callable[[], object]) -> float:
    """CPU time over wall time of a one-thread NumPy loop run right after ``fn``: about 1, unless
    ``fn`` left threads of this process busy (OpenBLAS's spin after a large matrix product)."""
    x = np.random.default_rng(0).random(300_000).astype(np.float32)
    fn()
    c0, w0 = time.process_time(), time.perf_counter()
    for _ in range(30):
        x.sum()
    return (time.process_time() - c0) / (time.perf_counter() - w0)


def interleaved_n(fns: list[Callable[[], object]], repeat: int, clock: Callable[[], float] = time.perf_counter) -> list[float]:
    """Median seconds of each of ``fns``, timed in turn, call for call, after one warm-up each."""
    for f in fns:
        f()
    ts: list[list[float]] = [[] for _ in fns]
    for _ in range(repeat):
        for f, t in zip(fns, ts):
            t0 = clock()
            f()
            t.append(clock() - t0)
    return [statistics.median(t) for t in ts]


def susan_with(path: str, img: np.ndarray):
    """``susan_corners(img)`` on one SUSAN path: "numpy" or "numba" at the defaults (every corner,
    each refined to sub-pixel), or "numba@100": the 100 strongest, as GFTT is asked for here."""
    from ejsrl.vision import _susan

    backend, _, most = path.partition("@")
    kw = {"max_corners": int(most)} if most else {}

    def run():
        _susan.BACKEND = backend
        return susan_corners(img, **kw)

    return run


#: numba's kernels in ``_susan._corners_compiled``, by the stage the profile names them
STAGES = {"candidates": "search", "judge": "judging", "lazy_maxima": "non-maxima", "saddles": "saddles",
          "refine": "refinement", "settle": "response map", "share_image": "side shares"}
STAGES_LEGEND = ("search: the uint8 bound over the image, then the exact USAN and moments of the pixels it leaves; "
                 "judging: each pixel with a response on its own (in-between pixels' side estimate; centroid, contiguity "
                 "and smooth tests; the side tests); non-maxima: deciding the failing pixels that could hide a corner")


def stage_profile(img: np.ndarray, n: int) -> str:
    """Median CPU time per call of each of numba's kernels in ``susan_corners(img)`` on one thread
    (the kernels wrapped in a timer), and of the rest (Python, OpenCV's 3x3 filters, allocations)."""
    import types

    from ejsrl.vision import _susan

    kernels = _susan._kernels()
    calls: dict[str, list[float]] = {}
    found: list[int] = []  # the candidates' kernel returns how many pixels have a response

    class Timed(types.ModuleType):
        def __getattr__(self, name: str):
            fn = getattr(kernels, name)
            if not callable(fn):
                return fn

            def timed(*a, **kw):
                t0 = time.thread_time()
                out = fn(*a, **kw)
                calls.setdefault(name, []).append(time.thread_time() - t0)
                if name == "candidates":
                    found.append(out)
                return out

            return timed

    timed = Timed("timed_kernels")
    saved = _susan._kernels
    _susan._kernels = lambda: timed
    try:
        totals = []
        for _ in range(n + 1):
            calls.clear()
            found.clear()
            t0 = time.thread_time()
            susan_corners(img)
            totals.append((time.thread_time() - t0, {k: sum(v) for k, v in calls.items()}))
    finally:
        _susan._kernels = saved
    totals = totals[1:]  # the first: warm-up
    total = statistics.median(t for t, _ in totals)
    per = {k: statistics.median(d.get(k, 0.0) for _, d in totals) for k in totals[0][1]}
    rest = total - sum(per.values())
    parts = [f"{STAGES.get(k, k)} {v * 1e3:.2f}" for k, v in sorted(per.items(), key=lambda kv: -kv[1])]
    return f"{total * 1e3:.2f} ms for {sum(found):,} pixels with a response: " + ", ".join(parts + [f"the rest {max(rest, 0.0) * 1e3:.2f}"])


def compile_times() -> str:
    """First-call time of the numba kernels in a fresh process: compiled (an empty numba cache)
    and loaded from the cache (numba's import included), and where the cache is."""
    import os
    import subprocess
    import sys
    import tempfile

    code = (
        "import time; t0 = time.perf_counter()\n"
        "from ejsrl.vision import _susan\n"
        "_susan.BACKEND = 'numba'; _susan.susan_backend()\n"
        "print(time.perf_counter() - t0)"
    )
    out = []
    with tempfile.TemporaryDirectory() as d:
        env = {**os.environ, "NUMBA_CACHE_DIR": d}
        for label in ("cold (compile)", "warm (cache)"):
            r = subprocess.run([sys.executable, "-P", "-c", code], capture_output=True, text=True, env=env, timeout=600)
            out.append(f"{label} {float(r.stdout.split()[-1]):.2f} s" if r.returncode == 0 else f"{label} failed: {r.stderr[-200:]}")
    return ", ".join(out)


def keep_freed_memory() -> str:
    """Make glibc keep freed memory for reuse (``mallopt``) instead of mapping large blocks anew on
    every call and returning them when freed: a fresh block's pages fault on their first write,
    which on this VM cost GFTT 6 ms a call instead of 2 at 640x480, depending on what earlier
    calls had left in the allocator (its thresholds move as blocks are freed). With this both
    detectors are timed on warm memory: their computing, not the allocator's luck."""
    import ctypes
    import ctypes.util

    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
        if libc.mallopt(M_MMAP_THRESHOLD, 1 << 28) and libc.mallopt(M_TRIM_THRESHOLD, 1 << 30):
            return "glibc keeps freed memory (mallopt): no call pays page faults for another's frees"
    except (OSError, AttributeError):
        pass
    return "the allocator's defaults (not glibc): times include page faults where it returns memory"


def bench_susan(n: int, rounds: int) -> None:
    import os

    from ejsrl.vision import _susan

    allocator = keep_freed_memory()
    have_numba = _susan.susan_backend(wait=True) == "numba"  # compiles (or loads) numba's kernels first
    paths = ["numpy", "numba", "numba@100"] if have_numba else ["numpy"]
    print("== SUSAN corners (defaults) vs cv2.goodFeaturesToTrack(100, 0.01, 5), 640x480 grey, interleaved medians ==")
    print(f"load average before: {os.getloadavg()[0]:.2f} (the machine may be shared: both detectors see the same load); "
          f"OpenCV threads: {cv2.getNumThreads()} (GFTT uses them); SUSAN's threads: {_susan.susan_threads()} (numba's path outside a served class)")
    print(f"memory: {allocator}")
    if not have_numba:
        print("numba is not installed: only the NumPy path (pip install 'ejsgen[fast]' for the compiled one)")
    print(f"{rounds} rounds, each timing every image {n} times, each SUSAN path and GFTT call for call; per image the median of the rounds' medians, and the rounds' spread of the ratio")
    head = " ".join(f"{p + ' ms':>9s} {'ratio':>6s} {'spread':>11s}" for p in paths)
    print(f"{'image':20s} {'GFTT ms':>8s} {head} {'corners':>8s}")
    base, extra = photographs(), extra_photographs()
    images = {**base, **extra, "rendered": rendered_image()}
    runs: dict[str, list[list[float]]] = {name: [] for name in images}
    for _ in range(rounds):
        for name, img in images.items():
            fns = [susan_with(p, img) for p in paths] + [lambda img=img: cv2.goodFeaturesToTrack(img, 100, 0.01, 5)]
            runs[name].append(interleaved_n(fns, n))
    ratios: dict[str, list[float]] = {p: [] for p in paths}
    for name, img in images.items():
        t_g = statistics.median(r[-1] for r in runs[name])
        cols = []
        for i, p in enumerate(paths):
            r = [x[i] / x[-1] for x in runs[name]]
            if name != "rendered":
                ratios[p].append(statistics.median(r))
            cols.append(f"{statistics.median(x[i] for x in runs[name]) * 1e3:9.2f} {statistics.median(r):6.2f} {min(r):5.2f}-{max(r):<5.2f}")
        print(f"{name:20s} {t_g * 1e3:8.2f} {' '.join(cols)} {len(susan_corners(img)):8d}")
    photo_names = [k for k in images if k != "rendered"]
    print(f"-- two threads, wall time (outside a served class), load average now {os.getloadavg()[0]:.2f}:")
    for p in paths:
        by = dict(zip(photo_names, ratios[p]))
        note = " (as GFTT, the 100 strongest: for comparison)" if "@" in p else ""
        print(f"SUSAN ({p}) / GFTT{note}: " + "; ".join(
            _summary(lab, names, by) for lab, names in (("the 18", list(base)), ("the 22 more", list(extra)), ("all 40", photo_names))))
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    # the same in CPU time with one OpenCV thread: a loaded machine stretches wall-clock times
    # unevenly (SUSAN's many short calls more than one long one), CPU time much less
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    _susan.set_threads(1)  # as a served class runs it
    cpu: dict[str, dict[str, float]] = {p: {} for p in paths}
    load0 = os.getloadavg()[0]
    for name, img in images.items():
        if name != "rendered":
            fns = [susan_with(p, img) for p in paths] + [lambda img=img: cv2.goodFeaturesToTrack(img, 100, 0.01, 5)]
            t = interleaved_n(fns, n, time.process_time)
            for i, p in enumerate(paths):
                cpu[p][name] = t[i] / t[-1]
    profiles = {}
    if have_numba:  # where the time goes on the slowest, stage by stage (still one thread each)
        load_p = os.getloadavg()[0]
        for name in sorted(photo_names, key=lambda k: -cpu["numba"][k])[:3]:
            profiles[name] = stage_profile(images[name], n)
    cv2.setNumThreads(threads)
    _susan.set_threads(None)
    print(f"-- one thread each, CPU time (as in a served class), load average {load0:.2f} before, {os.getloadavg()[0]:.2f} after:")
    for p in paths:
        verdict = "" if "@" in p else f" (target worst <= 3x on all 40: {'met' if max(cpu[p].values()) <= 3 else 'NOT met'})"
        print(f"SUSAN ({p}) / GFTT{verdict}: " + "; ".join(
            _summary(lab, names, cpu[p]) for lab, names in (("the 18", list(base)), ("the 22 more", list(extra)), ("all 40", photo_names))))
    worst = sorted(photo_names, key=lambda k: -cpu[paths[-1] if len(paths) == 1 else "numba"][k])[:6]
    print("   the slowest (one thread): " + ", ".join(f"{k} {cpu['numba' if 'numba' in cpu else 'numpy'][k]:.2f}x" for k in worst))
    if profiles:
        print(f"where numba's time goes, one thread, CPU time, ms per call (load average {load_p:.2f}; {STAGES_LEGEND}):")
        for name, line in profiles.items():
            print(f"   {name}: {line}")
    # a detector that leaves threads spinning (OpenBLAS after a large product) also slows whatever runs
    # next, GFTT in the interleaved timing above included: that would flatter the ratio
    img = images["camera"]
    print("threads left busy: CPU/wall of a one-thread loop right after SUSAN " + ", ".join(f"{p} {busy_threads_after(susan_with(p, img)):.2f}" for p in paths) + " (1.00: none)")
    if have_numba:
        print(f"numba kernels' first call in a new process: {compile_times()}")
    _susan.BACKEND = "auto"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--rounds", type=int, default=3, help="rounds of the interleaved SUSAN timing (the spread between them is reported)")
    ap.add_argument("--only", choices=("susan", "camera"), help="run one part of the benchmark")
    args = ap.parse_args()
    n = args.repeat
    cv2.setNumThreads(cv2.getNumThreads())  # OpenCV's default threading, as apps run it

    import os

    if args.only != "camera":
        bench_susan(n, args.rounds)
    if args.only == "susan":
        return
    print()
    print("== Virtual camera rendering (render(world, CameraModel, T)) ==")

    from ejsrl.world import _gl
    from ejsrl.world.rendering import _pick_backend, available_backends

    backends = available_backends()  # "numpy", and "gl" where moderngl + EGL work
    print(f"load average before: {os.getloadavg()[0]:.2f} (the machine is shared: medians move with load, bests less)")
    print(f"gl back end: {_gl.describe()}")
    scenes = [("small", small_scene()), ("large", big_scene())]
    T = look_at((0.0, -1.6, 1.1), (0.0, 0.0, 0.3))
    print(f"{'scene':8s} {'triangles':>9s} {'resolution':>10s} {'backend':>7s} {'median ms':>10s} {'fps':>7s} {'best fps':>8s}")
    results = {}
    for name, w in scenes:
        for res in [(320, 240), (640, 480)]:
            cam = CameraModel(*res, fov_deg=50)
            for be in backends:
                med, best = timeit(lambda w=w, cam=cam, be=be: render(w, cam, T, backend=be), n)
                results[(name, res, be)] = (med, best)
                print(f"{name:8s} {count_tris(w):9d} {res[0]:>4d}x{res[1]:<5d} {be:>7s} {med * 1e3:10.2f} {1 / med:7.1f} {1 / best:8.1f}")
    for be in backends:
        med, best = results[("large", (640, 480), be)]
        fps = 1 / med
        print(
            f"{be} back end, 20k triangles at 640x480: {fps:.1f} frames/s median, {1 / best:.1f} best "
            f"(target >= 30: {'met' if fps >= 30 else 'NOT met'} on the median)"
        )
    if "gl" in backends:  # the two back ends agree except along edges
        w = scenes[1][1]
        cam = CameraModel(640, 480, fov_deg=50)
        rgb_n, d_n = render(w, cam, T, backend="numpy")
        rgb_g, d_g = render(w, cam, T, backend="gl")
        same = (np.abs(rgb_n.astype(int) - rgb_g).max(axis=2) <= 2).mean()
        both = np.isfinite(d_n) & np.isfinite(d_g)
        rel = np.abs(d_n[both] - d_g[both]) / d_n[both]
        print(f"gl vs numpy (large, 640x480): {100 * same:.2f} % of pixels within 2 levels, depth within 1e-4 relative at {100 * (rel <= 1e-4).mean():.2f} % of pixels")
    print(f"(auto back end picks: {_pick_backend('auto')})")

    # the realistic camera's options (camera props antialias, shading, distortion, blur, noise), large scene, 640x480
    from ejsrl.world.rendering import Realism

    options = {
        "plain": Realism(),
        "antialias 2": Realism(antialias=2),
        "antialias 3": Realism(antialias=3),
        "shading smooth": Realism(shading="smooth"),
        "distortion": Realism(distortion=(-0.2, 0.05, 0.0, 0.0, 0.0)),
        "blur 1.0": Realism(blur=1.0),
        "noise 2.0": Realism(noise=2.0),
        "all of them (aa 2)": Realism(antialias=2, shading="smooth", distortion=(-0.2, 0.05, 0, 0, 0), blur=1.0, noise=2.0),
    }
    w = scenes[1][1]
    cam = CameraModel(640, 480, fov_deg=50)
    print(f"realistic camera, large scene ({count_tris(w)} triangles), 640x480, load average {os.getloadavg()[0]:.2f} "
          "(the machine is shared: frame rates are lower bounds)")
    print(f"{'options':20s} " + " ".join(f"{be + ' fps':>9s} {be + ' best':>9s}" for be in backends))
    for label, r in options.items():
        row = []
        for be in backends:
            render(w, cam, T, backend=be, realism=r)  # warm caches (remap tables, smooth normals)
            med, best = timeit(lambda r=r, be=be: render(w, cam, T, backend=be, realism=r), max(3, n // 3))
            row.append(f"{1 / med:9.1f} {1 / best:9.1f}")
        print(f"{label:20s} " + " ".join(row))

    # where the NumPy back end's time goes, large scene at 640x480
    from ejsrl.world._raster import face_normals, front_faces, zbuffer
    from ejsrl.world.rendering import AMBIENT, _bg_uint8, _shade, _to_camera

    w = scenes[1][1]
    cam = CameraModel(640, 480, fov_deg=50)
    tris, rgb = w.triangles()
    P = _to_camera(tris, T)
    nrm = face_normals(P)
    front = front_faces(P, nrm)
    zb = zbuffer(P, cam.K, 640, 480, near=cam.near, far=cam.far, front=front)
    shaded = _shade(nrm.take(zb.ids, axis=1), rgb[zb.ids], AMBIENT)
    bg = _bg_uint8((0.8, 0.8, 0.8))
    parts = {
        "world.triangles": lambda: w.triangles(),
        "to camera frame": lambda: _to_camera(tris, T),
        "normals + culling": lambda: front_faces(P, face_normals(P)),
        "z-buffer (setup, spans, fragments, z-test)": lambda: zbuffer(P, cam.K, 640, 480, near=cam.near, far=cam.far, front=front),
        "shading of the faces drawn": lambda: _shade(nrm.take(zb.ids, axis=1), rgb[zb.ids], AMBIENT),
        "writing rgb + depth": lambda: (zb.lookup(shaded, bg), zb.depth()),
    }
    print("breakdown (numpy, large, 640x480), best of runs: " + ", ".join(f"{k} {timeit(f, n)[1] * 1e3:.2f} ms" for k, f in parts.items()))


if __name__ == "__main__":
    main()
