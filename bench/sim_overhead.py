"""Simulation-engine overhead of generated apps, side by side with hand-written NumPy RK4.

Prints, in one run:
- time per step of a generated app's engine (``model._ejs_step()``: the RK4 page and the
  fixed relations) against a hand-written NumPy RK4 loop of the same model computing the
  same fixed relations, for the pendulum (2 states) and the mass-spring chain with N = 30
  (60 states); target ratio <= 1.3;
- ``ejsgen build`` time per example, in-process and as a fresh command (target < 1 s);
- app start-to-serving time: from launching ``python app.py`` to the first HTTP answer
  (target < 3 s).

Run: python bench/sim_overhead.py [--steps 20000] [--repeat 7]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
import urllib.request
from math import cos, sin
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import EXAMPLES, build_and_import  # noqa: E402


def hand_pendulum(steps: int) -> float:
    g, L, b, h = 9.81, 1.0, 0.1, 0.01
    t = 0.0
    y = np.array([1.0, 0.0])

    def f(t: float, y: np.ndarray) -> np.ndarray:
        th, om = y
        return np.array([om, -g / L * sin(th) - b * om])

    start = time.perf_counter()
    for _ in range(steps):
        k1 = f(t, y)
        k2 = f(t + h / 2, y + h / 2 * k1)
        k3 = f(t + h / 2, y + h / 2 * k2)
        k4 = f(t + h, y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t += h
        x = L * sin(y[0])  # noqa: F841 - same fixed relations as the app
        yy = -L * cos(y[0])
        E = 0.5 * L**2 * y[1] ** 2 + g * (yy + L)  # noqa: F841 - same fixed relations as the app
    return (time.perf_counter() - start) / steps


def hand_chain(steps: int, n: int = 30) -> float:
    k, m, c, h = 100.0, 0.1, 0.0, 0.005
    t = 0.0
    x0 = 0.05 * np.sin(np.pi * np.arange(1, n + 1) / (n + 1))
    y = np.concatenate((x0, np.zeros(n)))

    def f(t: float, y: np.ndarray) -> np.ndarray:
        pos, vel = y[:n], y[n:]
        padded = np.concatenate(([0.0], pos, [0.0]))
        return np.concatenate((vel, k / m * (padded[2:] - 2 * pos + padded[:-2]) - c * vel))

    start = time.perf_counter()
    for _ in range(steps):
        k1 = f(t, y)
        k2 = f(t + h / 2, y + h / 2 * k1)
        k3 = f(t + h / 2, y + h / 2 * k2)
        k4 = f(t + h, y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t += h
        pos, vel = y[:n], y[n:]
        E = 0.5 * m * np.sum(vel**2) + 0.5 * k * np.sum(np.diff(np.concatenate(([0.0], pos, [0.0]))) ** 2)  # noqa: F841
    return (time.perf_counter() - start) / steps


def app_step_time(module, steps: int) -> float:
    model = module.Model()
    start = time.perf_counter()
    for _ in range(steps):
        model._ejs_step()
    return (time.perf_counter() - start) / steps


def overhead(name: str, hand, steps: int, repeat: int, tmp: Path) -> float:
    module, _ = build_and_import(EXAMPLES / f"{name}.ejs.yaml", tmp)
    app_times, hand_times = [], []
    for _ in range(repeat):  # interleaved, so load changes hit both alike
        app_times.append(app_step_time(module, steps))
        hand_times.append(hand(steps))
    a, h = min(app_times), min(hand_times)
    ratio = a / h
    print(f"  {name:18s} app {a * 1e6:7.2f} us/step   hand-written {h * 1e6:7.2f} us/step   ratio {ratio:5.2f}   {'met' if ratio <= 1.3 else 'NOT met'} (target <= 1.3)")
    return ratio


def build_times(tmp: Path) -> None:
    from ejsgen.cli import build

    specs = sorted(EXAMPLES.glob("*.ejs.yaml")) + sorted((EXAMPLES / "paper").glob("*.ejs.yaml"))
    build(specs[0], tmp / "warm")  # imports and template cache, as in a long-lived tool
    worst = 0.0
    for spec in specs:
        t0 = time.perf_counter()
        build(spec, tmp / ("b_" + spec.name))
        warm = time.perf_counter() - t0
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-P", "-m", "ejsgen", "build", str(spec), "-o", str(tmp / ("c_" + spec.name))], check=True, capture_output=True)
        cold = time.perf_counter() - t0
        worst = max(worst, cold)
        print(f"  {spec.name:34s} in-process {warm * 1000:6.0f} ms   as a command {cold * 1000:6.0f} ms")
    print(f"  slowest command: {worst:.2f} s -> {'met' if worst < 1.0 else 'NOT met'} (target < 1 s)")


def start_to_serving(tmp: Path, name: str = "pendulum") -> None:
    from ejsgen.cli import build

    app = build(EXAMPLES / f"{name}.ejs.yaml", tmp / f"serve_{name}")
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, str(app / "app.py"), "--port", "0"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        url = None
        try:
            for line in proc.stdout:  # type: ignore[union-attr]
                if "serving on http://" in line:
                    url = line.split("serving on ")[1].split()[0]
                    break
            assert url is not None, "the app did not print its URL"
            while True:
                try:
                    urllib.request.urlopen(url, timeout=1).read(64)
                    break
                except OSError:
                    time.sleep(0.02)
            times.append(time.perf_counter() - t0)
        finally:
            proc.terminate()
            proc.wait(timeout=10)
    best = min(times)
    print(f"  {name}: {', '.join(f'{t:.2f}' for t in times)} s (best {best:.2f} s) -> {'met' if best < 3.0 else 'NOT met'} (target < 3 s)")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--steps", type=int, default=20000)
    p.add_argument("--repeat", type=int, default=7)
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        print("engine time per RK4 step, generated app vs hand-written NumPy (min of interleaved runs):")
        overhead("pendulum", hand_pendulum, args.steps, args.repeat, tmp)
        overhead("mass_spring_chain", hand_chain, args.steps // 2, args.repeat, tmp)
        print("ejsgen build time per example:")
        build_times(tmp)
        print("app start-to-serving time (python app.py until the first HTTP answer):")
        start_to_serving(tmp)


if __name__ == "__main__":
    main()
