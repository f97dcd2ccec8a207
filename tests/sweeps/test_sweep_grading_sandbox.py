"""Grading runs hand-ins in a sandbox: each escape attempt is a failed hand-in with its reason.

Spec code is Python with the teacher's rights: before, ``imports: [import os]`` and
``os.system(...)`` wrote a file as root, a hand-in whose ``init:`` never ended hung grading,
and SIGTERM was ignored. Each hand-in here is the reference with one hostile ``init:``;
an honest copy of the reference is graded beside them and still passes.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path


from testkit import EXAMPLES
from testkit.sweeps import listening, processes_with

GRADE = EXAMPLES / "grading" / "grade.py"
REFERENCE = EXAMPLES / "grading" / "reference.ejs.yaml"
FAST = ["--values", "c=0.5", "--duration", "0.5"]


def handin(folder: Path, name: str, imports: list[str], init: str) -> Path:
    """The reference spec with ``imports`` and ``init`` code (lines, indented as the block) of a student."""
    text = REFERENCE.read_text(encoding="utf-8")
    if imports:
        text = text.replace("model:\n", "imports:\n" + "".join(f"  - {i}\n" for i in imports) + "model:\n", 1)
    text = text.replace("  init: |\n    x = x0\n", "  init: |\n" + "".join(f"    {line}\n" for line in init.splitlines()) + "    x = x0\n")
    path = folder / f"{name}.ejs.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def grade(students: Path, *extra: str, timeout: float = 600) -> tuple[int, dict[str, str], str]:
    proc = subprocess.run([sys.executable, "-P", str(GRADE), str(REFERENCE), str(students), *FAST, *extra],
                          capture_output=True, text=True, timeout=timeout)
    lines = dict(line.split(": ", 1) for line in proc.stdout.splitlines() if ".ejs.yaml: " in line)
    return proc.returncode, lines, proc.stderr


def test_writing_outside_its_folder_fails_the_handin_and_writes_nothing(tmp_path: Path) -> None:
    students = tmp_path / "students"
    students.mkdir()
    target = Path("/root") / f"ejsgen-pwned-{uuid.uuid4().hex}"
    handin(students, "mallory", ["import pathlib"], f"pathlib.Path('{target}').write_text('x')")
    handin(students, "oscar", ["import os"], f"os.system('touch {target}.sh; echo written > /work/{target.name}')")
    (students / "zoe.ejs.yaml").write_text(REFERENCE.read_text(encoding="utf-8"), encoding="utf-8")
    status, lines, err = grade(students)
    assert status == 0, err
    assert lines["mallory.ejs.yaml"].startswith("FAIL: run 0 (c=0.5) failed: ") and "Read-only file system" in lines["mallory.ejs.yaml"]
    # os.system's shell could not write either (the run itself goes on: os.system only returns a status)
    assert not target.exists() and not Path(f"{target}.sh").exists() and not Path(f"/work/{target.name}").exists()
    assert lines["zoe.ejs.yaml"] == "PASS (1 runs)"


def test_connecting_out_fails_the_handin_and_nothing_arrives(tmp_path: Path) -> None:
    students = tmp_path / "students"
    students.mkdir()
    with listening() as (port, arrived):
        handin(students, "eve", ["import socket"], f"socket.create_connection(('127.0.0.1', {port}), timeout=5).sendall(b'answers')")
        handin(students, "trudy", ["import urllib.request"], "urllib.request.urlopen('http://1.1.1.1/', timeout=5)")
        status, lines, err = grade(students)
    assert status == 0, err
    assert lines["eve.ejs.yaml"].startswith("FAIL: run 0 (c=0.5) failed: ")
    assert "Connection refused" in lines["eve.ejs.yaml"] or "unreachable" in lines["eve.ejs.yaml"], lines["eve.ejs.yaml"]
    assert lines["trudy.ejs.yaml"].startswith("FAIL: run 0 (c=0.5) failed: ") and "unreachable" in lines["trudy.ejs.yaml"]
    assert arrived == []


def test_a_loop_and_a_memory_hog_fail_on_their_limits_and_the_rest_carry_on(tmp_path: Path) -> None:
    students = tmp_path / "students"
    students.mkdir()
    handin(students, "loopy", [], "while True:\n    pass")
    handin(students, "greedy", [], "hog = [bytearray(2**26) for _ in range(200)]")
    (students / "zoe.ejs.yaml").write_text(REFERENCE.read_text(encoding="utf-8"), encoding="utf-8")
    t0 = time.monotonic()
    status, lines, err = grade(students, "--cpu-limit", "8", "--memory-limit", "1500", "--wall-limit", "120")
    assert status == 0, err
    assert lines["loopy.ejs.yaml"] == "FAIL: run 0 (c=0.5) failed: used more than 8 s of CPU time and was stopped"
    assert lines["greedy.ejs.yaml"] == "FAIL: run 0 (c=0.5) failed: used more than 1500 MB of memory and was stopped"
    assert lines["zoe.ejs.yaml"] == "PASS (1 runs)"
    assert time.monotonic() - t0 < 400


def test_a_loop_past_the_wall_limit_is_stopped(tmp_path: Path) -> None:
    students = tmp_path / "students"
    students.mkdir()
    handin(students, "sleepy", ["import time"], "time.sleep(3600)")  # no CPU used: only the wall limit stops it
    t0 = time.monotonic()
    status, lines, err = grade(students, "--wall-limit", "10")
    assert status == 0, err
    assert lines["sleepy.ejs.yaml"] == "FAIL: run 0 (c=0.5) failed: ran longer than 10 s and was stopped"
    assert time.monotonic() - t0 < 200


def test_sigterm_stops_grading_while_a_handin_loops_and_leaves_nothing_running(tmp_path: Path) -> None:
    students = tmp_path / "students"
    students.mkdir()
    handin(students, "a_loopy", [], "while True:\n    pass")
    handin(students, "b_zoe", [], "")
    proc = subprocess.Popen([sys.executable, "-P", str(GRADE), str(REFERENCE), str(students), *FAST, "--cpu-limit", "600", "--wall-limit", "600"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    marker = "run0.csv"  # the looping hand-in's run is the only command with it
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and not processes_with(marker, ancestor=proc.pid):
        time.sleep(0.1)
    time.sleep(1.0)
    running = processes_with(marker, ancestor=proc.pid)
    assert running, "the looping hand-in never ran"
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=60)
    assert time.monotonic() - t0 < 30
    assert proc.returncode == 143, err
    assert "stopped by SIGTERM after 0 of 2 hand-ins; the others are not graded" in err
    assert "Traceback" not in err and "PASS" not in out
    left = time.monotonic() + 15  # the sandbox dies with its parent; give a loaded machine time
    while time.monotonic() < left and processes_with(marker, among=running):
        time.sleep(0.1)
    assert processes_with(marker, among=running) == []


def test_sigterm_while_the_reference_runs_grades_nobody(tmp_path: Path) -> None:
    students = tmp_path / "students"
    students.mkdir()
    (students / "zoe.ejs.yaml").write_text(REFERENCE.read_text(encoding="utf-8"), encoding="utf-8")
    tmp = tmp_path / "tmp"  # grading's temporary folder lands here: the reference's build shows in it
    tmp.mkdir()
    proc = subprocess.Popen([sys.executable, "-P", str(GRADE), str(REFERENCE), str(students), "--values", "c=0,0.1,0.2,0.3,0.4,0.5",
                             "--duration", "2000"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, TMPDIR=str(tmp)))
    deadline = time.monotonic() + 300  # the reference is built; its sweep of 6 long runs (tens of seconds each) starts
    while time.monotonic() < deadline and not list(tmp.glob("ejsgen-grade-*/reference/app.py")):
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.1)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert "while running the reference; no hand-in was graded" in err
    assert "zoe" not in out and "passed" not in out
