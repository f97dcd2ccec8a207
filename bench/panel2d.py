"""Frames per second of the 2D drawing panel in Chromium, with 1,000 elements moving every frame.

    python bench/panel2d.py                 # a lab: 500 particles + a field of 500 arrows, 8 s
    python bench/panel2d.py --engine        # the panel engine alone, fed frames from NumPy
    python bench/panel2d.py --n 2000 --seconds 5

By default a lab is built from a spec (a ``drawing`` with a set of N/2 particles on circles
and a field of N/2 arrows that turn, both moved by an evolution page every step) and served
as ``python app.py`` serves it, a simulation per tab, asking for 60 frames a second. Every
frame then goes the whole way: the step, the panel's expressions, the frame's encoding,
viser, the browser's decoding and drawing. ``--engine`` skips the lab: a server thread
hands frames built from NumPy to :class:`ejsrl.view._panel2d.Panel2D` 60 times a second.
Headless Debian Chromium (``/usr/bin/chromium``) shows it; the page counts the frames its
canvas draws.

Printed: frames per second drawn in the browser (the figure the issue asks >= 30 for),
frames per second sent by the server, and where a frame's time goes: the server's cost to
build and send a frame (ms; with the lab: the frame's step and panel together) and the
browser's to decode and draw one (ms, measured in the page around the draw).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import threading
import time

import numpy as np

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]

#: what the page runs to time the engine's draws: wraps requestAnimationFrame callbacks
_TIMING = """
() => { const E = window.__ejs2d; const id = Object.keys(E.panels)[0];
  const c = E.panels[id].canvas; return {drawn: +c.getAttribute('data-drawn'), t: performance.now()}; }
"""


def frame_at(t: float, n: int) -> dict:
    """A frame of ``n`` elements at time ``t``: n/2 particles on circles, an n/2 field of arrows."""
    from ejsrl.view._panel2d import encode_xy

    k = n // 2
    i = np.arange(k)
    r = 1.0 + 3.0 * (i % 37) / 37.0
    a = t * (0.5 + (i % 11) / 11.0) + i
    particles = np.column_stack([r * np.cos(a), r * np.sin(a)])
    side = int(np.ceil(np.sqrt(n - k)))
    gx, gy = np.meshgrid(np.linspace(-4.5, 4.5, side), np.linspace(-4.5, 4.5, side))
    gx, gy = gx.ravel()[: n - k], gy.ravel()[: n - k]
    ang = t + 0.3 * gx - 0.2 * gy
    arrows = np.column_stack([gx, gy, 0.3 * np.cos(ang), 0.3 * np.sin(ang)])
    return {
        "bounds": [-5, 5, -5, 5], "aspect": "equal", "background": "#ffffff", "title": "", "axes": None, "legend": [],
        "items": [
            {"t": "arrows", "xy": encode_xy(arrows), "stroke": "#1971c2", "width": 1.5, "head": 6},
            {"t": "circles", "xy": encode_xy(particles), "r": 0.06, "fill": "#e03131", "stroke": None, "width": 1},
        ],
    }


LAB = """
ejs: 1
title: Panel bench
model:
  variables:
    t: 0.0
    dt: 0.02
    k: {value: %(k)d}
    P: {expr: "np.zeros((%(k)d, 2))"}
    G: {expr: "np.column_stack([g.ravel() for g in np.meshgrid(np.linspace(-4.5, 4.5, %(side)d), np.linspace(-4.5, 4.5, %(side)d))])[:%(m)d]"}
    V: {expr: "np.zeros((%(m)d, 2))"}
  evolution:
    - code: |
        t = t + dt
        i = np.arange(k)
        r = 1.0 + 3.0*(i %% 37)/37.0
        a = t*(0.5 + (i %% 11)/11.0) + i
        P = np.column_stack([r*np.cos(a), r*np.sin(a)])
        ang = t + 0.3*G[:, 0] - 0.2*G[:, 1]
        V = 0.3*np.column_stack([np.cos(ang), np.sin(ang)])
view:
  - drawing:
      x_range: [-5, 5]
      y_range: [-5, 5]
      height: 420
      children:
        - arrow: {position: G, vector: V, color: "#1971c2", width: 1.5, head: 6}
        - particle: {position: P, radius: 0.06, color: "#e03131"}
simulation: {fps: 60, autoplay: true}
"""


def _served_lab(n: int, tmp: str):
    """The bench lab (n elements) built in ``tmp`` and served a simulation per tab: ``(app, url, stop)``."""
    from pathlib import Path

    from ejsgen.cli import build
    from ejsrl.app import load_app

    k = n // 2
    m = n - k
    side = int(np.ceil(np.sqrt(m)))
    spec = Path(tmp) / "panel_bench.ejs.yaml"
    spec.write_text(LAB % {"k": k, "m": m, "side": side})
    app = load_app(build(spec, Path(tmp) / "app"))
    server = app.serve("127.0.0.1", 0, block=False, per_client=True, max_sessions=2)

    def stop() -> None:
        app.stop()
        server.stop()

    return app, f"http://127.0.0.1:{server.get_port()}", stop


def _served_engine(n: int, rate: float):
    """A bare panel fed ``frame_at`` ``rate`` times a second: ``(panels, build_ms, url, stop)``."""
    from ejsrl.view._panel2d import Panel2D
    from ejsrl.view.viser_view import make_server

    server, url = make_server("127.0.0.1", 0, banner=False)
    done = threading.Event()
    build_ms: list[float] = []
    panels: list[Panel2D] = []
    server.on_client_connect(lambda client: panels.append(Panel2D(client.gui, "bench", height=420)))
    server.on_client_disconnect(lambda client: panels.clear())

    def pump() -> None:
        t0 = time.perf_counter()
        while not done.is_set():
            start = time.perf_counter()
            for p in list(panels):
                p.show(frame_at(start - t0, n))
            build_ms.append((time.perf_counter() - start) * 1e3)
            done.wait(max(0.0, 1.0 / rate - (time.perf_counter() - start)))

    thread = threading.Thread(target=pump, daemon=True)
    thread.start()

    def stop() -> None:
        done.set()
        thread.join(timeout=2)
        server.stop()

    return panels, build_ms, url, stop


def run(n: int, seconds: float, rate: float, engine: bool) -> dict:
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as tmp:
        if engine:
            panels, build_ms, url, stop = _served_engine(n, rate)
            sent = lambda: panels[0].sent  # noqa: E731
        else:
            app, url, stop = _served_lab(n, tmp)
            build_ms = []
            sent = None
        try:
            with sync_playwright() as pw, tempfile.TemporaryDirectory() as profile:
                ctx = pw.chromium.launch_persistent_context(profile, executable_path=CHROMIUM, headless=True, args=ARGS,
                                                            viewport={"width": 1280, "height": 800})
                page = ctx.new_page()
                page.goto(url)
                page.wait_for_selector("canvas.ejs2d-c[data-drawn]", timeout=60_000)
                page.evaluate("""() => { const E = window.__ejs2d; E.drawMs = [];
                    const p = Object.values(E.panels).find(q => q.canvas && q.canvas.classList.contains('ejs2d-c'));
                    const c = p.canvas; const ctx = c.getContext('2d'); const orig = ctx.clearRect.bind(ctx);
                    // a draw starts with clearRect and ends setting data-drawn
                    ctx.clearRect = (...a) => { E.t0 = performance.now(); return orig(...a); };
                    new MutationObserver(() => { if (E.t0) E.drawMs.push(performance.now() - E.t0); })
                      .observe(c, {attributes: true, attributeFilter: ['data-drawn']}); }""")
                if not engine:
                    session = next(iter(app.classroom.sessions.values()))
                    binding = session.app.views[0].panel.drawings[0]
                    sent = lambda: binding.panel.sent  # noqa: E731
                    original = binding.refresh

                    def timed() -> None:
                        start = time.perf_counter()
                        original()
                        build_ms.append((time.perf_counter() - start) * 1e3)

                    binding.refresh = timed
                time.sleep(1.0)  # warm up
                a = page.evaluate(_TIMING)
                sent0 = sent()
                time.sleep(seconds)
                b = page.evaluate(_TIMING)
                sent1 = sent()
                draw_ms = page.evaluate("() => window.__ejs2d.drawMs.slice(-200)")
                ctx.close()
        finally:
            stop()
    elapsed = (b["t"] - a["t"]) / 1e3
    return {
        "browser_fps": (b["drawn"] - a["drawn"]) / elapsed,
        "server_fps": (sent1 - sent0) / seconds,
        "build_ms": float(np.median(build_ms)) if build_ms else float("nan"),
        "draw_ms": float(np.median(draw_ms)) if draw_ms else float("nan"),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1000, help="elements: half particles, half arrows (default 1000)")
    parser.add_argument("--seconds", type=float, default=8.0)
    parser.add_argument("--rate", type=float, default=60.0, help="with --engine: frames a second the server makes (default 60)")
    parser.add_argument("--target", type=float, default=30.0, help="exit 1 below this many browser frames a second")
    parser.add_argument("--engine", action="store_true", help="the panel engine alone, without a lab")
    args = parser.parse_args(argv)
    r = run(args.n, args.seconds, args.rate, args.engine)
    what = "the panel engine fed from NumPy" if args.engine else "a lab asking for 60 frames/s"
    print(f"2D panel, {args.n} elements ({args.n // 2} particles + {args.n - args.n // 2} arrows), {what}")
    print(f"  browser draws   {r['browser_fps']:6.1f} frames/s   (target >= {args.target:.0f})")
    print(f"  server sends    {r['server_fps']:6.1f} frames/s")
    print(f"  server per frame  {r['build_ms']:6.2f} ms ({'build the frame, encode, queue' if args.engine else 'the panel: expressions, frame, encode, queue'})")
    print(f"  browser per draw  {r['draw_ms']:6.2f} ms (decode and draw on the canvas)")
    return 0 if r["browser_fps"] >= args.target else 1


if __name__ == "__main__":
    sys.exit(main())
