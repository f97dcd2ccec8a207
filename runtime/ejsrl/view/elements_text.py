"""The records of the view's data and text elements (re-exported by ``ejsrl.view.elements``).

``Table``: rows of values (``TableRow``: label, value, unit) or an array (``data``) with
column headers and units, formatted with a Python format and updated every frame.
``Console``: the last ``lines`` lines the simulation's code printed (``print`` in a lab
with a console is ``ModelBase.print``), with a Clear button; each browser tab its own.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from ejsrl.view.elements import Element

__all__ = ["TableRow", "Table", "Console"]


@dataclass
class TableRow(Element):
    """One row of a table of values: ``value`` (a constant or ``Dynamic``), its ``label``,
    ``unit`` and ``format`` (a Python format of its numbers; '' for the table's)."""

    value: Any
    label: str = ""
    unit: str = ""
    format: str = ""


@dataclass
class Table(Element):
    """A table: ``rows`` (name, value, unit), or ``data`` (a ``Dynamic`` giving a 1-D array:
    one column, or a 2-D array: rows x columns) under ``columns`` headers with ``units``.

    ``format``: the Python format of the numbers (``".6g"``); ``max_rows``: most rows of
    ``data`` shown (a last line counts the others); ``title``: a caption (plain text).
    """

    rows: list[TableRow] = field(default_factory=list)
    data: Any = None
    columns: Sequence[str] = ()
    units: Sequence[str] = ()
    format: str = ".6g"
    title: str = ""
    max_rows: int = 100


@dataclass
class Console(Element):
    """What the simulation's code prints: the last ``lines`` lines in a box ``height`` pixels
    high under ``label``, newest at the bottom, with a Clear button."""

    label: str = "Console"
    lines: int = 200
    height: int = 160
