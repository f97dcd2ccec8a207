"""Every broken spec in tests/core/broken/ is refused with its exact FILE:LINE:COL: message.

Each file's first line says what ejsgen must print first: ``# expect: LINE:COL: error: ...``.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from ejsgen.cli import main

BROKEN = sorted((Path(__file__).parent / "broken").glob("*.ejs.yaml"))


def test_the_corpus_is_large_enough() -> None:
    assert len(BROKEN) >= 30


@pytest.mark.parametrize("spec", BROKEN, ids=lambda p: p.name.removesuffix(".ejs.yaml"))
def test_broken_spec_is_reported_at_its_place(spec: Path, capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    expect = spec.read_text().splitlines()[0].removeprefix("# expect: ")
    out_dir = tmp_path / "out"
    status = main(["build", str(spec), "-o", str(out_dir)])
    err = capsys.readouterr().err
    assert status == 1
    assert err.splitlines()[0] == f"{spec}:{expect}"
    assert "Traceback" not in err
    assert not out_dir.exists(), "a failed build must not leave a folder"
    assert not any(tmp_path.iterdir()), "a failed build must not leave temporary files"


def test_validate_reports_from_a_separate_process_without_traceback() -> None:
    spec = next(p for p in BROKEN if p.name == "unknown_name_rate.ejs.yaml")
    r = subprocess.run([sys.executable, "-P", "-m", "ejsgen", "validate", str(spec)], capture_output=True, text=True)
    assert r.returncode == 1
    assert "did you mean 'theta'?" in r.stderr
    assert "Traceback" not in r.stderr


def test_several_errors_are_all_reported_in_file_order(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "two.ejs.yaml"
    spec.write_text(
        "ejs: 1\ntitle: Two\nmodel:\n  variables:\n    t: 0.0\n    dt: 0.1\n    x: 0.0\n"
        "  evolution:\n    - ode:\n        equations:\n          x: -k*x\n"
        "  fixed_relations: |\n    y = x + zz\n"
    )
    assert main(["validate", str(spec)]) == 1
    lines = capsys.readouterr().err.splitlines()
    assert lines == [
        f"{spec}:11:15: error: unknown name 'k'",
        f"{spec}:13:13: error: unknown name 'zz'",
    ]


def test_a_syntax_error_is_reported_alone_not_after_its_echoes(capsys: pytest.CaptureFixture[str]) -> None:
    """A function defined in code that cannot be parsed is unknown where it is called: no echo."""
    spec = next(p for p in BROKEN if p.name == "syntax_error_before_its_echoes.ejs.yaml")
    assert main(["validate", str(spec)]) == 1
    lines = capsys.readouterr().err.splitlines()
    assert lines == [f"{spec}:22:35: error: Python syntax error in model.custom: invalid syntax"]


def test_a_syntax_error_comes_before_other_problems(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = tmp_path / "two.ejs.yaml"
    spec.write_text(
        "ejs: 1\ntitle: Two\nmodel:\n  variables:\n    t: 0.0\n    dt: 0.1\n    x: 0.0\n"
        "view:\n  - scene:\n      - mesh: {file: nowhere.obj}\n"
        "  - button: {label: Go, action: \"x = (1\"}\n"
    )
    assert main(["validate", str(spec)]) == 1
    lines = capsys.readouterr().err.splitlines()
    assert lines == [
        f"{spec}:11:38: error: Python syntax error in the action of button 'Go': '(' was never closed",
        f"{spec}:10:22: error: the mesh file 'nowhere.obj' does not exist; paths are relative to the spec's folder",
    ]


def test_yes_no_on_off_are_text_as_in_yaml_1_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A dropdown of 'on'/'off' and variables named 'on'/'yes' build; only true/false are booleans."""
    from ejsgen.cli import load_plan

    spec = tmp_path / "switch.ejs.yaml"
    spec.write_text(
        "ejs: 1\ntitle: Switch\nmodel:\n  variables:\n    t: 0.0\n    mode: off\n    on: 1.0\n    yes: true\n"
        "view:\n  - dropdown: {bind: mode, options: [on, off, Yes]}\n  - checkbox: {bind: yes}\n"
        "  - label: {text: \"{mode} {on}\"}\nsimulation: {autoplay: no}\n"
    )
    assert main(["validate", str(spec)]) == 0, capsys.readouterr().err
    plan = load_plan(spec)
    assert plan.variables == {"t": "float", "mode": "str", "on": "float", "yes": "bool"}
    app = "\n".join(plan.view_lines)
    assert "['on', 'off', 'Yes']" in app
    assert plan.sim["autoplay"] is False
