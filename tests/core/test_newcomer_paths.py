"""A new user's paths: ``python3 -m ejsgen`` from a checkout's root, however the package was installed.

After a wheel install, the checkout's root holds ``ejsgen/`` without ``ejsgen/templates``
(the wheel maps ``templates/``, ``specs/`` and ``runtime/ejsrl`` into the package), and
``python3 -m ejsgen`` there imported the checkout's ``ejsgen`` and failed with ``No module
named 'ejsgen.templates'``. The test copies the checkout's folders to a fresh root and runs
``python3 -m ejsgen`` there with no install finder of this machine in the way (the editable
install's is removed): the copy alone must build and serve its docs.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

from testkit import ROOT

RUN_MODULE = (
    "import runpy, sys; "
    "sys.meta_path[:] = [f for f in sys.meta_path if 'editable' not in type(f).__module__.lower() + getattr(f, '__name__', '').lower()]; "
    "sys.path[:] = [p for p in sys.path if not p.startswith(%r)]; "
    "sys.path.insert(0, ''); "
    "sys.argv[0] = 'ejsgen'; "
    "runpy.run_module('ejsgen', run_name='__main__', alter_sys=True)"
) % str(ROOT)


def _checkout(tmp_path: Path) -> Path:
    root = tmp_path / "checkout"
    for folder in ("ejsgen", "templates", "specs", "runtime", "examples"):
        shutil.copytree(ROOT / folder, root / folder, ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "gallery", "paper"))
    return root


def test_python_m_ejsgen_from_a_checkout_root_builds_without_an_install(tmp_path: Path) -> None:
    root = _checkout(tmp_path)
    r = subprocess.run([sys.executable, "-c", RUN_MODULE, "build", "examples/bouncing_ball.ejs.yaml", "-o", str(tmp_path / "out")],
                       cwd=root, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "No module named" not in r.stderr
    app = (tmp_path / "out" / "app.py").read_text(encoding="utf-8")
    assert "class Model(ModelBase)" in app
    # the runtime shipped beside app.py is the checkout's, in step with its compiler
    assert (tmp_path / "out" / "ejsrl" / "app" / "sweep_journal.py").is_file()
    run = subprocess.run([sys.executable, str(tmp_path / "out" / "app.py"), "--headless", "--duration", "0.05", "--csv", "-", "--vars", "y"],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0 and run.stdout.splitlines()[:2] == ["y", "1.0"], run.stderr


def test_python_m_ejsgen_from_a_checkout_root_prints_its_docs(tmp_path: Path) -> None:
    root = _checkout(tmp_path)
    r = subprocess.run([sys.executable, "-c", RUN_MODULE, "docs", "reference"], cwd=root, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "they are **not a sandbox**" in r.stdout
