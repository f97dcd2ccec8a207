"""A spec that needs an optional library the machine lacks fails at the build, at its line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from testkit import EXAMPLES

# hides yourdfpy from this interpreter, as on a machine where it was never installed
_HIDE = """
import sys
sys.modules["yourdfpy"] = None  # import yourdfpy raises ImportError
from ejsgen.cli import main
sys.exit(main(sys.argv[1:]))
"""


def test_a_urdf_arm_without_yourdfpy_fails_at_the_build_with_the_install_hint(tmp_path: Path) -> None:
    spec = EXAMPLES / "urdf_arm.ejs.yaml"
    out = tmp_path / "app"
    r = subprocess.run([sys.executable, "-P", "-c", _HIDE, "build", str(spec), "-o", str(out)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 1, r.stdout + r.stderr
    first = r.stderr.strip().splitlines()[0]
    assert first.startswith(f"{spec}:") and ": error: URDF arms are read with yourdfpy, which is not installed" in first, first
    line = int(first.split(":")[1])
    assert "urdf" in spec.read_text().splitlines()[line - 1]  # the spec line that loads the arm
    assert "pip install 'ejsgen[urdf]'" in first
    assert not out.exists()  # nothing half-written


def test_a_urdf_arm_builds_where_yourdfpy_is_installed(tmp_path: Path) -> None:
    from ejsgen.cli import build

    app = build(EXAMPLES / "urdf_arm.ejs.yaml", tmp_path / "app")
    assert "yourdfpy" in (app / "requirements.txt").read_text()


def test_a_lab_that_detects_susan_corners_tells_how_to_make_them_faster(tmp_path: Path) -> None:
    """numba is optional (the ``[fast]`` extra): an app whose spec runs SUSAN says in its README and
    requirements.txt how to install it, as a comment, so the install never fails for want of a
    numba wheel; an app without SUSAN does not mention it."""
    from ejsgen.cli import build

    servo = build(EXAMPLES / "paper" / "visual_servoing_eih.ejs.yaml", tmp_path / "servo")
    reqs = (servo / "requirements.txt").read_text()
    assert "# numba>=0.60" in reqs.splitlines()
    assert all("numba" not in line for line in reqs.splitlines() if not line.startswith("#"))
    assert "`python -m pip install numba` makes them 3-5x faster" in (servo / "README.md").read_text()
    plain = build(EXAMPLES / "pendulum.ejs.yaml", tmp_path / "plain")
    assert "numba" not in (plain / "requirements.txt").read_text() + (plain / "README.md").read_text()


def test_requirements_list_each_package_once_on_its_own_line(tmp_path: Path) -> None:
    from ejsgen.cli import build

    app = build(EXAMPLES / "paper" / "fmu_motor_control.ejs.yaml", tmp_path / "fmu")
    lines = [ln for ln in (app / "requirements.txt").read_text().splitlines() if ln and not ln.startswith("#")]
    names = [ln.split(">")[0].split("<")[0].split("=")[0] for ln in lines]
    assert "fmpy" in names and len(names) == len(set(names))
