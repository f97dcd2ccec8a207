"""Generated apps: golden app.py files, every file compiles, atomic builds, bundles, CLI.

Regenerate the golden files after an intended change (or write the one of a new example)
with ``EJSGEN_REGEN_GOLDEN=1 python3 -m pytest tests/core/test_generation.py -k golden``;
a missing golden file fails the test, it is never written silently.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ejsgen.cli import build, load_plan, main
from ejsgen.generate import render_app
from testkit import EXAMPLES, ROOT, run_app

GOLDEN = Path(__file__).parent / "golden"
CORE_EXAMPLES = ["pendulum", "bouncing_ball", "lorenz", "van_der_pol", "mass_spring_chain"]
PAPER_LABS = sorted(f"paper/{p.name.removesuffix('.ejs.yaml')}" for p in (EXAMPLES / "paper").glob("*.ejs.yaml"))
REGEN = os.environ.get("EJSGEN_REGEN_GOLDEN") == "1"
REGEN_HOW = "EJSGEN_REGEN_GOLDEN=1 python3 -m pytest tests/core/test_generation.py -k golden"


def golden_path(name: str) -> Path:
    return GOLDEN / f"test_generated_app_matches_golden-{name.replace('/', '-')}.app.py.golden"


def check_golden(text: str, golden: Path, *, regen: bool = False) -> None:
    """``text`` must equal the golden file; ``regen`` (re)writes it first. A missing
    golden file fails, with the command that writes it."""
    if regen:
        golden.write_text(text)
    if not golden.exists():
        pytest.fail(f"no golden file {golden.name} in {golden.parent}; write it with {REGEN_HOW}", pytrace=False)
    assert text == golden.read_text(), f"{golden.name} differs; if intended, rerun with {REGEN_HOW}"


@pytest.mark.parametrize("name", CORE_EXAMPLES + PAPER_LABS)
def test_generated_app_matches_golden(name: str) -> None:
    text = render_app(load_plan(EXAMPLES / f"{name}.ejs.yaml"))
    check_golden(text, golden_path(name), regen=REGEN)


def test_every_paper_lab_is_checked_against_a_golden_file() -> None:
    assert len(PAPER_LABS) == 9  # the paper's seven labs, lab 8 (FMU) and RobUALab (section 5.1, the remote lab)
    missing = [name for name in PAPER_LABS if not golden_path(name).exists()]
    assert missing == [], f"no golden file for {missing}; write them with {REGEN_HOW}"


def test_a_missing_golden_file_fails_and_is_not_written(tmp_path: Path) -> None:
    golden = tmp_path / "test_generated_app_matches_golden-new_lab.app.py.golden"
    with pytest.raises(pytest.fail.Exception, match="EJSGEN_REGEN_GOLDEN=1"):
        check_golden("print('hi')\n", golden)
    assert not golden.exists()
    check_golden("print('hi')\n", golden, regen=True)  # the regeneration writes it
    assert golden.read_text() == "print('hi')\n"
    with pytest.raises(AssertionError, match="differs"):
        check_golden("print('bye')\n", golden)


@pytest.mark.parametrize("name", CORE_EXAMPLES)
def test_every_generated_python_file_compiles(name: str, built) -> None:
    app = built(name)
    files = list(app.rglob("*.py"))
    assert app / "app.py" in files
    for f in files:
        compile(f.read_text(encoding="utf-8"), str(f), "exec")
    assert (app / "requirements.txt").read_text().count("numpy") == 1
    assert "python app.py" in (app / "README.md").read_text()


def test_example_specs_carry_a_header_comment() -> None:
    for spec in EXAMPLES.glob("*.ejs.yaml"):
        assert spec.read_text().startswith("# "), f"{spec.name} needs a short header comment"


def test_spec_lines_point_back_into_the_spec() -> None:
    spec = EXAMPLES / "pendulum.ejs.yaml"
    text = render_app(load_plan(spec))
    namespace: dict = {"__name__": "golden_check"}
    exec(compile(text, "app.py", "exec"), namespace)  # noqa: S102 - our own generated code
    lines = text.splitlines()
    spec_lines = spec.read_text().splitlines()
    table = namespace["Model"].SPEC_LINES
    # the fixed relation 'x = L*sin(theta)' (written as the author wrote it) maps to the spec line that has it
    app_line = next(i for i, ln in enumerate(lines, 1) if "self.x = self.L*sin(self.theta)" in ln)
    line, col = table[app_line]
    assert spec_lines[line - 1][col - 1 :].startswith("x = L*sin(theta)")


def test_failed_build_leaves_nothing_and_keeps_the_old_app(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "app"
    build(EXAMPLES / "pendulum.ejs.yaml", out)
    before = (out / "app.py").read_text()

    def broken_copy(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr("ejsgen.generate.shutil.copy2", broken_copy)
    monkeypatch.setattr("ejsgen.generate.shutil.copytree", broken_copy)
    with pytest.raises(OSError):
        build(EXAMPLES / "bouncing_ball.ejs.yaml", out)
    assert (out / "app.py").read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["app"]


def test_bundle_runs_headless_from_one_file(tmp_path: Path) -> None:
    out = tmp_path / "pend"
    build(EXAMPLES / "pendulum.ejs.yaml", out, bundle=True)
    pyz = out / "pend.pyz"
    lone = tmp_path / "elsewhere" / "pend.pyz"
    lone.parent.mkdir()
    shutil.copy2(pyz, lone)  # one file, away from the folder and its runtime copy
    r = subprocess.run([sys.executable, str(lone), "--headless", "--duration", "0.5", "--csv", "-", "--vars", "t,theta"], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    rows = r.stdout.strip().splitlines()
    assert rows[0] == "t,theta" and len(rows) == 52


def test_new_writes_a_starter_that_builds_and_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["new", "spring"]) == 0
    assert main(["new", "spring"]) == 1  # no overwrite without --force
    app = build(tmp_path / "spring.ejs.yaml", tmp_path / "out")
    r = run_app(app, "--headless", "--duration", "1", "--csv", "-", "--vars", "t,E", "--every", "100")
    assert r.returncode == 0, r.stderr
    energies = [float(row.split(",")[1]) for row in r.stdout.strip().splitlines()[1:]]
    assert energies[-1] < energies[0]  # damped


def test_new_says_a_command_that_pastes_into_a_shell_for_a_name_with_spaces(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import shlex

    monkeypatch.chdir(tmp_path)
    assert main(["new", "my lab"]) == 0
    command = capsys.readouterr().out.split("try: ", 1)[1].strip()
    assert shlex.split(command) == ["ejsgen", "run", "my lab.ejs.yaml"]
    assert "#   ejsgen run 'my lab.ejs.yaml'" in (tmp_path / "my lab.ejs.yaml").read_text()


def test_run_passes_options_to_the_app(tmp_path: Path) -> None:
    r = subprocess.run(
        [sys.executable, "-P", "-m", "ejsgen", "run", str(EXAMPLES / "pendulum.ejs.yaml"), "--headless", "--duration", "0.1", "--csv", "-", "--vars", "t"],
        capture_output=True, text=True, timeout=120,
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[0] == "t" and len(r.stdout.splitlines()) == 12


def test_schema_command_matches_the_committed_schema(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["schema"]) == 0
    printed = json.loads(capsys.readouterr().out)
    committed = ROOT / "specs" / "ejs.schema.json"
    if REGEN:
        committed.write_text(json.dumps(printed, indent=2) + "\n")
    assert printed == json.loads(committed.read_text()), "specs/ejs.schema.json is stale; rerun with EJSGEN_REGEN_GOLDEN=1"


def test_schema_accepts_the_examples_and_rejects_a_typo() -> None:
    from ejsgen.schema import json_schema
    from ejsgen.yamlload import load_yaml

    schema = json_schema()
    view_kinds = {next(iter(o["properties"])) for o in schema["$defs"]["ViewItem"]["oneOf"]}
    scene_kinds = {next(iter(o["properties"])) for o in schema["$defs"]["SceneItem"]["oneOf"]}
    for spec in EXAMPLES.glob("*.ejs.yaml"):
        data = load_yaml(spec).data
        for item in data.get("view", []):
            assert set(item) <= view_kinds
            for node in item.get("scene", []):
                assert set(node) <= scene_kinds
    assert "slidr" not in view_kinds
    assert schema["$defs"]["SliderEl"]["properties"]["bind"]["description"]


def test_every_field_is_documented() -> None:
    from ejsgen import spec as spec_module
    from pydantic import BaseModel

    for name in dir(spec_module):
        cls = getattr(spec_module, name)
        if isinstance(cls, type) and issubclass(cls, BaseModel) and cls.__module__ == spec_module.__name__:
            for field, info in cls.model_fields.items():
                assert info.description, f"{name}.{field} has no docstring"
