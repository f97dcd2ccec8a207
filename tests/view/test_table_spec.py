"""What a build says about a ``table`` or ``console`` that cannot work: each error at the
spec's FILE:LINE:COL, in plain words, with the fix."""

from __future__ import annotations

from pathlib import Path

import pytest

from ejsgen.cli import main

SPEC = """\
ejs: 1
title: Tables
model:
  variables:
    t: 0.0
    stiffness: {{value: 2.0, unit: N/m}}
    data: [[0, 1], [1, 2], [2, 3]]
    v: [1.0, 2.0]
view:
  - {element}
"""


def _first_error(tmp_path: Path, element: str, capsys: pytest.CaptureFixture[str]) -> str:
    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(SPEC.format(element=element))
    status = main(["build", str(spec), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 1, err
    return err.splitlines()[0].replace(f"{spec}:", "")


def test_a_row_naming_no_variable_suggests_the_closest(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    got = _first_error(tmp_path, "table: {rows: [stiffnes]}", capsys)
    assert got == "10:20: error: unknown name 'stiffnes'; did you mean 'stiffness'?"


def test_headers_must_match_the_arrays_columns(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    got = _first_error(tmp_path, "table: {data: data, columns: [t, y, z]}", capsys)
    assert got == "10:34: error: 3 column headers for 'data', which has 2 columns (shape (3, 2)); give one header per column"


def test_units_one_per_column(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    got = _first_error(tmp_path, "table: {data: v, units: [m, s]}", capsys)
    assert got == "10:29: error: 2 units for 1 column; give one unit per column ('' for none)"


def test_a_number_is_no_table(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    got = _first_error(tmp_path, "table: {data: 't * 2'}", capsys)
    assert got.startswith("10:19: error: a table's data is a 1-D or 2-D array, but 't * 2' is one number")


def test_a_format_that_formats_no_number(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    got = _first_error(tmp_path, "table: {rows: [stiffness], format: '%.2f'}", capsys)
    assert got.startswith("10:40: error: '%.2f' is not a number format")
    assert got.endswith("write a Python format such as '.3f', '.4g', '.2e' or 'd'")


def test_rows_and_data_together_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    got = _first_error(tmp_path, "table: {rows: [stiffness], data: data}", capsys)
    assert got == "10:32: error: a table shows either rows: (variables) or data: (an array expression), not both; e.g. rows: [k, b], or data: np.c_[t_data, y_data]"
    got = _first_error(tmp_path, "table: {rows: [stiffness], units: [m]}", capsys)
    assert got.startswith("10:32: error: units: goes with data:; a row's unit is its variable's unit:")


def test_a_console_too_tall(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    got = _first_error(tmp_path, "console: {height: 5000}", capsys)
    assert got.startswith("10:23: error:") and "2000" in got


def test_print_in_code_is_the_models_which_also_writes_to_the_console(tmp_path: Path) -> None:
    spec = tmp_path / "p.ejs.yaml"
    spec.write_text("ejs: 1\ntitle: P\nmodel:\n  variables: {t: 0.0}\n  init: |\n    print('hi', t)\nview:\n  - console: {}\n")
    assert main(["build", str(spec), "-o", str(tmp_path / "out")]) == 0
    lines = [ln.strip() for ln in (tmp_path / "out" / "app.py").read_text().splitlines()]
    assert "self.print('hi', self.t)" in lines
