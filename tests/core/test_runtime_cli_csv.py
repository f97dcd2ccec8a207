"""The headless command line's variables: `expr:` variables in the default CSV and under
`--set`, text and booleans when named in `--vars`, and values that do not fit refused
with a message (status 2, no traceback)."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np
import pytest

from ejsrl.app import parse_set
from testkit import run_app

SPEC = """\
ejs: 1
title: Variables of every kind
imports:
  - from ejsrl.robotics import models
model:
  variables:
    t: 0.0
    dt: 0.25
    n: {expr: "1 + 2", doc: an integer given by an expression}
    k: {expr: "2 * pi"}
    xs: {expr: "np.arange(n) * 1.5", doc: sized by n}
    label: {expr: "'n = ' + str(n)"}
    arm: {expr: "models.rrr()"}
    on: true
    note: 'a, "quoted" note'
    big: false
    mask: {expr: "xs > 2"}
    total: 0.0
    img: {expr: "np.full((2, 3, 3), 7, dtype=np.uint8)", doc: a tiny camera image}
  evolution:
    - code: |
        t = t + dt
  fixed_relations: |
    total = k + xs.sum()
    big = xs.sum() > 4
view:
  - label: {text: "{total}"}
"""


@pytest.fixture(scope="module")
def app_dir(tmp_path_factory) -> Path:
    from ejsgen.cli import build

    spec = tmp_path_factory.mktemp("kinds") / "kinds.ejs.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    return build(spec, spec.parent / "app")


def headless(app_dir: Path, *args: str) -> tuple[list[str], list[list[str]]]:
    r = run_app(app_dir, "--headless", "--duration", "0.5", "--csv", "-", *args, timeout=60)
    assert r.returncode == 0, r.stderr
    rows = list(csv.reader(io.StringIO(r.stdout)))
    return rows[0], rows[1:]


def test_the_default_csv_has_every_numeric_variable_expr_ones_included(app_dir) -> None:
    header, rows = headless(app_dir)
    assert header == ["t", "dt", "n", "k", "xs[0]", "xs[1]", "xs[2]", "total"]
    assert len(rows) == 3
    assert rows[0] == ["0.0", "0.25", "3", repr(2 * np.pi), "0.0", "1.5", "3.0", repr(2 * np.pi + 4.5)]


def test_set_replaces_an_expr_variable_and_later_expressions_see_it(app_dir) -> None:
    header, rows = headless(app_dir, "--set", "n=5", "--set", "k=1", "--vars", "n,k,xs,label,total")
    assert header == ["n", "k", "xs[0]", "xs[1]", "xs[2]", "xs[3]", "xs[4]", "label", "total"]
    assert rows[0] == ["5", "1.0", "0.0", "1.5", "3.0", "4.5", "6.0", "n = 5", "16.0"]
    header, rows = headless(app_dir, "--set", "xs=[1, 2]", "--set", "label=hello there", "--vars", "xs,label,total")
    assert rows[-1] == ["1.0", "2.0", "hello there", repr(2 * np.pi + 3.0)]


def test_text_and_booleans_named_in_vars_are_written(app_dir) -> None:
    header, rows = headless(app_dir, "--vars", "t,on,note,big,mask", "--set", "on=false")
    assert header == ["t", "on", "note", "big", "mask[0]", "mask[1]", "mask[2]"]
    # booleans as 0/1 (also NumPy's, from a comparison); text as the csv module quotes it
    assert rows[0] == ["0.0", "0", 'a, "quoted" note', "1", "0", "0", "1"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--set", "n=2.5"], "--set n: expected an integer, got '2.5'"),
        (["--set", "k=fast"], "--set k: 'fast' is not a number or a list of numbers"),
        (["--set", "arm=3"], "--set arm: its expression gives a Robot, which cannot be set from the command line"),
        (["--vars", "t,arm"], "--vars: 'arm' holds a Robot; the CSV takes numbers, booleans, text and arrays of numbers"),
    ],
)
def test_values_that_do_not_fit_are_refused_with_a_message(app_dir, args, message) -> None:
    r = run_app(app_dir, "--headless", "--duration", "0.5", "--csv", "-", *args, timeout=60)
    assert r.returncode == 2
    assert f"error: {message}" in r.stderr and "Traceback" not in r.stderr
    assert r.stdout == ""


def test_parse_set_defers_expr_variables_to_their_declared_type() -> None:
    name, value = parse_set("x=2", {"x": "auto"})
    assert name == "x" and callable(value)
    assert value(0.5) == 2.0 and isinstance(value(0.5), float)
    assert value(7) == 2 and isinstance(value(7), int)
    np.testing.assert_array_equal(parse_set("q=[1, 2]", {"q": "auto"})[1](np.zeros(3)), [1.0, 2.0])
    assert parse_set("s=2", {"s": "auto"})[1]("text") == "2"


def test_images_are_left_out_of_the_default_csv_and_written_when_named(app_dir) -> None:
    """A camera image would be hundreds of thousands of columns; named, it is written."""
    header, _ = headless(app_dir)
    assert not any(h.startswith("img") for h in header)
    header, rows = headless(app_dir, "--vars", "t,img")
    assert header[1:] == [f"img[{i}][{j}][{k}]" for i in range(2) for j in range(3) for k in range(3)]
    assert rows[0][1:] == ["7"] * 18


def test_a_model_without_time_writes_no_csv_file(tmp_path) -> None:
    from ejsgen.cli import build

    spec = tmp_path / "still.ejs.yaml"
    spec.write_text("ejs: 1\ntitle: Still\nmodel:\n  variables:\n    a: 1.0\nview:\n  - label: {text: '{a}'}\n")
    out = tmp_path / "out.csv"
    r = run_app(build(spec, tmp_path / "app"), "--headless", "--duration", "1", "--csv", str(out), timeout=60)
    assert r.returncode == 2 and "no independent variable" in r.stderr
    assert not out.exists()
