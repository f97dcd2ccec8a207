"""The grading recipe (examples/grading): each student's spec against the reference, over the same runs."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

from testkit import EXAMPLES


def test_grading_passes_the_right_variant_and_names_what_differs_in_the_others(tmp_path: Path) -> None:
    report = tmp_path / "grades.csv"
    proc = subprocess.run([sys.executable, "-P", str(EXAMPLES / "grading" / "grade.py"), "--report", str(report)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    lines = dict(line.split(": ", 1) for line in proc.stdout.splitlines() if ".ejs.yaml: " in line)
    # alice writes the rate differently: equal to rounding, within the tolerance
    assert lines["alice.ejs.yaml"] == "PASS (4 runs)"
    # bob's damping has the wrong sign: his motion is wrong, and worst in a run with damping
    assert lines["bob.ejs.yaml"].startswith("FAIL: x, v, E differ; worst:") and "(c=0.5 " in lines["bob.ejs.yaml"]
    # carol's motion is right; only her energy is wrong, by the missing 1/2 of the kinetic energy
    assert lines["carol.ejs.yaml"].startswith("FAIL: E differs; worst:")
    # dave's spec does not build; the reason points into his file
    assert lines["dave.ejs.yaml"].startswith("FAIL: does not build: ") and "dave.ejs.yaml:27:18: error: unknown name 'xx'" in lines["dave.ejs.yaml"]
    # erin integrates with Euler's method: the motion drifts away from RK4's
    assert lines["erin.ejs.yaml"].startswith("FAIL: x, v, E differ")
    assert "1 of 5 passed" in proc.stdout
    with open(report, newline="") as fh:
        rows = {r["student"]: r for r in csv.DictReader(fh)}
    assert {name: row["passed"] for name, row in rows.items()} == {
        "alice.ejs.yaml": "1", "bob.ejs.yaml": "0", "carol.ejs.yaml": "0", "dave.ejs.yaml": "0", "erin.ejs.yaml": "0"}
    assert rows["carol.ejs.yaml"]["differing"] == "E"


def test_a_student_without_the_compared_variable_fails_with_the_reason(tmp_path: Path) -> None:
    students = tmp_path / "students"
    students.mkdir()
    text = (EXAMPLES / "grading" / "reference.ejs.yaml").read_text()
    (students / "frank.ejs.yaml").write_text(text.replace("E: {value: 0.0, unit: J}", "energy: {value: 0.0, unit: J}")
                                             .replace("E = 0.5*m*v**2", "energy = 0.5*m*v**2").replace("energy_left: E /", "energy_left: energy /"))
    proc = subprocess.run([sys.executable, "-P", str(EXAMPLES / "grading" / "grade.py"), str(EXAMPLES / "grading" / "reference.ejs.yaml"),
                           str(students), "--values", "c=0.5", "--duration", "1"], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "frank.ejs.yaml: FAIL: does not fit the exercise: --vars: unknown variable 'E'" in proc.stdout
