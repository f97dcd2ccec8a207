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


def test_run_knows_every_app_option_that_takes_a_value() -> None:
    """``ejsgen run`` keeps its own list of the app's options that take a value (importing
    the runtime to ask would slow every command's start by a quarter of a second): it must
    be the served app's and the sweep's options exactly, or a value would be taken for the spec."""
    import argparse

    from ejsgen.cli import _APP_OPTIONS_WITH_VALUE
    from ejsrl.app.cli import _parser
    from ejsrl.app.sweep import add_sweep_options

    sweep = argparse.ArgumentParser()
    add_sweep_options(sweep)
    taking_values = {o for parser in (_parser("lab"), sweep) for a in parser._actions if a.option_strings and a.nargs != 0
                     for o in a.option_strings if o.startswith("--")}
    assert set(_APP_OPTIONS_WITH_VALUE) == taking_values
