"""What a person at a terminal sees: the progress bar, Ctrl+C keeping the finished runs, the plot, install hints."""

from __future__ import annotations

import os
import pty
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from testkit import EXAMPLES
from testkit.sweeps import SPECS, read


def _sweep_cmd(*args: str) -> list[str]:
    return [sys.executable, "-P", "-m", "ejsgen", "sweep", *args]


def test_a_terminal_shows_a_progress_bar_with_runs_done_rate_and_eta(tmp_path: Path) -> None:
    main, child = pty.openpty()
    cmd = _sweep_cmd(str(SPECS / "springs.ejs.yaml"), "--grid", "k=1:6:6", "--duration", "0.5", "--workers", "1", "--out", str(tmp_path / "r.csv"))
    proc = subprocess.Popen(cmd, stdin=child, stdout=child, stderr=child, close_fds=True)
    os.close(child)
    screen = b""
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline:
        ready, _, _ = select.select([main], [], [], 1.0)
        if ready:
            try:
                chunk = os.read(main, 4096)
            except OSError:  # the child closed the terminal
                break
            if not chunk:
                break
            screen += chunk
        elif proc.poll() is not None:
            break
    proc.wait(timeout=60)
    os.close(main)
    text = screen.decode(errors="replace")
    assert proc.returncode == 0, text
    # redrawn in place: a carriage return before each state of the bar, the last one full
    assert "\r[####" in text
    assert "\r[########################] 6/6 runs" in text
    assert " runs/s  ETA " in text
    assert "6 runs (6 ok, 0 failed)" in text


def test_progress_counts_failures_and_estimates_the_time_left() -> None:
    import io

    from ejsrl.app.sweep_exec import Progress
    from ejsrl.app.sweep_worker import RunResult

    now = [0.0]
    out = io.StringIO()
    bar = Progress(100, out, tty=False, clock=lambda: now[0])
    now[0] = 10.0
    bar.update([RunResult(i, (), "ok") for i in range(20)] + [RunResult(20, (), "error")])
    # 21 runs in 10 s: 2.1 runs/s, 79 left: 38 s
    assert out.getvalue() == "[#####-------------------] 21/100 runs  2.1 runs/s  ETA 0:38  1 failed\n"


def test_ctrl_c_stops_the_sweep_and_keeps_the_runs_that_finished(tmp_path: Path) -> None:
    out = tmp_path / "runs.parquet"
    cmd = _sweep_cmd(str(EXAMPLES / "pendulum.ejs.yaml"), "--values", "L=" + ",".join(str(1 + i / 10) for i in range(20)),
                     "--duration", "20", "--every", "50", "--workers", "1", "--out", str(out))
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stderr is not None
    lines = []
    for line in proc.stderr:  # a line of progress every tenth of the runs when not on a terminal
        lines.append(line)
        if "runs/s" in line:
            break
    proc.send_signal(signal.SIGINT)
    _, rest = proc.communicate(timeout=300)
    text = "".join(lines) + rest
    assert proc.returncode == 130, text
    summary = read(tmp_path / "runs.summary.parquet")
    done = len(summary["run"])
    assert 2 <= done < 20, text
    assert f"stopped by SIGINT after {done} of 20 runs" in text
    assert summary["status"] == ["ok"] * done
    # each finished run is whole: 2000 steps recorded every 50th, plus the first row
    runs = read(out)["run"]
    assert all(runs.count(r) == 41 for r in summary["run"])
    assert "Traceback" not in text


def test_plot_draws_a_summary_column_against_two_parameters(tmp_path: Path) -> None:
    from PIL import Image

    out = tmp_path / "runs.parquet"
    png = tmp_path / "plot.png"
    proc = subprocess.run(
        _sweep_cmd(str(SPECS / "springs.ejs.yaml"), "--grid", "c=0:2:5", "--values", "m=1,2", "--duration", "1",
                   "--out", str(out), "--plot", str(png), "--plot-y", "energy_left", "--workers", "2"),
        capture_output=True, text=True, timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert f"drew {png}" in proc.stderr
    image = np.asarray(Image.open(png).convert("RGB")).astype(int)
    assert image.shape == (440, 640, 3)
    # two curves (m = 1 and m = 2) in matplotlib's first two colours
    blue = np.all(np.abs(image - [31, 119, 180]) < 30, axis=2).sum()
    orange = np.all(np.abs(image - [255, 127, 14]) < 30, axis=2).sum()
    assert blue > 200 and orange > 200, (blue, orange)
    bad = subprocess.run(
        _sweep_cmd(str(SPECS / "springs.ejs.yaml"), "--values", "m=1,2", "--duration", "0.1", "--out", str(out),
                   "--plot", str(png), "--plot-y", "energy_lef", "--workers", "0"),
        capture_output=True, text=True, timeout=300,
    )
    assert bad.returncode == 2 and "'energy_lef' is not a column of the summary; did you mean 'energy_left'?" in bad.stderr


def test_missing_optional_packages_are_named_with_their_install_hint(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    import argparse

    from ejsrl.app import sweep

    for module in ("pyarrow", "distributed", "matplotlib"):
        monkeypatch.setitem(sys.modules, module, None)  # `import module` now raises ImportError
    args = argparse.Namespace(out=str(tmp_path / "r.parquet"), summary=None, dask=False, scheduler=None, plot=None)
    assert "pip install 'ejsgen[sweep]'" in (sweep._check_output(args) or "")
    args.out = str(tmp_path / "r.csv")
    assert sweep._check_output(args) is None  # CSV needs no pyarrow
    args.dask = True
    assert "Dask is not installed: pip install 'ejsgen[sweep]'" in (sweep._check_output(args) or "")
    args.dask, args.plot = False, str(tmp_path / "p.png")
    assert "--plot needs matplotlib: pip install 'ejsgen[plot]'" in (sweep._check_output(args) or "")
