"""A new user's paths, as a trial found them (issue #31): app.py copied on its own, a lab's
requirements, an error on a long expression's own line, a resumed sweep's figures.

- ``uv run app.py`` with app.py copied alone installed the packages, then died with a bare
  ``ModuleNotFoundError: No module named 'ejsrl'``: the runtime is the folder beside it (not
  on PyPI), and app.py now says so in one line.
- The pendulum listed OpenCV, which it never loads, and the missing-packages check demanded
  it (and viser) even for ``--headless`` and ``--help``. Here the app runs on a Python whose
  only third-party packages are NumPy, SciPy and trimesh (no OpenCV, no viser): headless it
  runs, served it names viser and the command that installs it.
- A 50,000-term expression was refused at its block's first line, not its own.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from testkit import EXAMPLES

PEP_723 = re.compile(r"(?m)^# /// (?P<type>[a-zA-Z0-9-]+)$\s(?P<content>(^#(| .*)$\s)+)^# ///$")  # the PEP's own expression


def _metadata(app: Path) -> dict:
    """The TOML of app.py's PEP 723 block, read as the PEP says."""
    (block,) = PEP_723.finditer((app / "app.py").read_text(encoding="utf-8"))
    return tomllib.loads("".join(ln[2:] if ln.startswith("# ") else ln[1:] for ln in block.group("content").splitlines(keepends=True)))


def _requirements(app: Path) -> list[str]:
    return [ln for ln in (app / "requirements.txt").read_text().splitlines() if ln and not ln.startswith("#")]


@pytest.fixture(scope="module")
def pendulum(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from ejsgen.cli import build

    return build(EXAMPLES / "pendulum.ejs.yaml", tmp_path_factory.mktemp("pendulum") / "app")


@pytest.fixture(scope="module")
def numpy_scipy_trimesh_only(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder for ``PYTHONPATH`` holding NumPy, SciPy and trimesh (links to this machine's), and
    nothing else: with ``python -S`` (no site-packages) that is a machine without OpenCV and viser."""
    import numpy

    site = Path(numpy.__file__).resolve().parents[1]
    folder = tmp_path_factory.mktemp("site")
    for entry in site.iterdir():
        if re.match(r"(numpy|scipy|trimesh)([.-]|$)", entry.name):
            (folder / entry.name).symlink_to(entry)
    return folder


def test_app_py_copied_alone_says_in_one_line_that_it_needs_its_ejsrl_folder(pendulum: Path, tmp_path: Path) -> None:
    alone = tmp_path / "alone"
    alone.mkdir()
    shutil.copy(pendulum / "app.py", alone / "app.py")
    # python -S: no site-packages, so no ejsrl but the folder a built app carries (here: none)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    r = subprocess.run([sys.executable, "-S", "app.py", "--headless", "--duration", "1"], cwd=alone, env=env, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 1, r.stderr
    assert "Traceback" not in r.stderr and "ModuleNotFoundError" not in r.stderr, r.stderr
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("app.py: this app needs the ejsrl runtime beside it"), r.stderr
    assert "keep the built folder together" in r.stderr and ".pyz" in r.stderr
    # the same app.py with its folder runs (the guard lets a real import error of the runtime through too)
    ok = subprocess.run([sys.executable, str(pendulum / "app.py"), "--headless", "--duration", "0.02", "--csv", "-", "--vars", "theta"],
                        capture_output=True, text=True, timeout=120)
    assert ok.returncode == 0 and ok.stdout.splitlines()[:2] == ["theta", "1.0"], ok.stderr


def test_the_pendulum_lists_no_opencv_and_runs_headless_without_opencv_or_viser(pendulum: Path, numpy_scipy_trimesh_only: Path) -> None:
    listed = _requirements(pendulum)
    assert _metadata(pendulum)["dependencies"] == listed
    assert not any("opencv" in r for r in listed), listed
    assert any(r.startswith("viser") for r in listed)  # serving needs it
    env = {"PYTHONPATH": str(numpy_scipy_trimesh_only), "PATH": "/usr/bin:/bin"}
    probe = subprocess.run([sys.executable, "-S", "-c", "import cv2"], env=env, capture_output=True, text=True, timeout=60)
    assert "No module named 'cv2'" in probe.stderr  # the environment really lacks them
    probe = subprocess.run([sys.executable, "-S", "-c", "import viser"], env=env, capture_output=True, text=True, timeout=60)
    assert "No module named 'viser'" in probe.stderr
    app = str(pendulum / "app.py")
    run = subprocess.run([sys.executable, "-S", app, "--headless", "--duration", "1", "--csv", "-", "--vars", "t,theta"], env=env,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    rows = run.stdout.splitlines()
    assert rows[0] == "t,theta" and len(rows) == 102 and abs(float(rows[-1].split(",")[0]) - 1.0) < 1e-9
    assert subprocess.run([sys.executable, "-S", app, "--help"], env=env, capture_output=True, text=True,
                          timeout=120).returncode == 0
    out = pendulum.parent / "sweep.csv"
    sweep = subprocess.run([sys.executable, "-S", app, "--sweep", "--values", "L=1,2", "--duration", "0.1", "--workers", "0", "--quiet",
                            "--out", str(out)], env=env, capture_output=True, text=True, timeout=120)
    assert sweep.returncode == 0 and "2 runs (2 ok, 0 failed)" in sweep.stderr, sweep.stderr
    # served, it needs viser: the check names it (and only it) with the command that installs the list
    served = subprocess.run([sys.executable, "-S", app, "--port", "0"], env=env, capture_output=True, text=True, timeout=120)
    assert served.returncode == 1 and "Traceback" not in served.stderr, served.stderr
    assert served.stderr.startswith("app.py: this app needs Python packages that are not installed: viser\n"), served.stderr
    assert f"-m pip install -r {pendulum / 'requirements.txt'}" in served.stderr


@pytest.mark.parametrize("spec", ["camera_calibration", "marker_servoing"])
def test_a_vision_lab_still_lists_opencv(spec: str, tmp_path: Path) -> None:
    from ejsgen.cli import build

    app = build(EXAMPLES / f"{spec}.ejs.yaml", tmp_path / "app")
    assert "opencv-python-headless>=4.8" in _requirements(app)
    assert _metadata(app)["dependencies"] == _requirements(app)
    # and it does use it: the headless run imports cv2
    run = subprocess.run([sys.executable, "-X", "importtime", str(app / "app.py"), "--headless", "--steps", "2"],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    assert re.search(r"\|\s+cv2$", run.stderr, re.M), "the lab lists OpenCV but did not import it"


def test_a_spec_that_imports_cv2_lists_opencv(tmp_path: Path) -> None:
    from ejsgen.cli import build

    text = (EXAMPLES / "pendulum.ejs.yaml").read_text(encoding="utf-8")
    spec = tmp_path / "cv.ejs.yaml"
    spec.write_text(text.replace("model:\n", "imports:\n  - import cv2\nmodel:\n", 1), encoding="utf-8")
    app = build(spec, tmp_path / "app")
    assert "opencv-python-headless>=4.8" in _requirements(app) and _metadata(app)["dependencies"] == _requirements(app)


def test_a_too_long_expression_is_refused_at_its_own_line(tmp_path: Path) -> None:
    text = (EXAMPLES / "pendulum.ejs.yaml").read_text(encoding="utf-8")
    lines = text.splitlines()
    key = lines.index("  init: |") + 1  # the line of `init: |` (1-based); the block's code starts on the next
    long = "+".join(["1"] * 50_000)
    spec = tmp_path / "long.ejs.yaml"
    spec.write_text(text.replace("  init: |\n    omega = 0.0\n", f"  init: |\n    omega = 0.0\n    theta = 1.0\n    x = {long}\n    y = 2\n"),
                    encoding="utf-8")
    r = subprocess.run([sys.executable, "-m", "ejsgen", "validate", str(spec)], capture_output=True, text=True, timeout=120)
    assert r.returncode != 0 and "Traceback" not in r.stderr
    assert f"{spec}:{key + 3}:5: error: the code in model.init nests more than 200 levels deep" in r.stderr, r.stderr[:500]
    # a deep expression among statements: also at its own line
    spec.write_text(text.replace("  init: |\n    omega = 0.0\n", "  init: |\n    omega = 0.0\n    if omega == 0:\n"
                                 f"        theta = {'(' * 150}1{')' * 150} + {'-' * 3000}1\n    y = [1, 2, 3]\n"), encoding="utf-8")
    r = subprocess.run([sys.executable, "-m", "ejsgen", "validate", str(spec)], capture_output=True, text=True, timeout=120)
    assert f"{spec}:{key + 3}:9: error: the code in model.init nests more than 200 levels deep" in r.stderr, r.stderr[:500]
