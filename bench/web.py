"""A lab as a web page (``ejsgen build --web``, issue #32): what a first visit downloads, how
long the page takes to a usable panel cold and warm, and the cost of a model step in the
browser's Python against native CPython, side by side.

    python bench/web.py [--lab pendulum] [--steps 2000] [--rounds 3]

Builds the example with ``--web``, serves it with ``python -m http.server`` on 127.0.0.1 and
opens it in headless Chromium (Debian's, the tests' flags). Step costs are measured in
interleaved rounds (browser, native, browser, ...), wall time in the browser (the WASI shim
has no CPU clock) and both wall and CPU time natively; ``uptime`` is printed beside each.
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

    return App(module.Model, module.VIEW, meta=module.META).model


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--lab", default="pendulum", help="an example under examples/ (default pendulum)")
    ap.add_argument("--steps", type=int, default=2000, help="model steps per measurement")
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    from playwright.sync_api import sync_playwright

    from ejsgen._web_build import build_web
    from ejsgen.cli import build
    from testkit.web_page import visit

    spec = ROOT / "examples" / f"{args.lab}.ejs.yaml"
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        site = build_web(spec, Path(tmp) / "site")
        app_dir = build(spec, Path(tmp) / "app")
        print(f"built {args.lab} for the web in {time.perf_counter() - t:.1f} s ({uptime()})")
        print(f"{'file':<16} {'on disk MB':>11} {'download MB':>12}")
        for name, (raw, gz) in site.sizes.items():
            print(f"{name:<16} {raw / 1e6:>11.2f} {gz / 1e6:>12.2f}")
        print(f"{'first visit':<16} {'':>11} {site.download_bytes / 1e6:>12.2f}  (page and scripts included)")
        model = native_model(app_dir)
        with serve(site.out) as url, sync_playwright() as pw:
            ctx = pw.chromium.launch_persistent_context(tempfile.mkdtemp(dir=tmp), executable_path="/usr/bin/chromium",
                                                        headless=True, args=ARGS)
            page = ctx.new_page()
            cold, got = visit(page, url, cold=True, timeout_ms=180_000)
            timing = page.evaluate("ejsWeb.timing")
            print(f"cold start {cold:.1f} s to a usable panel, {got / 1e6:.1f} MB over the wire ({uptime()})")
            print("  in the page (ms): " + ", ".join(f"{k} {v:.0f}" for k, v in timing.items()))
            page.goto("about:blank")
            warm, got = visit(page, url, cold=False, timeout_ms=180_000)
            timing = page.evaluate("ejsWeb.timing")
            print(f"warm start {warm:.1f} s, {got / 1e6:.2f} MB over the wire ({uptime()})")
            print("  in the page (ms): " + ", ".join(f"{k} {v:.0f}" for k, v in timing.items()))
            print(f"\nstep cost, {args.steps} steps a round   browser wall | native wall  native CPU | ratio")
            for r in range(args.rounds):
                web_s = page.evaluate("(n) => ejsWeb.call('steps', {n})", args.steps)
                w0, c0 = time.perf_counter(), time.process_time()
                for _ in range(args.steps):
                    model._ejs_step()
                nat_wall, nat_cpu = time.perf_counter() - w0, time.process_time() - c0
                us = 1e6 / args.steps
                print(f"round {r + 1}: {web_s * us:>8.1f} µs | {nat_wall * us:>8.1f} µs {nat_cpu * us:>8.1f} µs | "
                      f"{web_s / max(nat_wall, 1e-12):.2f}x   ({uptime()})")
            ctx.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
