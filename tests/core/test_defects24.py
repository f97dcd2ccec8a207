"""Issue #24, item 7: the small defects new authors met, each as the author meets it.

- ``start_program(name)`` from ``init`` (or from a custom function ``init`` calls) starts
  the program, and again after every reset;
- ``x^2`` is refused when the spec is built, at the ``^``, with "did you mean x**2";
- a variable named after a prelude name (``e`` for a restitution) is refused with the
  reason and a name to use instead;
- a local of an ODE page's ``preliminary`` is seen by that page's rates; used anywhere
  else, the error says where it is visible and how to share it;
- every public function of ``ejsrl.vision`` is in the language reference, with its
  signature and the first line of its docstring.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from ejsgen.errors import SpecErrors
from ejsrl.app import load_app
from testkit import ROOT

LANGUAGE = ROOT / "specs" / "language.md"


def build_text(tmp_path: Path, text: str, name: str = "lab") -> Path:
    from ejsgen.cli import build

    spec = tmp_path / f"{name}.ejs.yaml"
    spec.write_text(text, encoding="utf-8")
    return build(spec, tmp_path / name)


def build_errors(tmp_path: Path, text: str, name: str = "bad") -> list[str]:
    """The build's error lines (``FILE:LINE:COL: error: message; hint``), the spec's folder left out."""
    with pytest.raises(SpecErrors) as info:
        build_text(tmp_path, text, name)
    return [str(e).replace(f"{tmp_path}/", "") for e in info.value.errors]


def position(text: str, line_text: str, needle: str) -> tuple[int, int]:
    """1-based (line, column) of ``needle`` in the first line of ``text`` holding ``line_text``."""
    for i, line in enumerate(text.splitlines(), start=1):
        if line_text in line:
            return i, line.index(needle, line.index(line_text)) + 1
    raise AssertionError(f"{line_text!r} not in the spec")


# -- 1. start_program() from init ---------------------------------------------------------------

PROGRAM = """\
ejs: 1
title: A program started by init
imports:
  - from ejsrl.robotics import models
model:
  variables:
    t: 0.0
    dt: 0.01
    arm: {{expr: "models.planar(2)"}}
    q: [0.0, 0.0]
    stage: 0
    t_arrived: -1.0
  init: |
    {start}
  evolution:
    - code: |
        t = t + dt
  custom: |
    def begin():
        start_program('go')
  programs:
    go:
      robot: arm
      q: q
      code: |
        stage = 1
        move_j([1.0, -0.5], time=1.0)
        t_arrived = t
        stage = 2
view:
  - button: {{label: Halt, action: "stop_program('go')"}}
"""


@pytest.mark.parametrize("start", ["start_program('go')", "begin()"], ids=["in-init", "from-a-custom-function"])
def test_start_program_from_init_starts_it(tmp_path: Path, start: str) -> None:
    app = load_app(build_text(tmp_path, PROGRAM.format(start=start)))
    assert app.error is None
    assert app.model.stage == 1  # the statements before the first move ran at once
    assert app.model._ejs_program_status("go").startswith("program 'go': running")
    for _ in range(150):
        app.step_once()
    assert app.model.stage == 2
    assert np.allclose(app.model.q, [1.0, -0.5])  # the move took its second of simulated time
    assert app.model.t_arrived == pytest.approx(1.0, abs=0.011)
    # a reset stops the program, then init runs and starts it again from its first line
    app.reset()
    assert np.allclose(app.model.q, [0.0, 0.0]) and app.model.t == 0.0
    assert app.model.stage == 1
    assert app.model._ejs_program_status("go").startswith("program 'go': running")
    for _ in range(150):
        app.step_once()
    assert app.model.stage == 2


def test_an_autostart_program_started_by_init_runs_once(tmp_path: Path) -> None:
    text = PROGRAM.format(start="start_program('go')").replace("      q: q\n", "      q: q\n      autostart: true\n")
    text = text.replace("        stage = 1\n", "        stage = stage + 1\n")
    app = load_app(build_text(tmp_path, text))
    assert app.model.stage == 1  # started by init, not started a second time by autostart


# -- 4. ^ is refused: did you mean ** ------------------------------------------------------------

CARET = """\
ejs: 1
title: Caret
model:
  variables:
    t: 0.0
    dt: 0.01
    x: 1.0
    v: 0.0
    k: 2.0
    E: 0.0
  evolution:
    - ode:
        equations:
          x: v
          v: -k*x^3
  fixed_relations: |
    E = 0.5*v^2 + (k*x) ^ 4/4
view:
  - label: {text: "x squared: {x^2:.3f}"}
"""


def test_caret_is_refused_at_the_operator_with_the_power_to_write(tmp_path: Path) -> None:
    errors = build_errors(tmp_path, CARET)
    name = "bad.ejs.yaml"
    want = [
        (position(CARET, "v: -k*x^3", "^"), "x**3"),
        (position(CARET, "E = 0.5*v^2", "^"), "v**2"),
        (position(CARET, "(k*x) ^ 4", "^ 4"), "(k*x) ** 4"),
        (position(CARET, "x squared", "^"), "x**2"),
    ]
    assert len(errors) == len(want), errors
    for ((line, col), power), err in zip(want, errors):
        assert err.startswith(f"{name}:{line}:{col}: error: '^' is not a power in Python"), err
        assert f"did you mean '{power}'" in err


def test_caret_assignment_is_refused_too_and_cli_says_where(tmp_path: Path, capsys) -> None:
    from ejsgen.cli import main

    text = CARET.replace("E = 0.5*v^2 + (k*x) ^ 4/4", "E = 0.5*v**2\n    E ^= 2").replace("-k*x^3", "-k*x**3").replace("{x^2:.3f}", "{x:.3f}")
    spec = tmp_path / "aug.ejs.yaml"
    spec.write_text(text, encoding="utf-8")
    assert main(["validate", str(spec)]) == 1
    err = capsys.readouterr().err
    line, col = position(text, "E ^= 2", "^")
    assert f"aug.ejs.yaml:{line}:{col}: error: '^=' is not a power in Python" in err
    assert "did you mean 'E **= 2'" in err
    # written as a power, the same spec builds and runs: E = (0.5 v^2)^2 with v = 0 at the start
    fixed = text.replace("E ^= 2", "E **= 2")
    app = load_app(build_text(tmp_path, fixed, "fixed"))
    app.model.v = 2.0
    app.model._fixed_relations()
    assert app.model.E == 4.0


# -- 5. a prelude name as a variable: refused with the reason and names to use -------------------

BOUNCE = """\
ejs: 1
title: Bounce
model:
  variables:
    t: 0.0
    dt: 0.01
    y: 1.0
    v: 0.0
    e: 0.8
  evolution:
    - ode:
        equations:
          y: v
          v: -9.81
        events:
          - {name: floor, when: y, direction: down, action: "v = -e*v"}
view:
  - slider: {bind: e, min: 0, max: 1}
"""


@pytest.mark.parametrize(
    ("name", "meaning", "suggested"),
    [("e", "Euler's number", ["e_", "restitution"]), ("log", "the function log() of Python's math module", ["log_", "history"])],
)
def test_a_prelude_name_as_a_variable_says_why_and_what_to_call_it(tmp_path: Path, name: str, meaning: str, suggested: list[str]) -> None:
    text = BOUNCE.replace("    e: 0.8", f"    {name}: 0.8").replace("-e*v", f"-{name}*v").replace("bind: e,", f"bind: {name},")
    errors = build_errors(tmp_path, text)
    line, col = position(text, f"    {name}: 0.8", name)
    assert errors[0].startswith(f"bad.ejs.yaml:{line}:{col}: error: '{name}' is a prelude name ({meaning}")
    assert f"every code block and expression of the spec reads '{name}' as the prelude's" in errors[0]
    for s in suggested:
        assert f"'{s}'" in errors[0]
    # the first name suggested builds, and the ball bounces with that restitution
    fixed = text.replace(f"    {name}: 0.8", f"    {suggested[0]}: 0.8").replace(f"-{name}*v", f"-{suggested[0]}*v").replace(f"bind: {name},", f"bind: {suggested[0]},")
    app = load_app(build_text(tmp_path, fixed, "fixed"))
    v_hit = -np.sqrt(2 * 9.81)
    for _ in range(60):
        app.step_once()
    assert app.model.v == pytest.approx(-0.8 * v_hit - 9.81 * (app.model.t - np.sqrt(2 / 9.81)), abs=1e-6)


# -- 6. preliminary's locals: seen by its rates; elsewhere, the error says where they are visible --

PRELIMINARY = """\
ejs: 1
title: Preliminary locals
model:
  variables:
    t: 0.0
    dt: 0.01
    x: 1.0
    v: 0.0
    w: 2.0
    calls: 0
  evolution:
    - ode:
        preliminary: |
          acc = -w**2*x
          calls = calls + 1
        equations:
          x: v
          v: acc
view:
  - label: {text: "{x:.3f}"}
"""


def test_preliminary_locals_are_seen_by_the_rates_of_their_page(tmp_path: Path) -> None:
    app = load_app(build_text(tmp_path, PRELIMINARY))
    for _ in range(100):
        app.step_once()
    assert app.model.t == 1.0
    assert app.model.x == pytest.approx(np.cos(2.0), abs=1e-7)  # x'' = -w^2 x, w = 2
    assert app.model.v == pytest.approx(-2.0 * np.sin(2.0), abs=1e-7)
    assert app.model.calls == 400  # once per rate evaluation: 4 per RK4 step


def test_a_preliminary_local_used_elsewhere_says_where_it_is_visible(tmp_path: Path) -> None:
    text = PRELIMINARY.replace("view:\n", "  fixed_relations: |\n    E = 0.5*v**2 - acc*x/2\nview:\n").replace("    calls: 0\n", "    calls: 0\n    E: 0.0\n")
    errors = build_errors(tmp_path, text)
    line, col = position(text, "E = 0.5*v**2 - acc", "acc")
    pre_line, _ = position(text, "preliminary: |", "preliminary")
    assert errors == [
        f"bad.ejs.yaml:{line}:{col}: error: unknown name 'acc' here: it is a local of the preliminary code of the ODE page "
        f"'page 1' (line {pre_line}), seen only by that page's rates; to use it elsewhere, make it a model variable: "
        "declare 'acc: 0.0' under model.variables (the preliminary code then sets it for everyone)"
    ]
    # declared as the hint says, it builds, and the fixed relations see the value preliminary set
    declared = text.replace("    E: 0.0\n", "    E: 0.0\n    acc: 0.0\n")
    app = load_app(build_text(tmp_path, declared, "declared"))
    app.step_once()
    assert app.model.acc == pytest.approx(-4.0 * app.model.x, rel=1e-3)  # the last rate evaluation's


# -- 7. the vision API in the language reference --------------------------------------------------


def _vision_section() -> str:
    text = LANGUAGE.read_text(encoding="utf-8")
    m = re.search(r"<!-- generated: vision -->\n(.*?)<!-- end generated -->", text, re.S)
    assert m, "specs/language.md has no vision section"
    return m.group(1)


def test_every_public_vision_name_is_in_the_reference_with_its_signature_and_first_line() -> None:
    import inspect

    import ejsrl.vision as vision

    section = _vision_section()
    rows = {m.group(1): m.group(2) for m in re.finditer(r"^\| `([^`]+)` \| (.*) \|$", section, re.M)}
    by_name = {key.split("(")[0]: (key, what) for key, what in rows.items()}
    for name in vision.__all__:
        assert name in by_name, f"ejsrl.vision.{name} is missing from the language reference"
        obj = getattr(vision, name)
        if not callable(obj):
            continue
        sig = inspect.signature(obj)
        params = [p.replace(annotation=inspect.Parameter.empty) for p in sig.parameters.values() if p.name != "self"]
        want = name + str(sig.replace(parameters=params, return_annotation=inspect.Signature.empty))
        key, what = by_name[name]
        assert key == want, f"{name}: the reference says {key}, the code {want}"
        first = " ".join((inspect.getdoc(obj) or "").split("\n\n")[0].split()).replace("``", "`").replace("|", "\\|")
        assert what == first, f"{name}: the reference says {what!r}, the docstring {first!r}"
    # what the labs needed, found by the name a user searches for
    for name in ("color_segment", "blobs", "centroid", "connected_components", "draw_points", "threshold", "threshold_otsu", "threshold_adaptive", "color_mask"):
        assert name in by_name


def test_ejsgen_docs_prints_the_vision_functions(capsys) -> None:
    from ejsgen.cli import main

    assert main(["docs"]) == 0
    out = capsys.readouterr().out
    assert "## The vision library" in out
    assert "| `color_segment(img, color, *, min_saturation=80, min_value=50, min_area=10)` |" in out


def test_preliminary_pages_share_their_locals_and_an_event_is_told_it_cannot(tmp_path: Path) -> None:
    text = PRELIMINARY.replace(
        "        preliminary: |\n          acc = -w**2*x\n          calls = calls + 1\n",
        "        preliminary:\n          - {name: force, code: \"f = -w**2*x\"}\n          - {name: accel, code: \"acc = f / 1.0\"}\n",
    )
    app = load_app(build_text(tmp_path, text))
    for _ in range(100):
        app.step_once()
    assert app.model.x == pytest.approx(np.cos(2.0), abs=1e-7)
    bad = text.replace("          v: acc\n", "          v: acc\n        events:\n          - {name: turn, when: \"acc\", action: \"calls = calls + 1\"}\n")
    errors = build_errors(tmp_path, bad)
    line, col = position(bad, "when: \"acc\"", "acc")
    assert len(errors) == 1 and errors[0].startswith(f"bad.ejs.yaml:{line}:{col}: error: unknown name 'acc' here: it is a local of the preliminary code")
