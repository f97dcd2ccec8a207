"""Numbers in a spec follow YAML 1.2's core schema (issue #24's trial): ``1e5``, ``3e8``,
``1E-3`` are floats, not text that fails at run time ("unsupported operand type(s) for /:
'float' and 'str'"). Every form loads as Python's own ``float``/``int`` parses it; quoted
and explicitly tagged text stays text; an int with a leading zero (8 by YAML 1.1, 10 by
YAML 1.2) is a build error at its line and column; and a lab whose variables are written
in exponent form builds and runs with their values."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import pytest

from ejsgen.errors import SpecError
from ejsgen.yamlload import load_yaml
from testkit import run_app

#: (as written, what Python reads it as): the reference is Python's own parser
FLOATS = ["1e5", "1E-3", "1e-3", "3e8", "1.0e3", "1.0E+3", ".5", "-.5", "+1.0e3", "1.", "2.0e-5", "3.0E+5",
          "-1e-300", "6.02214076e23", "1_000.5", "0.5"]
INTS = [("42", 42), ("-7", -7), ("+3", 3), ("0", 0), ("0x1F", 31), ("0o17", 15), ("0b101", 5), ("1_000", 1000)]


def load(text: str) -> dict:
    return load_yaml("n.ejs.yaml", text=text).data


@pytest.mark.parametrize("text", FLOATS)
def test_float_forms_are_floats(text: str) -> None:
    data = load(f"a: {text}\nb: [{text}, 1]\nc: {{value: {text}}}\n")
    want = float(text)
    for got in (data["a"], data["b"][0], data["c"]["value"]):
        assert type(got) is float and got == want, (text, got)


@pytest.mark.parametrize(("text", "want"), INTS)
def test_int_forms_are_ints(text: str, want: int) -> None:
    data = load(f"a: {text}\n")
    assert type(data["a"]) is int and data["a"] == want


def test_infinities_and_nan() -> None:
    data = load("a: .inf\nb: -.inf\nc: +.Inf\nd: .nan\ne: .NaN\nf: -.INF\n")
    assert data["a"] == math.inf and data["b"] == -math.inf and data["c"] == math.inf and data["f"] == -math.inf
    assert math.isnan(data["d"]) and math.isnan(data["e"])


def test_quoted_and_tagged_text_stays_text() -> None:
    data = load("a: '1e5'\nb: \"3e8\"\nc: !!str 1e5\nd: 1e5 Pa\ne: e5\nf: 1e\ng: 1.2.3\nh: '010'\n")
    assert data == {"a": "1e5", "b": "3e8", "c": "1e5", "d": "1e5 Pa", "e": "e5", "f": "1e", "g": "1.2.3", "h": "010"}


def test_base_sixty_is_text_as_in_yaml_1_2() -> None:
    # YAML 1.1 read 1:30 as 90 and 16:9 as 969
    assert load("a: 1:30\nb: 16:9\n") == {"a": "1:30", "b": "16:9"}


def test_booleans_and_nulls_unchanged() -> None:
    assert load("a: true\nb: False\nc: off\nd: null\ne: ~\n") == {"a": True, "b": False, "c": "off", "d": None, "e": None}


@pytest.mark.parametrize("text", ["010", "-007", "00"])
def test_leading_zero_int_is_a_build_error(text: str) -> None:
    with pytest.raises(SpecError) as info:
        load(f"title: x\nn:   {text}\n")
    err = info.value
    assert str(err).startswith("n.ejs.yaml:2:6: error:")
    assert "ambiguous" in str(err) and "0o" in str(err)


SPEC = """\
ejs: 1
title: Exponent numbers
model:
  variables:
    t: 0.0
    dt: 0.5
    p: {value: 1e5, unit: Pa}
    c: 3e8
    a: 1e-3
    d: 1.0e3
    ratio: 0.0
  evolution:
    - code: |
        t = t + dt
  fixed_relations: |
    ratio = p / c + a * d
view:
  - label: {text: "{ratio}"}
  - slider: {bind: a, min: 1e-4, max: 1E-2, step: 1e-4, label: a}
simulation:
  fps: 2.5e1
  steps_per_display: 2
"""


def test_lab_with_exponent_numbers_builds_and_runs(tmp_path: Path) -> None:
    from ejsgen.cli import build

    spec = tmp_path / "expo.ejs.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    app = build(spec, tmp_path / "app")
    text = (app / "app.py").read_text()
    # a view property and a simulation setting in exponent form are the numbers too
    assert "min=0.0001, max=0.01, step=0.0001" in text and "fps=25.0" in text
    r = run_app(app, "--headless", "--duration", "1", "--csv", "-", "--vars", "p,c,a,d,ratio", timeout=60)
    assert r.returncode == 0, r.stderr
    rows = list(csv.reader(io.StringIO(r.stdout)))
    assert rows[0] == ["p", "c", "a", "d", "ratio"]
    p, c, a, d, ratio = map(float, rows[-1])
    assert (p, c, a, d) == (100000.0, 300000000.0, 0.001, 1000.0)
    assert ratio == 100000.0 / 300000000.0 + 0.001 * 1000.0
