"""Nothing a sweep finished is lost: SIGKILL then --resume, a full disk, a lost Dask scheduler.

Before, a sweep kept every result in memory until the end (SIGKILL lost everything, with no
way to resume), crashed after the last run on a full disk (losing them all), and reported a
lost scheduler as thousands of failed runs with status 0. Each test makes the real fault:
a SIGKILL of the process, a 64 KB tmpfs, a `dask scheduler` process started here and killed.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from testkit.disk import small_disk
from testkit.sweeps import SPECS, read

SWEEP = ["--grid", "k=1:4:60", "--values", "m=1,0", "--duration", "0.2", "--every", "5"]  # 120 runs, m = 0 fails


@pytest.fixture(scope="module")
def springs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from ejsgen.cli import build

    return build(SPECS / "springs.ejs.yaml", tmp_path_factory.mktemp("springs") / "app")


def sweep_cmd(app: Path, *args: str) -> list[str]:
    return [sys.executable, str(app / "app.py"), "--sweep", *args]


def _without_seconds(table: dict) -> dict:
    return {k: v for k, v in table.items() if k != "seconds"}


@pytest.fixture(scope="module")
def reference(springs: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, dict]:
    """The same sweep, uninterrupted, in this process (``--workers 0``)."""
    out = tmp_path_factory.mktemp("ref") / "runs.parquet"
    r = subprocess.run(sweep_cmd(springs, *SWEEP, "--workers", "0", "--quiet", "--out", str(out)), capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert not Path(str(out) + ".parts").exists()  # a finished sweep leaves no parts behind
    return read(out), read(out.with_name("runs.summary.parquet"))


def test_a_sigkilled_sweep_resumes_running_only_the_missing_runs_each_once(springs: Path, reference: tuple[dict, dict], tmp_path: Path) -> None:
    out = tmp_path / "runs.parquet"
    parts = tmp_path / "runs.parquet.parts"
    proc = subprocess.Popen(sweep_cmd(springs, *SWEEP, "--workers", "1", "--quiet", "--out", str(out)),
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and len(list(parts.glob("b*.npz"))) < 3:  # some batches kept, not all
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(60)
    kept = sorted(p.name for p in parts.glob("b*.npz"))
    assert 3 <= len(kept) and not out.exists()
    done_before = sum(int(n[10:18]) - int(n[1:9]) + 1 for n in kept)
    assert done_before < 120
    r = subprocess.run(sweep_cmd(springs, *SWEEP, "--workers", "2", "--out", str(out), "--resume"), capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert f"(resuming: {done_before} done, {120 - done_before} to run)" in r.stderr
    results, summary = read(out), read(tmp_path / "runs.summary.parquet")
    assert summary["run"] == list(range(120))  # every run exactly once
    assert results == reference[0]
    assert _without_seconds(summary) == _without_seconds(reference[1])
    assert not parts.exists()


def test_resume_refuses_another_sweeps_parts_and_a_missing_one(springs: Path, tmp_path: Path) -> None:
    out = tmp_path / "runs.csv"
    r = subprocess.run(sweep_cmd(springs, *SWEEP, "--workers", "0", "--quiet", "--out", str(out), "--resume"), capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "--resume: no stopped sweep to continue" in r.stderr and "Traceback" not in r.stderr
    parts = tmp_path / "runs.csv.parts"
    parts.mkdir()
    (parts / "sweep.json").write_text('{"key": "another", "runs": 120}')
    r = subprocess.run(sweep_cmd(springs, *SWEEP, "--workers", "0", "--quiet", "--out", str(out), "--resume"), capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "holds the runs of another sweep" in r.stderr


@pytest.mark.parametrize("suffix", ["csv", "parquet"])
def test_a_full_disk_keeps_the_runs_and_says_so_then_resume_writes_the_tables(springs: Path, reference: tuple[dict, dict], tmp_path: Path, suffix: str) -> None:
    # the runs' parts (19 files of 7 runs, 244 KB in tmpfs pages) fit on the disk; the tables beside them do not
    with small_disk(tmp_path / "disk", "280k") as disk:
        out = disk / f"runs.{suffix}"
        r = subprocess.run(sweep_cmd(springs, *SWEEP, "--workers", "1", "--quiet", "--out", str(out)), capture_output=True, text=True, timeout=600)
        assert r.returncode == 74, r.stderr
        assert "Traceback" not in r.stderr
        last = r.stderr.strip().splitlines()[-1]
        assert last.startswith(f"error: cannot write {disk}/runs.") and "No space left on device" in last, r.stderr
        assert "; removed it; " in last and "rerun with --resume once there is room" in last
        assert not out.exists() and not out.with_name(f"runs.summary.{suffix}").exists()  # no cut table is left
        parts = disk / f"runs.{suffix}.parts"
        files = sorted(parts.glob("b*.npz"))
        assert sum(int(p.name[10:18]) - int(p.name[1:9]) + 1 for p in files) == 120
        # room again: the tables come from the kept runs, nothing is run again
        elsewhere = tmp_path / "room"
        elsewhere.mkdir()
        subprocess.run(["cp", "-r", str(parts), str(elsewhere)], check=True)
    out = tmp_path / "room" / f"runs.{suffix}"
    r = subprocess.run(sweep_cmd(springs, *SWEEP, "--workers", "2", "--quiet", "--out", str(out), "--resume"), capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert "(resuming: 120 done, 0 to run)" in r.stderr
    summary = read(out.with_name(f"runs.summary.{suffix}"))
    if suffix == "parquet":
        assert read(out) == reference[0]
        assert _without_seconds(summary) == _without_seconds(reference[1])
    else:
        assert [int(v) for v in summary["run"]] == list(range(120))
        assert [float(v) for v in read(out)["x[0]"]] == reference[0]["x[0]"]


def test_a_full_disk_during_the_runs_stops_the_sweep_with_the_reason(springs: Path, tmp_path: Path) -> None:
    with small_disk(tmp_path / "disk", "24k") as disk:
        out = disk / "runs.parquet"
        r = subprocess.run(sweep_cmd(springs, *SWEEP, "--workers", "1", "--quiet", "--out", str(out)), capture_output=True, text=True, timeout=600)
        assert r.returncode == 74, r.stderr
        assert "Traceback" not in r.stderr
        assert f"error: cannot write {disk}/runs.parquet.parts/b" in r.stderr and "No space left on device" in r.stderr
        assert "finished runs are kept in" in r.stderr
        # what is kept is whole: no temporary file, every batch file readable
        assert not list((disk / "runs.parquet.parts").glob("*.tmp"))
        from ejsrl.app.sweep_journal import Journal

        j = Journal(disk / "runs.parquet.parts", "", 120)
        assert sum(len(j.read(p)) for _, _, p in j.files()) == len(j.done()) > 0


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_for_port(port: int, proc: subprocess.Popen, timeout: float) -> None:
    """Until something listens on ``port`` (``proc`` must stay alive meanwhile)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert proc.poll() is None, f"the process for port {port} ended with {proc.returncode}"
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=5):
                return
        except OSError:
            time.sleep(0.1)
    raise AssertionError(f"nothing listened on port {port} within {timeout:g} s")


@pytest.mark.slow
def test_a_lost_dask_scheduler_ends_the_sweep_with_one_line_and_a_status_of_its_own(springs: Path, tmp_path: Path) -> None:
    from ejsrl.app.sweep_journal import Journal

    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = dict(os.environ, DASK_DISTRIBUTED__WORKER__DAEMON="False")
    scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", str(port),
                                  "--dashboard-address", ":0", "--no-show"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    worker = sweep = None
    out = tmp_path / "runs.parquet"
    parts = tmp_path / "runs.parquet.parts"
    many = ["--grid", "k=1:4:400", "--duration", "0.5"]
    try:
        # generous waits for a loaded 2-core machine: each step waits on state, not on time
        _wait_for_port(port, scheduler, 300)
        worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nworkers", "1", "--nthreads", "1",
                                   "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
        sweep = subprocess.Popen(sweep_cmd(springs, *many, "--scheduler", address, "--quiet", "--out", str(out)),
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        # the scheduler is killed only once the sweep has demonstrably finished runs (batches kept on disk)
        deadline = time.monotonic() + 600
        while time.monotonic() < deadline and sweep.poll() is None:
            if parts.is_dir() and len(Journal(parts, "", 400).files()) >= 2:
                break
            time.sleep(0.05)
        assert sweep.poll() is None, sweep.communicate()[1]
        assert parts.is_dir() and len(Journal(parts, "", 400).files()) >= 2, "no finished batch within 600 s"
        scheduler.kill()
        scheduler.wait(60)
        _, err = sweep.communicate(timeout=600)
    finally:
        for p in (sweep, worker, scheduler):
            if p is not None and p.poll() is None:
                p.kill()
                p.wait(60)
    assert sweep.returncode == 69, err
    lines = [x for x in err.strip().splitlines() if x.startswith("error:")]
    assert len(lines) == 1 and "Traceback" not in err, err
    done = len(Journal(parts, "", 400).done())
    assert lines[0] == (f"error: the Dask scheduler at {address} was lost after {done} of 400 runs; "
                        f"finished runs are in {parts}; rerun with --resume")
    assert 0 < done < 400
    # resumed on this machine, the rest are run and every run is in the tables once
    r = subprocess.run(sweep_cmd(springs, *many, "--workers", "2", "--quiet", "--out", str(out), "--resume"), capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert read(tmp_path / "runs.summary.parquet")["run"] == list(range(400))


def _peak_rss_kb(cmd: list[str], timeout: float) -> tuple[int, str]:
    """The peak resident memory (VmHWM) of the process ``cmd`` starts (not its workers'), and its stderr."""
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    err: list[str] = []
    reader = threading.Thread(target=lambda: err.append(proc.stderr.read() if proc.stderr else ""), daemon=True)
    reader.start()
    peak = 0
    deadline = time.monotonic() + timeout
    while proc.poll() is None and time.monotonic() < deadline:
        try:
            for line in Path(f"/proc/{proc.pid}/status").read_text().splitlines():
                if line.startswith("VmHWM:"):
                    peak = max(peak, int(line.split()[1]))
        except OSError:
            pass
        time.sleep(0.05)
    proc.wait(timeout=max(deadline - time.monotonic(), 1))
    reader.join(10)
    assert proc.returncode == 0, err
    return peak, "".join(err)


@pytest.mark.slow
def test_the_parents_memory_stays_flat_from_2000_to_20000_runs(springs: Path, tmp_path: Path) -> None:
    # before: 111 MB at 2,000 runs, 166 MB at 20,000 (every result held until the end)
    small, _ = _peak_rss_kb(sweep_cmd(springs, "--grid", "k=1:4:2000", "--duration", "0.05", "--workers", "2", "--quiet",
                                       "--out", str(tmp_path / "small.parquet")), 600)
    large, err = _peak_rss_kb(sweep_cmd(springs, "--grid", "k=1:4:20000", "--duration", "0.05", "--workers", "2",
                                        "--out", str(tmp_path / "large.parquet")), 1800)
    assert "20000 runs (20000 ok, 0 failed)" in err
    assert read(tmp_path / "large.summary.parquet")["run"] == list(range(20000))
    assert large <= 1.25 * small, (small, large)


ENDLESS = """\
ejs: 1
title: Endless
model:
  variables:
    t: 0.0
    dt: 0.1
    x: 1.0
    n: 0
  init: |
    while x > 0:
        try:
            n = n + 1
        except Exception:
            n = 0
  evolution:
    - ode:
        equations:
          x: -x
view: []
"""


@pytest.mark.parametrize("workers", ["0", "1"])
def test_sigterm_stops_a_sweep_whatever_the_spec_code_is_doing(tmp_path: Path, workers: str) -> None:
    from ejsgen.cli import build

    spec = tmp_path / "endless.ejs.yaml"
    spec.write_text(ENDLESS, encoding="utf-8")
    app = build(spec, tmp_path / "app")
    proc = subprocess.Popen(sweep_cmd(app, "--values", "x=1,2,3", "--duration", "1", "--workers", workers, "--out", str(tmp_path / "runs.csv")),
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert proc.stderr is not None
    seen = ""
    deadline = time.monotonic() + 120
    while "3 runs" not in seen and time.monotonic() < deadline:  # the sweep has started its runs
        seen += proc.stderr.readline()
    time.sleep(2.0)  # inside the endless init: (a loop that catches Exception, as spec code may)
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    _, rest = proc.communicate(timeout=60)
    assert time.monotonic() - t0 < 30
    assert proc.returncode == 143, seen + rest
    assert "stopped by SIGTERM after 0 of 3 runs" in rest and "Traceback" not in rest
