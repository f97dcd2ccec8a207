"""Labs as web pages (``ejsgen build --web``, issue #32): what a first visit downloads, how
long the page takes to a usable panel cold and warm, where that time goes (the start's phases,
as the page marks them), and the cost of a model step in the browser's Python against native
CPython, side by side.

    python bench/web.py [--lab pendulum paper/six_axis_kinematics paper/path_planning_434] [--rounds 3] [--steps 2000]

Builds each example with ``--web``, serves it with ``python -m http.server`` on 127.0.0.1 and
opens it in headless Chromium (Debian's, the tests' flags). Each round makes a cold visit (the
browser's cache, the page's Cache Storage and its service worker emptied) then a warm one (a
second visit), so cold and warm runs interleave; the phase table gives each phase's median
moment in ms from the page's navigation. Step costs are measured in interleaved rounds
(browser, native, browser, ...), wall time in the browser (the WASI shim has no CPU clock) and
both wall and CPU time natively; ``uptime`` is printed beside each figure.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))  # testkit.web_page: a visit timed and weighed, as the page tests do
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def uptime() -> str:
    return "load " + " ".join(f"{x:.1f}" for x in os.getloadavg())


@contextlib.contextmanager
def serve(folder: Path):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = subprocess.Popen([sys.executable, "-m", "http.server", str(port), "--bind", "127.0.0.1", "-d", str(folder)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        time.sleep(1.0)
        yield f"http://127.0.0.1:{port}/"
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def native_model(app_dir: Path):
    spec = importlib.util.spec_from_file_location("bench_web_app", app_dir / "app.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["bench_web_app"] = module
    spec.loader.exec_module(module)
    from ejsrl.app import App

    return App(module.Model, module.VIEW, meta=module.META, base_dir=app_dir).model  # the lab's assets beside app.py


#: the start's phases (ejsWeb.marks, ms from navigation) in the order they happen, with what each is
PHASES = [
    ("responseEnd", "index.html received"),
    ("clientAsked", "viser's client evaluated (asks for its websocket)"),
    ("serviceWorker", "sw.js controls the page"),
    ("manifest", "manifest.json"),
    ("wasmFetched", "python.wasm downloaded and inflated (cold)"),
    ("wasmLoaded", "python.wasm in Cache Storage"),
    ("wasmCompiled", "python.wasm compiled (warm: from the code cache)"),
    ("instantiated", "instantiated"),
    ("pythonStarted", "Python started"),
    ("numpyImported", "NumPy imported"),
    ("runtimeImported", "ejsrl.web.lab (runtime, viser) imported"),
    ("appImported", "the lab's app.py imported"),
    ("labOpened", "the lab made (App, ViserServer)"),
    ("firstBatch", "first batch of viser messages to the client"),
    ("panelDrawn", "the lab's panel in the page"),
    ("usable", "Play visible to playwright (the main thread free)"),
]


def median(xs: list[float]) -> float:
    xs = sorted(xs)
    return xs[len(xs) // 2] if xs else float("nan")


def wire_bytes(response) -> int:
    """Bytes of ``response`` over the wire: none when sw.js served it (from Cache Storage)."""
    if response.from_service_worker:
        return 0
    sizes = response.request.sizes()
    return (0 if response.request.method == "HEAD" else sizes["responseBodySize"]) + sizes["responseHeadersSize"]


def start_times(page, url: str, rounds: int) -> dict[str, list[dict[str, float]]]:
    """``rounds`` of a cold then a warm visit; each visit's marks, with ``usable`` and ``wire``
    (bytes over the wire: python.wasm served by sw.js is not counted)."""
    from testkit.web_page import visit

    out: dict[str, list[dict[str, float]]] = {"cold": [], "warm": []}
    for r in range(rounds):
        for kind in ("cold", "warm"):
            page.goto("about:blank")
            responses: list = []

            def seen(response, responses=responses) -> None:
                responses.append(response)

            page.on("response", seen)
            took, _received = visit(page, url, cold=kind == "cold", timeout_ms=180_000)
            page.remove_listener("response", seen)
            marks = page.evaluate("ejsWeb.marks")
            nav = page.evaluate("performance.getEntriesByType('navigation')[0].responseEnd")
            marks.update(responseEnd=nav, usable=took * 1000)
            marks["wire"] = sum(wire_bytes(r) for r in responses)
            marks["software"] = bool(page.evaluate("ejsWeb.software"))
            out[kind].append(marks)
            print(f"  round {r + 1} {kind}: usable {took:5.2f} s, {marks['wire'] / 1e6:6.2f} MB over the wire "
                  f"({uptime()})", flush=True)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--lab", nargs="+", default=["pendulum", "paper/six_axis_kinematics", "paper/path_planning_434"],
                    help="examples under examples/ (default: pendulum paper/six_axis_kinematics paper/path_planning_434)")
    ap.add_argument("--steps", type=int, default=2000, help="model steps per measurement")
    ap.add_argument("--rounds", type=int, default=3, help="rounds of a cold and a warm visit, and of step costs")
    args = ap.parse_args()
    from playwright.sync_api import sync_playwright

    from ejsgen._web_build import build_web
    from ejsgen.cli import build

    summary = []
    for lab in args.lab:
        spec = ROOT / "examples" / f"{lab}.ejs.yaml"
        with tempfile.TemporaryDirectory() as tmp:
            t = time.perf_counter()
            site = build_web(spec, Path(tmp) / "site")
            app_dir = build(spec, Path(tmp) / "app")
            print(f"\n== {lab}: built for the web in {time.perf_counter() - t:.1f} s ({uptime()})")
            print(f"{'file':<16} {'on disk MB':>11} {'download MB':>12}")
            for name, (raw, gz) in site.sizes.items():
                print(f"{name:<16} {raw / 1e6:>11.2f} {gz / 1e6:>12.2f}")
            print(f"{'first visit':<16} {'':>11} {site.download_bytes / 1e6:>12.2f}  (page and scripts included)")
            model = native_model(app_dir)
            with serve(site.out) as url, sync_playwright() as pw:
                ctx = pw.chromium.launch_persistent_context(tempfile.mkdtemp(dir=tmp), executable_path="/usr/bin/chromium",
                                                            headless=True, args=ARGS, viewport={"width": 1280, "height": 800})
                page = ctx.new_page()
                runs = start_times(page, url, args.rounds)
                print(f"phases, median of {args.rounds} (ms from navigation)    cold     warm")
                for key, what in PHASES:
                    cold, warm = (median([m[key] for m in runs[k] if key in m]) for k in ("cold", "warm"))
                    print(f"  {what:<52} {cold:>7.0f}  {warm:>7.0f}")
                cold_s, warm_s = (median([m["usable"] for m in runs[k]]) / 1000 for k in ("cold", "warm"))
                wire = median([m["wire"] for m in runs["cold"]]) / 1e6
                soft = runs["cold"][0]["software"]
                print(f"{lab}: usable cold {cold_s:.2f} s, warm {warm_s:.2f} s; first visit {wire:.1f} MB over the wire "
                      f"({'software' if soft else 'GPU'} WebGL; {uptime()})")
                print(f"step cost, {args.steps} steps a round   browser wall | native wall  native CPU | ratio")
                ratios = []
                for r in range(args.rounds):
                    web_s = page.evaluate("(n) => ejsWeb.call('steps', {n})", args.steps)
                    w0, c0 = time.perf_counter(), time.process_time()
                    for _ in range(args.steps):
                        model._ejs_step()
                    nat_wall, nat_cpu = time.perf_counter() - w0, time.process_time() - c0
                    us = 1e6 / args.steps
                    ratios.append(web_s / max(nat_wall, 1e-12))
                    print(f"round {r + 1}: {web_s * us:>8.1f} µs | {nat_wall * us:>8.1f} µs {nat_cpu * us:>8.1f} µs | "
                          f"{ratios[-1]:.2f}x   ({uptime()})")
                summary.append((lab, cold_s, warm_s, wire, median(ratios)))
                ctx.close()
    print(f"\n{'lab':<24} {'cold s':>7} {'warm s':>7} {'first visit MB':>15} {'step vs native':>15}   ({uptime()})")
    for lab, cold_s, warm_s, wire, ratio in summary:
        print(f"{lab:<24} {cold_s:>7.2f} {warm_s:>7.2f} {wire:>15.1f} {ratio:>14.1f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
