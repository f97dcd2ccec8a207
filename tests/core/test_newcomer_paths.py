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


def test_an_app_and_its_pyz_without_their_packages_name_them_and_the_one_command(tmp_path: Path) -> None:
    from ejsgen.cli import build

    from testkit import EXAMPLES

    app = build(EXAMPLES / "bouncing_ball.ejs.yaml", tmp_path / "ball", bundle=True)
    wanted = [line for line in (app / "requirements.txt").read_text().splitlines() if line and not line.startswith("#")]
    # python3 -S: no site-packages, as on a machine with only Python
    for target, command in ((app / "app.py", f"-m pip install -r {app / 'requirements.txt'}"),
                            (app / "ball.pyz", "-m pip install " + " ".join(f"'{w}'" if "<" in w or ">" in w else w for w in wanted))):
        r = subprocess.run([sys.executable, "-S", str(target), "--headless", "--duration", "1"], capture_output=True, text=True,
                           timeout=120, cwd=tmp_path)
        assert r.returncode == 1, r.stderr
        assert "Traceback" not in r.stderr and "ModuleNotFoundError" not in r.stderr, r.stderr
        assert r.stderr.startswith(f"{target.name}: this app needs Python packages that are not installed: numpy, "), r.stderr
        assert command in r.stderr, r.stderr


def test_app_py_carries_its_packages_as_pep_723_inline_script_metadata(tmp_path: Path) -> None:
    import re
    import tomllib

    from ejsgen.cli import build

    from testkit import EXAMPLES

    app = build(EXAMPLES / "bouncing_ball.ejs.yaml", tmp_path / "ball")
    text = (app / "app.py").read_text(encoding="utf-8")
    # PEP 723's reference regular expression, and its way of reading the block's TOML
    blocks = list(re.finditer(r"(?m)^# /// (?P<type>[a-zA-Z0-9-]+)$\s(?P<content>(^#(| .*)$\s)+)^# ///$", text))
    assert [b.group("type") for b in blocks] == ["script"]
    content = "".join(line[2:] if line.startswith("# ") else line[1:] for line in blocks[0].group("content").splitlines(keepends=True))
    meta = tomllib.loads(content)
    wanted = [line for line in (app / "requirements.txt").read_text().splitlines() if line and not line.startswith("#")]
    assert meta["dependencies"] == wanted and meta["requires-python"] == ">=3.11"
    # with its packages present the app runs as before
    run = subprocess.run([sys.executable, str(app / "app.py"), "--headless", "--duration", "0.02", "--csv", "-", "--vars", "y"],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and run.stdout.splitlines()[:2] == ["y", "1.0"], run.stderr
