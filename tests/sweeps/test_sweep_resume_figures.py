"""What a resumed sweep says (issue #31, from a trial): its rate counts only the runs it
computes now (the trial saw "333.6 runs/s" from runs it skipped), and a sweep whose runs were
all done already says there was nothing to run (it said "in 0.00 s (0.0 runs/s)")."""

from __future__ import annotations

import io
import subprocess
import sys
from pathlib import Path

import pytest

from testkit.disk import small_disk
from testkit.sweeps import SPECS, read

SWEEP = ["--grid", "k=1:4:60", "--values", "m=1,0", "--duration", "0.2", "--every", "5"]  # 120 runs, m = 0 fails


def test_a_resumed_sweeps_progress_rates_only_the_runs_computed_now() -> None:
    from ejsrl.app.sweep_exec import Progress
    from ejsrl.app.sweep_worker import RunResult

    now = [0.0]
    out = io.StringIO()
    bar = Progress(100, out, tty=False, clock=lambda: now[0])
    bar.skip(60)  # --resume found 60 runs done
    assert out.getvalue() == ""  # nothing drawn for runs not run now
    now[0] = 10.0
    bar.update([RunResult(60 + i, (), "ok") for i in range(10)])
    # 10 runs in 10 s: 1.0 runs/s (not 7.0), 30 left: 30 s
    assert out.getvalue() == "[################--------] 70/100 runs  1.0 runs/s  ETA 0:30\n"


@pytest.fixture(scope="module")
def springs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from ejsgen.cli import build

    return build(SPECS / "springs.ejs.yaml", tmp_path_factory.mktemp("springs") / "app")


def test_a_resumed_sweep_with_every_run_done_says_there_was_nothing_to_run(springs: Path, tmp_path: Path) -> None:
    # every run finished, then the tables did not fit on the disk: the runs are kept in the parts folder
    with small_disk(tmp_path / "disk", "280k") as disk:
        out = disk / "runs.csv"
        cmd = [sys.executable, str(springs / "app.py"), "--sweep", *SWEEP, "--workers", "1", "--quiet"]
        r = subprocess.run([*cmd, "--out", str(out)], capture_output=True, text=True, timeout=600)
        assert r.returncode == 74 and "rerun with --resume once there is room" in r.stderr, r.stderr
        room = tmp_path / "room"
        room.mkdir()
        subprocess.run(["cp", "-r", str(disk / "runs.csv.parts"), str(room)], check=True)
    parts = room / "runs.csv.parts"
    r = subprocess.run([*cmd, "--out", str(room / "runs.csv"), "--resume"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    summary = read(room / "runs.summary.csv")
    ok = sum(s == "ok" for s in summary["status"])
    assert [int(v) for v in summary["run"]] == list(range(120)) and ok == 60
    lines = r.stderr.splitlines()
    assert f"nothing to run: all 120 runs (60 ok, 60 failed) were already in {parts}; wrote {room / 'runs.csv'}" in lines[1], r.stderr
    assert "runs/s" not in r.stderr and " in 0.00 s" not in r.stderr


def test_a_resumed_sweep_reports_the_rate_of_the_runs_it_computed(springs: Path, tmp_path: Path) -> None:
    """Stopped by Ctrl+C after some runs, then resumed: the line says how many ran now, at what
    rate, and how many were already there."""
    import signal

    out = tmp_path / "runs.csv"
    cmd = [sys.executable, str(springs / "app.py"), "--sweep", *SWEEP, "--workers", "1", "--out", str(out)]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert proc.stderr is not None
    for line in proc.stderr:  # a line of progress every tenth of the runs when not on a terminal
        if "runs/s" in line:
            break
    proc.send_signal(signal.SIGINT)
    _, rest = proc.communicate(timeout=300)
    assert proc.returncode == 130, rest
    before = len(read(Path(str(out).replace(".csv", ".summary.csv")))["run"])
    assert 0 < before < 120
    r = subprocess.run([*cmd, "--quiet", "--resume"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    (line,) = [ln for ln in r.stderr.splitlines() if "runs/s" in ln]
    assert f": {120 - before} run now (" in line and f"runs/s), {before} were already in {out}.parts; wrote {out}" in line, line
