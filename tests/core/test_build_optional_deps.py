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
