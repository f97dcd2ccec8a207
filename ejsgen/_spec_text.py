"""The view's data and text elements: ``table`` (variables or an array, with units) and
``console`` (what the spec's code prints), as pydantic models of the language.

Registered in ``ejsgen.spec.GUI_ELEMENT_MODELS``; compiled by ``ejsgen._view_compile_text``;
shown by ``ejsrl.view._table`` and ``ejsrl.view._console``.
"""

from __future__ import annotations

from typing import Union

from pydantic import Field

from ejsgen.spec import Strict

__all__ = ["TableRowEl", "TableEl", "ConsoleEl"]


class TableRowEl(Strict):
    """One row of a table of values: a label, a value and its unit."""

    value: Union[float, int, str]
    """Expression giving the value (a number, text, or a short array)."""
    label: str | None = None
    """The row's name (default: the expression)."""
    unit: str | None = None
    """The value's unit (default: the variable's unit, when the value is one variable)."""
    format: str | None = None
    """Python format of this row's numbers, e.g. '.3e' (default: the table's)."""


class TableEl(Strict):
    """A table updated every frame: rows of variables (name, value, unit), or an array with column headers."""

    title: str | None = None
    """Caption above the table (plain text)."""
    rows: list[Union[str, TableRowEl]] | None = None
    """The rows: each a variable or expression (its unit from the variable's unit:), or {value, label, unit, format}."""
    data: str | None = None
    """Expression giving an array shown as a table: N values (1-D) or N rows of M columns (2-D)."""
    columns: list[str] | None = None
    """With data: the column headers, one per column (default: 0, 1, ...)."""
    units: list[str] | None = None
    """With data: the unit of each column, shown under its header ('' for none)."""
    format: str = ".6g"
    """Python format of the numbers, as in {x:.6g}: '.3f', '.2e', 'd'..."""
    max_rows: int = Field(default=100, ge=1, le=10000)
    """With data: most rows shown (the first ones; a last line says how many more there are)."""
    # one of rows and data, and columns/units only with data: checked by the compiler, at the key


class ConsoleEl(Strict):
    """What the spec's code prints (print(...) in init, evolution, custom code and actions), per browser tab, with a Clear button."""

    label: str = "Console"
    """Title above the lines."""
    lines: int = Field(default=200, ge=1, le=2000)
    """Most lines shown (the last ones printed)."""
    height: int = Field(default=160, ge=40, le=2000)
    """Height of the box in pixels (it scrolls; it starts at the newest line)."""
