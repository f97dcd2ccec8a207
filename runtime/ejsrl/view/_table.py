"""The ``table`` element in the control panel: an HTML table rebuilt when its values change.

Every cell is formatted here (:func:`cell_text`) and escaped (``html.escape``) before it is
put into the page: a string variable holding ``<img onerror=...>`` (text a user typed)
shows as those characters. The panel calls :meth:`TableBinding.refresh` every frame with
the model lock held; the table is sent only when its HTML differs from the one shown.
"""

from __future__ import annotations

import html
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ejsrl.view._wire import set_prop
from ejsrl.view.elements import format_value
from ejsrl.view.elements_text import Table

__all__ = ["TableBinding", "cell_text", "table_html", "table_cells", "table_values", "same_values"]

#: an array in one cell is written out up to this many numbers (else its shape is shown)
CELL_ARRAY_MAX = 12
_MISSING = "—"  # a value that could not be read (the simulation is paused on an error)

_TABLE = ('<table style="width:100%;border-collapse:collapse;font-size:0.8rem;margin:2px 0 6px 0" '
          'class="ejs-table">')
_CAPTION = '<caption style="caption-side:top;text-align:left;font-weight:600;padding:0 0 2px 2px">{}</caption>'
_TH = '<th style="text-align:{align};padding:2px 6px;border-bottom:1px solid #ced4da;font-weight:600">{}</th>'
_TD = '<td style="text-align:{align};padding:1px 6px;border-bottom:1px solid #f1f3f5{mono}">{}</td>'
_MONO = ";font-family:monospace;font-variant-numeric:tabular-nums;white-space:pre"
_UNIT = '<br><span style="font-weight:400;opacity:0.7">{}</span>'


def cell_text(value: Any, spec: str = ".6g") -> str:
    """A value as a table shows it (not escaped): a number in ``spec`` (a format that does not
    fit it, 'd' for 2.5, falls back to '.6g'), a boolean as true/false, text as it is, a
    short array as ``[a b c]``, a longer one by its shape; None as a dash."""
    if value is None:
        return _MISSING
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, str):
        return value
    if isinstance(value, (int, float, np.integer, np.floating)):
        return _number(value, spec)
    if isinstance(value, (list, tuple, np.ndarray)):
        try:
            arr = np.asarray(value)
        except Exception:  # noqa: BLE001 - ragged lists: shown as Python writes them
            return str(value)
        if arr.ndim == 0:
            return cell_text(arr.item(), spec)
        if arr.size > CELL_ARRAY_MAX or arr.dtype.kind not in "biuf":
            return f"array {tuple(arr.shape)}" if arr.dtype.kind in "biufc" else str(value)
        try:
            return format_value(arr, spec).replace("\n", " ")
        except ValueError:
            return format_value(arr, ".6g").replace("\n", " ")
    return str(value)


def _number(x: Any, spec: str) -> str:
    if isinstance(x, (float, np.floating)) and not math.isfinite(float(x)):
        return str(float(x))
    try:
        return format(x, spec)
    except (ValueError, TypeError):
        return format(float(x), ".6g")


def table_values(table: Table, value_of: Callable[[Any, str], Any]) -> list[Any]:
    """What the table shows, read from the model now: each row's value, or the data (an array
    copy, so a later change of the model's array is seen as one). ``value_of(prop, where)``
    reads a property (the app's ``safe_value``: None after an error)."""
    if table.data is None:
        return [value_of(r.value, r.where or table.where) for r in table.rows]
    value = value_of(table.data, table.where)
    if isinstance(value, np.ndarray):
        value = value.copy()
    return [value]


def same_values(a: list[Any] | None, b: list[Any]) -> bool:
    """Whether two readings of a table's values are the same (so its HTML would be too)."""
    if a is None or len(a) != len(b):
        return False
    for x, y in zip(a, b):
        if type(x) is not type(y):
            return False
        if isinstance(x, np.ndarray):
            if x.shape != y.shape or x.dtype != y.dtype or not np.array_equal(x, y, equal_nan=x.dtype.kind in "fc"):
                return False
            continue
        try:
            if not bool(x == y) and not (x != x and y != y):  # nan == nan here
                return False
        except Exception:  # noqa: BLE001 - values that cannot be compared: shown again
            return False
    return True


def table_cells(table: Table, value_of: Callable[[Any, str], Any], values: list[Any] | None = None) -> tuple[list[str], list[str], list[list[str]], int]:
    """The table's (headers, units, rows of cell texts, rows left out) as the model is now
    (``values``: a reading by :func:`table_values`, else one is made)."""
    if values is None:
        values = table_values(table, value_of)
    if table.data is None:
        rows = [[r.label, cell_text(v, r.format or table.format), r.unit] for r, v in zip(table.rows, values)]
        return ["", "value", "unit"], [], rows, 0
    value = values[0]
    if value is None:
        return list(table.columns), list(table.units), [[_MISSING] * max(1, len(table.columns))], 0
    try:
        arr = np.asarray(value)
    except Exception:  # noqa: BLE001
        return list(table.columns), list(table.units), [[f"cannot show {type(value).__name__} as a table"]], 0
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    elif arr.ndim == 1:
        arr = arr.reshape(-1, 1)
    elif arr.ndim > 2:
        return list(table.columns), list(table.units), [[f"cannot show an array of shape {tuple(arr.shape)} as a table"]], 0
    ncols = arr.shape[1]
    headers = list(table.columns) or [str(j) for j in range(ncols)]
    headers += [""] * (ncols - len(headers))
    shown = arr[: table.max_rows]
    rows = [[cell_text(x.item() if hasattr(x, "item") else x, table.format) for x in row] for row in shown]
    return headers, list(table.units), rows, max(0, arr.shape[0] - len(shown))


def table_html(title: str, headers: Sequence[str], units: Sequence[str], rows: Sequence[Sequence[str]], more: int = 0) -> str:
    """The HTML of a table; every text escaped. Numbers are right-aligned in a monospace font."""
    esc = html.escape
    out = [_TABLE]
    if title:
        out.append(_CAPTION.format(esc(title)))
    if any(headers) or any(units):
        out.append("<thead><tr>")
        first = rows[0] if rows else []
        for j, h in enumerate(headers):
            unit = units[j] if j < len(units) else ""
            numeric = j < len(first) and _looks_numeric(first[j])  # a header sits as its column's first cell does
            out.append(_TH.format(esc(h) + (_UNIT.format(esc(unit)) if unit else ""), align="right" if numeric else "left"))
        out.append("</tr></thead>")
    out.append("<tbody>")
    for row in rows:
        out.append("<tr>")
        for j, text in enumerate(row):
            numeric = _looks_numeric(text)
            out.append(_TD.format(esc(text), align="right" if numeric else "left", mono=_MONO if numeric else ""))
        out.append("</tr>")
    if more:
        out.append(f'<tr><td colspan="{max(1, len(headers))}" style="padding:2px 6px;opacity:0.7">… {more} more row{"s" if more > 1 else ""}</td></tr>')
    out.append("</tbody></table>")
    return "".join(out)


def _looks_numeric(text: str) -> bool:
    t = text.strip().lstrip("[").rstrip("]").split(" ")[0]
    try:
        float(t)
        return True
    except ValueError:
        return t in ("nan", "inf", "-inf", _MISSING)


class TableBinding:
    """One ``table`` element of one panel (one browser tab) and its viser HTML handle."""

    def __init__(self, gui: Any, table: Table, value_of: Callable[[Any, str], Any]) -> None:
        self.table = table
        self.values = table_values(table, value_of)
        self.shown = self._html()
        self.handle = gui.add_html(self.shown)

    def _html(self) -> str:
        headers, units, rows, more = table_cells(self.table, lambda p, w: None, self.values)
        return table_html(self.table.title, headers, units, rows, more)

    def refresh(self, value_of: Callable[[Any, str], Any]) -> None:
        """Show the model's values now (the caller holds the model lock); sends only a change.

        The values are compared with the last ones shown first: a frame that changed none of
        them costs a read and a comparison, not the formatting of every cell.
        """
        values = table_values(self.table, value_of)
        if same_values(self.values, values):
            return
        self.values = values
        text = self._html()
        if text != self.shown:
            set_prop(self.handle, "content", text)
            self.shown = text
