"""Compile the view's data and text elements: ``table`` and ``console``.

A table of ``rows`` becomes ``E.Table(rows=[E.TableRow(value=E.Dynamic("k"), label="k",
unit="N/m"), ...])``: each row's unit is the variable's ``unit:`` unless the row gives its
own. A table of ``data`` becomes ``E.Table(data=E.Dynamic(...), columns=[...], units=[...])``;
an array whose shape is known at build time must be 1-D or 2-D with as many columns as
headers. Formats are checked by formatting a number with them. ``print`` in spec code is
the model's (:meth:`ejsrl.sim.model.ModelBase.print`, a prelude control), which also writes
to the simulation's console log, shown by a ``console``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ejsgen._shapes import infer_shape
from ejsgen.errors import SpecError
from ejsgen.plan import Call
from ejsgen.validate import ViewItem
from ejsgen.yamlload import Path_

if TYPE_CHECKING:
    from ejsgen._view_compile import ViewCompiler

__all__ = ["compile_table", "compile_console"]

def _check_format(vc: ViewCompiler, spec: str, path: Path_) -> bool:
    """Whether ``spec`` formats a number (else an error at ``path``, with an example)."""
    try:
        format(1.5, spec)
    except ValueError:
        try:
            format(2, spec)  # 'd' suits whole numbers only: allowed, floats fall back to .6g
        except ValueError as exc:
            vc.c.errors.append(SpecError(vc.c.loc(path), f"'{spec}' is not a number format ({exc})", "write a Python format such as '.3f', '.4g', '.2e' or 'd'"))
            return False
    return True


def _row(vc: ViewCompiler, row: Any, path: Path_, i: int, table_format: str) -> Call | None:
    if isinstance(row, str):
        text, label, unit, fmt, vpath = row, row.strip(), None, None, path
    else:
        text, vpath = row.value, path + ("value",)
        label = row.label if row.label is not None else str(row.value).strip()
        unit, fmt = row.unit, row.format
    if unit is None:
        unit = vc._unit_of(text)
    if fmt is not None and not _check_format(vc, fmt, path + ("format",)):
        fmt = None
    value = vc.number(text, vpath, "", f"row {i + 1} of the table")
    if value is None:
        return None
    kw: dict[str, Any] = {"value": value, "label": label}
    if unit:
        kw["unit"] = unit
    if fmt:
        kw["format"] = fmt
    return Call("E.TableRow", [], kw)


def compile_table(vc: ViewCompiler, item: ViewItem, n: int) -> Call | None:
    """``E.Table(...)`` for a ``table`` element."""
    p, path = item.props, item.path
    c = vc.c
    if (p.rows is None) == (p.data is None):
        where = c.doc.key_loc(path + ("data",)) if p.data is not None else c.loc(path)
        c.errors.append(SpecError(where, "a table shows either rows: (variables) or data: (an array expression), not both" if p.data is not None else "a table needs rows: (variables) or data: (an array expression)", "e.g. rows: [k, b], or data: np.c_[t_data, y_data]"))
        return None
    if p.rows is not None and (p.columns is not None or p.units is not None):
        key = "columns" if p.columns is not None else "units"
        c.errors.append(SpecError(c.doc.key_loc(path + (key,)), f"{key}: goes with data:; a row's unit is its variable's unit:", "or give a row as {value: ..., label: ..., unit: ...}"))
        return None
    kw: dict[str, Any] = {}
    if p.title:
        kw["title"] = p.title
    if p.rows is not None:
        if not p.rows:
            c.errors.append(SpecError(c.loc(path + ("rows",)), "a table needs at least one row", "list variables, e.g. rows: [k, b, chi2]"))
            return None
        rows = [_row(vc, r, path + ("rows", i), i, p.format) for i, r in enumerate(p.rows)]
        kw["rows"] = [r for r in rows if r is not None]
    else:
        dpath = path + ("data",)
        res = c.expr_source(dpath, "the table's data")
        if res is None:
            return None
        shape = infer_shape(res[1], c.var_shapes)
        if shape is not None and len(shape) not in (1, 2):
            what = "one number" if not shape else f"an array of shape {shape}"
            c.errors.append(SpecError(c.loc(dpath), f"a table's data is a 1-D or 2-D array, but '{p.data}' is {what}", "give N values, or N rows of M columns (np.c_[a, b] puts columns side by side)"))
        data = vc.dynamic(dpath, "", "the table's data", p.data)
        if data is None:
            return None
        kw["data"] = data
        ncols = 1 if shape is not None and len(shape) == 1 else (shape[1] if shape is not None and len(shape) == 2 else None)
        if p.columns is not None:
            if ncols is not None and len(p.columns) != ncols:
                c.errors.append(SpecError(c.loc(path + ("columns",)), f"{len(p.columns)} column headers for '{p.data}', which has {ncols} column{'s' if ncols != 1 else ''} (shape {shape})", "give one header per column"))
            kw["columns"] = list(p.columns)
        if p.units is not None:
            want = len(p.columns) if p.columns is not None else ncols
            if want is not None and len(p.units) != want:
                c.errors.append(SpecError(c.loc(path + ("units",)), f"{len(p.units)} units for {want} column{'s' if want != 1 else ''}", "give one unit per column ('' for none)"))
            kw["units"] = list(p.units)
        if p.max_rows != 100:
            kw["max_rows"] = p.max_rows
    if p.format != ".6g" and _check_format(vc, p.format, path + ("format",)):
        kw["format"] = p.format
    kw["where"] = c.where(path)
    return Call("E.Table", [], kw)


def compile_console(vc: ViewCompiler, item: ViewItem, n: int) -> Call:
    """``E.Console(...)`` for a ``console`` element (the defaults left out)."""
    p = item.props
    kw: dict[str, Any] = {}
    if p.label != "Console":
        kw["label"] = p.label
    if p.lines != 200:
        kw["lines"] = p.lines
    if p.height != 160:
        kw["height"] = p.height
    kw["where"] = vc.c.where(item.path)
    return Call("E.Console", [], kw)
