"""Seconds an ``init:`` spends importing modules are not taken for an endless loop.

The marker lab's first ``capture()`` imports trimesh and SciPy: 2.5 s of a 3.7 s ``init:``
on a busy machine, which printed "init: has been running for 3 s ... (an endless loop?)" at
every start. The warning now counts only the time ``init:`` runs outside imports: an
``init:`` that imports a slow module (here one that takes 3 s to import) says nothing,
while one that spends as long in its own code still gets the warning with its line.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

SPEC = """\
ejs: 1
title: Slow imports
imports:
  - import importlib
  - import time
model:
  variables:
    t: 0.0
    dt: 0.1
    x: 1.0
    own: false
  init: |
    x = 1.0
    if own:
        time.sleep(3.0)
    else:
        importlib.import_module("slow_to_import")
  evolution:
    - ode:
        equations:
          x: -x
view: []
"""


def _run(app: Path, modules: Path, *settings: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, PYTHONPATH=str(modules), EJSRL_SLOW_SECONDS="1")
    args = [sys.executable, str(app / "app.py"), "--headless", "--steps", "2", "--csv", "-"]
    for s in settings:
        args += ["--set", s]
    return subprocess.run(args, capture_output=True, text=True, timeout=300, env=env, check=False)


def test_an_init_slow_only_in_imports_gives_no_warning_and_one_slow_in_its_own_code_does(tmp_path: Path) -> None:
    from ejsgen.cli import build

    spec = tmp_path / "imports.ejs.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    app = build(spec, tmp_path / "app")
    modules = tmp_path / "modules"
    modules.mkdir()
    (modules / "slow_to_import.py").write_text("import time\ntime.sleep(3.0)\n", encoding="utf-8")
    importing = _run(app, modules)
    assert importing.returncode == 0, importing.stderr
    assert "warning" not in importing.stderr, importing.stderr
    assert importing.stdout.splitlines()[0].startswith("t,")
    looping = _run(app, modules, "own=true")
    assert looping.returncode == 0, looping.stderr
    assert "imports.ejs.yaml:15:9: warning: init: has been running for 1 s and is at this line now" in looping.stderr, looping.stderr
