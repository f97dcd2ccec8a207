"""``ejsgen sweep --sandbox``: a hand-in's escape attempts are failed runs with their reason.

Spec code is Python with the rights of whoever runs it: swept without a sandbox, the
hand-in below writes files as root, talks to the network and hangs the sweep. With
``--sandbox`` its build and each of its runs run in bubblewrap; each run of the sweep is one
attempt (``mode``), run 0 is the honest one and must give the unsandboxed sweep's rows bit
for bit, and every attempt fails with its reason (or, where the attempt only returns a
status, leaves no trace) while the other runs carry on.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
from testkit.sweeps import ejsgen, listening, processes_with, read

HONEST, WRITE, SHELL, CONNECT, LOOP, HOG, SLEEP, FAKE_RESULT, HOST_TMP, BIG_FILE, READ_HOME, READ_SIBLING, READ_SHADOW = range(13)


def hostile_spec(folder: Path, target: str, secret: str = "/root/unused") -> Path:
    """A damped spring whose ``init:`` tries one escape per value of ``mode``; ``secret``: a
    file of the teacher's it tries to read (and a classmate's hand-in beside it)."""
    spec = folder / "mallory.ejs.yaml"
    spec.write_text(f"""\
ejs: 1
title: Mallory's spring
imports:
  - import os
  - import pathlib
  - import socket
  - import time
model:
  variables:
    t: 0.0
    dt: 0.01
    x: 1.0
    v: 0.0
    k: 4.0
    mode: 0
    port: 0
  init: |
    x = 1.0
    if mode == {WRITE}:
        pathlib.Path('{target}').write_text('written by a hand-in')
    if mode == {SHELL}:
        os.system('touch {target}.sh; echo x > /work/{Path(target).name}')
    if mode == {CONNECT}:
        socket.create_connection(('127.0.0.1', port), timeout=5).sendall(b'the answers')
    if mode == {LOOP}:
        while True:
            pass
    if mode == {HOG}:
        hog = [bytearray(2**26) for _ in range(200)]
    if mode == {SLEEP}:
        time.sleep(3600)
    if mode == {FAKE_RESULT}:
        pathlib.Path('result.json').write_text('{{"status": "ok", "error": 5}}')
        os._exit(0)
    if mode == {HOST_TMP}:
        pathlib.Path('/tmp/{Path(target).name}').write_text('left in the host /tmp?')
    if mode == {BIG_FILE}:
        pathlib.Path('big.bin').write_bytes(bytes(40 * 2**20))
    if mode == {READ_HOME}:
        x = 2.0 + len(pathlib.Path('{secret}').read_text())
    if mode == {READ_SIBLING}:
        x = 2.0 + len(pathlib.Path('{folder / "classmate.ejs.yaml"}').read_text())
    if mode == {READ_SHADOW}:
        x = 2.0 + len(pathlib.Path('/etc/shadow').read_text())
  evolution:
    - ode:
        method: rk4
        equations:
          x: v
          v: -k*x
view: []
""", encoding="utf-8")
    return spec


@pytest.fixture
def listener() -> Iterator[tuple[int, list[object]]]:
    with listening() as (port, arrived):
        yield port, arrived


LIMITS = ["--cpu-limit", "3", "--memory-limit", "1500", "--wall-limit", "60", "--file-limit", "16"]  # a loaded machine gives the loop 3 s of CPU well within 60 s


def test_every_escape_attempt_fails_its_run_with_the_reason_and_the_honest_run_is_exact(
    tmp_path: Path, listener: tuple[int, list[object]], request: pytest.FixtureRequest
) -> None:
    port, arrived = listener
    target = f"/root/ejsgen-pwned-{uuid.uuid4().hex}"
    secret = Path.home() / f"ejsgen-teacher-secret-{uuid.uuid4().hex}"
    secret.write_text("the exam's answers")
    request.addfinalizer(lambda: secret.unlink(missing_ok=True))
    spec = hostile_spec(tmp_path, target, str(secret))
    (tmp_path / "classmate.ejs.yaml").write_text("ejs: 1\ntitle: a classmate's hand-in\n")
    modes = ",".join(str(m) for m in range(13))
    out = tmp_path / "runs.csv"
    t0 = time.monotonic()
    r = ejsgen("sweep", str(spec), "--sandbox", *LIMITS, "--values", f"mode={modes}", "--set", f"port={port}",
               "--duration", "0.5", "--workers", "2", "--quiet", "--out", str(out))
    took = time.monotonic() - t0
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr
    summary = read(tmp_path / "runs.summary.csv")
    by_mode = {int(m): (status, error) for m, status, error in zip(summary["mode"], summary["status"], summary["error"])}
    # the honest run, and the attempts that only get a status back, run to the end
    assert by_mode[HONEST] == ("ok", "") and by_mode[SHELL] == ("ok", "") and by_mode[HOST_TMP] == ("ok", "")
    status, error = by_mode[WRITE]
    # /root is there only as far as this Python's installation is (pyenv), read-only; elsewhere it is not there at all
    assert status == "error" and ("Read-only file system" in error or "No such file" in error) and "mallory.ejs.yaml:" in error, error
    status, error = by_mode[CONNECT]
    assert status == "error" and ("Network is unreachable" in error or "Connection refused" in error), error
    assert by_mode[LOOP] == ("error", "error: used more than 3 s of CPU time and was stopped")
    assert by_mode[HOG] == ("error", "error: used more than 1500 MB of memory and was stopped")
    assert by_mode[SLEEP] == ("error", "error: ran longer than 60 s and was stopped")
    status, error = by_mode[FAKE_RESULT]
    assert status == "error" and "its result has an error that is not text" in error, error
    assert by_mode[BIG_FILE] == ("error", "error: wrote a file larger than 16 MB and was stopped")
    # nothing of the teacher's, nor a classmate's hand-in beside this one, nor the system's secrets can be read
    for mode in (READ_HOME, READ_SIBLING):
        status, error = by_mode[mode]
        assert status == "error" and "No such file or directory" in error and "mallory.ejs.yaml:" in error, error
    status, error = by_mode[READ_SHADOW]  # hidden (empty), or not readable from the sandbox's user namespace
    assert status == "ok" or "Permission denied" in error or "No such file" in error, error
    # nothing reached the host: no file written anywhere, no connection made
    for path in (target, f"{target}.sh", f"/work/{Path(target).name}", f"/tmp/{Path(target).name}"):
        assert not Path(path).exists(), path
    assert arrived == []
    # the honest run's rows are the unsandboxed sweep's, bit for bit
    plain = tmp_path / "plain.csv"
    r = ejsgen("sweep", str(spec), "--values", f"mode={HONEST}", "--duration", "0.5", "--workers", "0", "--quiet", "--out", str(plain))
    assert r.returncode == 0, r.stderr
    rows = read(out)
    shadow = [float(rows["x"][i]) for i, run in enumerate(rows["run"]) if int(rows["mode"][i]) == READ_SHADOW]
    assert shadow[:1] in ([], [2.0]), shadow[:3]  # read, it read as empty: x starts at 2 + 0 characters
    mine = [i for i, run in enumerate(rows["run"]) if int(rows["mode"][i]) == HONEST]
    theirs = read(plain)
    for name in ("t", "x", "v"):
        assert [rows[name][i] for i in mine] == theirs[name]
    assert took < 400, took


def test_a_spec_that_does_not_build_is_named_at_its_line(tmp_path: Path) -> None:
    spec = tmp_path / "dave.ejs.yaml"
    spec.write_text("ejs: 1\ntitle: Dave\nmodel:\n  variables:\n    t: 0.0\n    x: 1.0\n  init: |\n    x = xx\nview: []\n", encoding="utf-8")
    r = ejsgen("sweep", str(spec), "--sandbox", "--values", "x=1,2", "--duration", "0.1", "--out", str(tmp_path / "runs.csv"))
    assert r.returncode == 1
    assert f"{spec}:8:9: error: unknown name 'xx'" in r.stderr and "did you mean 'x'" in r.stderr, r.stderr
    assert "Traceback" not in r.stderr and not (tmp_path / "runs.csv").exists()


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "Ctrl+C"])
def test_a_signal_stops_the_sweep_while_a_run_loops_and_leaves_nothing_running(tmp_path: Path, signum: int) -> None:
    spec = hostile_spec(tmp_path, "/root/unused")
    out = tmp_path / "runs.csv"
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    proc = subprocess.Popen([sys.executable, "-P", "-m", "ejsgen", "sweep", str(spec), "--sandbox", "--cpu-limit", "600", "--wall-limit", "600",
                             "--values", f"mode={HONEST},{LOOP}", "--duration", "0.5", "--workers", "2", "--quiet", "--out", str(out)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
    marker = "run1/result.json"  # the looping run is the only process with it in its command line
    parts = Path(f"{out}.parts")
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and not (processes_with(marker, ancestor=proc.pid) and list(parts.glob("b*"))):
        assert proc.poll() is None, proc.communicate()[1]
        time.sleep(0.1)
    running = processes_with(marker, ancestor=proc.pid)
    assert running, "the looping run never started"
    t0 = time.monotonic()
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=60)
    assert time.monotonic() - t0 < 30
    assert proc.returncode == 128 + signum, err
    assert f"stopped by {signal.Signals(signum).name} after 1 of 2 runs" in err, err
    assert "Traceback" not in err
    left = time.monotonic() + 15  # a loaded machine's kernel may take a moment to reap the sandbox
    while time.monotonic() < left and processes_with(marker, among=running):
        time.sleep(0.1)
    assert processes_with(marker, among=running) == []
    assert read(tmp_path / "runs.summary.csv")["mode"] == [str(HONEST)]  # the finished run is kept
