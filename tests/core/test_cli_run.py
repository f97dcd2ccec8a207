"""``ejsgen run``: the app's options may stand before or after the spec, and its help names them."""

from __future__ import annotations

import subprocess
import sys

from testkit import EXAMPLES


def _ejsgen(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-P", "-m", "ejsgen", *args], capture_output=True, text=True, timeout=300)


def test_app_options_before_the_spec_reach_the_app() -> None:
    spec = str(EXAMPLES / "pendulum.ejs.yaml")
    before = _ejsgen("run", "--headless", "--duration", "0.05", "--csv", "-", "--vars", "t,theta", spec)
    after = _ejsgen("run", spec, "--headless", "--duration", "0.05", "--csv", "-", "--vars", "t,theta")
    assert before.returncode == 0, before.stderr
    assert before.stdout.splitlines()[0] == "t,theta"
    assert before.stdout == after.stdout


def test_run_help_names_the_apps_serving_options() -> None:
    r = _ejsgen("run", "--help")
    assert r.returncode == 0
    text = " ".join(r.stdout.split())
    for option in ("--port", "--host", "--shared", "--max-sessions", "--headless", "python app.py --help"):
        assert option in text, option
