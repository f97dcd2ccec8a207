"""A generated app.py reads like its spec (issue 11, item 4).

No getter or setter methods (the runtime resolves ``bind:`` paths itself, ``q[2]`` included),
one-call actions reference the method, generated methods are named after their element,
variables keep their unit and doc, the author's comments and line breaks survive, long
literals keep their layout, and every example's app is at most twice its spec's lines.
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from ejsgen.cli import load_plan
from ejsgen.generate import render_app
from testkit import EXAMPLES, ROOT, bench_module

#: every example bench/app_lines.py measures (core examples, paper labs, tutorial steps)
SPECS = bench_module("app_lines").example_specs()


def _id(p: Path) -> str:
    return str(p.relative_to(EXAMPLES)).removesuffix(".ejs.yaml")


def _app(name: str) -> str:
    return render_app(load_plan(EXAMPLES / f"{name}.ejs.yaml"))


def _methods(text: str) -> dict[str, ast.FunctionDef]:
    model = next(n for n in ast.parse(text).body if isinstance(n, ast.ClassDef) and n.name == "Model")
    return {f.name: f for f in model.body if isinstance(f, ast.FunctionDef)}


@pytest.mark.parametrize("spec", SPECS, ids=_id)
def test_app_is_at_most_twice_its_spec(spec: Path) -> None:
    n_spec = len(spec.read_text(encoding="utf-8").splitlines())
    n_app = len(render_app(load_plan(spec)).splitlines()) - 2  # the 2 lines of every app's check for its ejsrl folder
    assert n_app / n_spec <= 2.0, f"{_id(spec)}: app.py has {n_app} lines for a {n_spec}-line spec"


@pytest.mark.parametrize("spec", SPECS, ids=_id)
def test_no_getters_setters_or_counter_names(spec: Path) -> None:
    methods = _methods(render_app(load_plan(spec)))
    assert not [m for m in methods if re.match(r"_(get|set)_", m)], "bind targets need no getter/setter methods"
    assert not [m for m in methods if re.search(r"(view|scene|ode)\d", m)], f"methods named by counters: {sorted(methods)}"
    assert not [m for m, f in methods.items() if "value" in [a.arg for a in f.args.args]]


def test_bind_paths_with_an_index_are_read_and_written_by_the_runtime() -> None:
    """The kinematics lab's joint sliders bind q_deg[0]..q_deg[5]: moving one moves that joint only."""
    from ejsrl.view.elements import Control

    text = _app("paper/six_axis_kinematics")
    assert "E.Slider(bind='q_deg[2]'" in text
    namespace: dict = {"__name__": "kinematics_app"}
    exec(compile(text, "app.py", "exec"), namespace)  # noqa: S102 - our own generated code
    sys.modules.setdefault("kinematics_app", type(sys)("kinematics_app"))
    model = namespace["Model"]()
    sliders = {c.bind: c for c in _controls(namespace["VIEW"]) if isinstance(c, Control)}
    q3 = sliders["q_deg[2]"]
    assert q3.get(model) == pytest.approx(35.0)
    before = model.q_deg.copy()
    q3.set(model, -10.0)
    assert model.q_deg[2] == -10.0
    assert np.array_equal(np.delete(model.q_deg, 2), np.delete(before, 2))


def _controls(items: list) -> list:
    out = []
    for item in items:
        out.append(item)
        out += _controls(getattr(item, "children", []) or [])
        for _, kids in getattr(item, "tabs", []) or []:
            out += _controls(kids)
    return out


def test_a_one_call_action_is_the_method_itself_and_other_code_a_named_method() -> None:
    text = _app("bouncing_ball")
    assert "on_change=Model.initialize" in text  # on_change: "initialize()"
    kin = _app("paper/six_axis_kinematics")
    assert "on_change=Model.joints_moved" in kin and "on_change=Model.target_from_gizmo" in kin
    assert "action=Model._button_solve_and_move" in kin  # "solve_and_move()\nplay()": two calls
    body = _methods(kin)["_button_solve_and_move"]
    assert [ast.unparse(s) for s in body.body] == ["self.solve_and_move()", "self.play()"]


def test_variables_keep_their_unit_and_doc() -> None:
    text = _app("pendulum")
    assert "self.theta = 1.0  # rad: angle from the vertical" in text
    assert "self.E = 0.0  # J/kg: energy per unit mass" in text


def test_the_authors_comments_line_breaks_and_layout_survive(tmp_path: Path) -> None:
    spec = tmp_path / "c.ejs.yaml"
    spec.write_text(
        "ejs: 1\ntitle: C\nmodel:\n  variables:\n    t: 0.0\n    x: 1.0\n    v: 0.0\n"
        "  init: |\n    # start at rest\n    x = 1.0\n\n    v = (x\n         + 2)  # a sum over two lines\n"
        "  custom: |\n    # kick it\n    def kick(dv=1.0):\n        v = v + dv  # more speed\n"
        "view: []\n",
        encoding="utf-8",
    )
    text = render_app(load_plan(spec))
    assert "        # start at rest\n        self.x = 1.0\n\n        self.v = (self.x\n                  + 2)  # a sum over two lines\n" in text  # still aligned under x
    assert "    # kick it\n    def kick(self, dv=1.0):\n        self.v = self.v + dv  # more speed\n" in text


def test_a_long_literal_keeps_the_authors_layout() -> None:
    """The kinematics lab's robot, a DH table of six links, is one row per link as in the spec."""
    text = _app("paper/six_axis_kinematics")
    declare = text[text.index("def _declare") : text.index("def _init")]
    assert "        self.robot = Robot([\n            RevoluteDH(d=self.L1, a=0.0, alpha=-pi/2, offset=pi/2, qlim=[-pi, pi]),\n" in declare
    robot = declare[declare.index("self.robot = ") : declare.index('name="six-axis arm")')]
    assert len(robot.splitlines()) == 8 and max(len(line) for line in robot.splitlines()) <= 100


def test_spec_lines_are_compact_and_still_point_into_the_spec() -> None:
    """Runs of lines: one entry per block of code; an error on any line maps to its spec line."""
    spec = EXAMPLES / "pendulum.ejs.yaml"
    text = render_app(load_plan(spec))
    namespace: dict = {"__name__": "spec_lines_check"}
    exec(compile(text, "app.py", "exec"), namespace)  # noqa: S102 - our own generated code
    table = namespace["Model"].SPEC_LINES
    spec_lines = spec.read_text().splitlines()
    lines = text.splitlines()
    for app_line, (line, col) in table.items():
        code = lines[app_line - 1].strip()
        if code.startswith(("self.", "def ", "return [self.")) and "=" in spec_lines[line - 1]:
            assert spec_lines[line - 1].strip().split("=")[0].strip().split("(")[0].split()[-1] in code, (app_line, code, spec_lines[line - 1])
    assert sum(1 for line in lines if "SPEC_LINES" in line) == 1
    assert len(table) >= 15


def test_the_benchmark_script_prints_every_example() -> None:
    import subprocess

    r = subprocess.run([sys.executable, "-P", str(ROOT / "bench" / "app_lines.py")], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert all(_id(p) in r.stdout for p in SPECS)
