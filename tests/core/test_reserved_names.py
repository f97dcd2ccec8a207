"""Names a spec may not take: derived from the runtime, checked against the runtime itself.

The reserved names are found here independently of the compiler's lists: by ``dir()`` of
``ModelBase``, by the globals of built apps (imported as modules) and by the parameters and
locals of their generated methods. Every such name must be refused at its spec location, so
a name added to the runtime or the template later is reserved (or this test says which is
not). A spec that used to build with such a name and then crash is now refused, and the
suggested name builds and runs.
"""

from __future__ import annotations

import ast
import importlib.util
import keyword
import re
import subprocess
import sys
from pathlib import Path

import pytest

from ejsgen.cli import load_plan, main
from ejsgen.errors import SpecErrors
from ejsrl.sim.model import ModelBase
from ejsrl.sim.programs import Program

#: examples that between them generate every kind of method: ODE pages with arrays and events,
#: view setters and actions, robot programs
EXAMPLES_BUILT = ["mass_spring_chain", "bouncing_ball", "paper/pick_and_place", "paper/six_axis_kinematics"]


def _refusals(tmp_path: Path, text: str) -> list[tuple[int, str]]:
    """(line, message) of every error ejsgen reports for the spec ``text`` (empty if it compiles)."""
    spec = tmp_path / "s.ejs.yaml"
    spec.write_text(text, encoding="utf-8")
    try:
        load_plan(spec)
    except SpecErrors as exc:
        return [(e.where.line, e.format().removeprefix(f"{spec}:")) for e in exc.errors]
    return []


def _identifier_names(names: set[str]) -> list[str]:
    return sorted(n for n in names if n.isidentifier() and not keyword.iskeyword(n))


def test_every_attribute_of_the_model_base_is_refused_as_a_variable_name(tmp_path: Path) -> None:
    names = _identifier_names(set(dir(ModelBase)))
    assert {"VARIABLES", "SPEC", "play", "_init", "_ejs_step", "__init__"} <= set(names)
    lines = "".join(f"    {n}: 1.0\n" for n in names)
    errors = _refusals(tmp_path, f"ejs: 1\ntitle: T\nmodel:\n  variables:\n{lines}view: []\n")
    refused_lines = {line for line, _ in errors}
    not_refused = [n for i, n in enumerate(names) if i + 5 not in refused_lines]
    assert not_refused == [], f"variables named like ModelBase attributes build: {not_refused}"


def test_every_attribute_of_the_model_base_is_refused_as_a_custom_function_name(tmp_path: Path) -> None:
    names = [n for n in _identifier_names(set(dir(ModelBase)))]
    body = "".join(f"    def {n}():\n        return 1\n" for n in names)
    errors = _refusals(tmp_path, f"ejs: 1\ntitle: T\nmodel:\n  variables:\n    x: 0.0\n  custom: |\n{body}view: []\n")
    refused_lines = {line for line, _ in errors}
    not_refused = [n for i, n in enumerate(names) if 7 + 2 * i not in refused_lines]
    assert not_refused == [], f"custom functions named like ModelBase attributes build: {not_refused}"


def _app_module(app: Path) -> dict[str, object]:
    """The globals of a built app's ``app.py``, imported as a module (not run as a script)."""
    spec = importlib.util.spec_from_file_location(f"built_app_{app.name}", app / "app.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return vars(module)


def _user_import_names(spec_file: Path) -> set[str]:
    plan = load_plan(spec_file)
    out: set[str] = set()
    for line in plan.user_imports:
        for node in ast.walk(ast.parse(line)):
            if isinstance(node, ast.alias):
                out.add((node.asname or node.name).split(".")[0])
    return out


_GENERATED_BODY = re.compile(r"_evolution|_ode\d+_(rates|state|load|step|event\d+_when)")


def _generated_locals(app: Path) -> set[str]:
    """Parameters of the generated (``_``-named) methods, and the locals of those with no spec code
    but expressions inside (rates, events, state packing)."""
    tree = ast.parse((app / "app.py").read_text(encoding="utf-8"))
    model = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Model")
    out: set[str] = set()
    for fn in model.body:
        if not isinstance(fn, ast.FunctionDef) or not fn.name.startswith("_"):
            continue
        out |= {a.arg for a in fn.args.args}
        if _GENERATED_BODY.fullmatch(fn.name):
            out |= {n.id for n in ast.walk(fn) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
    return out


def test_every_name_a_built_app_binds_is_refused_as_an_import(built, tmp_path: Path) -> None:
    from testkit import EXAMPLES

    reserved: set[str] = set()
    for name in EXAMPLES_BUILT:
        app = built(name)
        user = _user_import_names(EXAMPLES / f"{name}.ejs.yaml")
        module_names = {n for n in _app_module(app) if not n.startswith("__")} - user
        assert {"Model", "VIEW", "E"} <= module_names
        reserved |= module_names | _generated_locals(app)
    assert {"ProgramDef", "OdePage", "EventDef", "cmd", "self"} <= reserved  # the apps bind no getter/setter or packing locals any more
    names = sorted(reserved)
    imports = "".join(f"  - from math import tau as {n}\n" for n in names)
    errors = _refusals(tmp_path, f"ejs: 1\ntitle: T\nimports:\n{imports}model:\n  variables:\n    x: 0.0\nview: []\n")
    refused_lines = {line for line, _ in errors}
    not_refused = [n for i, n in enumerate(names) if 4 + i not in refused_lines]
    assert not_refused == [], f"imports binding names the generated app uses build: {not_refused}"


def test_every_prelude_method_is_reserved_and_callable_by_its_bare_name(tmp_path: Path) -> None:
    """The controls are read from ModelBase and the commands from Program: each is known to code."""
    from ejsrl.sim.names import command_names, control_names

    public = {n for n, v in vars(ModelBase).items() if callable(v) and not n.startswith("_")}
    assert set(control_names()) == public, "a public method of ModelBase that spec code cannot call (or the reverse)"
    assert {"move_j", "move_l", "wait", "wait_until", "open_gripper", "close_gripper"} == set(command_names())
    assert all(hasattr(Program, n) for n in command_names())
    calls = "".join(f"        ok = callable({n})\n" for n in control_names())
    errors = _refusals(tmp_path, f"ejs: 1\ntitle: T\nmodel:\n  variables:\n    x: 0.0\nview:\n  - button:\n      label: Go\n      action: |\n{calls}")
    assert errors == []


def test_an_import_binding_a_variable_name_is_refused_at_the_alias(tmp_path: Path) -> None:
    errors = _refusals(tmp_path, "ejs: 1\ntitle: T\nimports:\n  - import math, numpy as x\nmodel:\n  variables:\n    x: 0.0\nview: []\n")
    assert [m for _, m in errors] == [
        "4:18: error: the import binds 'x', which is also a variable; import it under another name, e.g. 'import numpy as x_'"
    ]


UNGUARDED = """\
ejs: 1
title: Energy
model:
  variables:
    t: 0.0
    dt: 0.01
    {name}: 3
    x: 1.0
  evolution:
    - ode:
        equations:
          x: -x
  fixed_relations: |
    {name} = {name} + 1
view:
  - label: {{text: "n = {{{name}}}"}}
"""


def test_a_variable_named_VARIABLES_is_refused_and_the_suggested_name_runs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``VARIABLES`` built cleanly and then the app crashed; now the build refuses it and names a fix."""
    spec = tmp_path / "energy.ejs.yaml"
    spec.write_text(UNGUARDED.format(name="VARIABLES"), encoding="utf-8")
    out = tmp_path / "out"
    assert main(["build", str(spec), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.splitlines()[0] == f"{spec}:7:5: error: 'VARIABLES' is a name the generated app uses; rename the variable (e.g. 'VARIABLES_')"
    assert not out.exists()
    spec.write_text(UNGUARDED.format(name="VARIABLES_"), encoding="utf-8")
    assert main(["build", str(spec), "-o", str(out)]) == 0
    csv = tmp_path / "run.csv"
    r = subprocess.run([sys.executable, str(out / "app.py"), "--headless", "--duration", "0.05", "--csv", str(csv)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    header, *rows = csv.read_text().splitlines()
    assert "VARIABLES_" in header.split(",")
    assert rows and float(rows[-1].split(",")[header.split(",").index("VARIABLES_")]) > 3


def test_an_import_named_like_the_view_module_is_refused_not_a_crash_at_start(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``from math import e as E`` replaced the app's view elements module ``E``: the app crashed on start."""
    spec = tmp_path / "e.ejs.yaml"
    spec.write_text("ejs: 1\ntitle: T\nimports:\n  - from math import e as E\nmodel:\n  variables:\n    x: 0.0\n  init: |\n    x = E\nview:\n  - label: {text: '{x}'}\n", encoding="utf-8")
    assert main(["build", str(spec), "-o", str(tmp_path / "out")]) == 1
    assert capsys.readouterr().err.splitlines()[0] == (
        f"{spec}:4:22: error: the import binds 'E', a name the generated app uses; import it under another name, e.g. 'from math import e as E_'"
    )
