"""A sweep's two tables, and writing them as Parquet (pyarrow) or CSV.

- **results** (tidy): one row per recorded step of every run: ``run``, the parameters,
  the independent variable, then the recorded variables (arrays spread as ``q[0]``, ...,
  as in a headless CSV). A parameter's column holds the value the run was started with; it
  is not recorded again as a variable.
- **summary**: one row per run: ``run``, the parameters, ``status`` (``ok``; ``stopped``:
  the simulation paused itself before the end; ``error``), ``error`` (its text), ``seconds``
  (the run's wall time), then ``NAME.final``, ``NAME.min`` and ``NAME.max`` of every
  recorded number, ``NAME.final`` of booleans and text, and the spec's ``metrics:``.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ejsrl.app.sweep_design import display_value
from ejsrl.app.sweep_worker import RunResult

__all__ = ["Table", "results_table", "summary_table", "write_table", "PYARROW_HINT", "SUMMARY_COLUMNS"]

PYARROW_HINT = "writing Parquet needs pyarrow: pip install 'ejsgen[sweep]' (or: pip install pyarrow), or write CSV (--out FILE.csv)"

#: the summary's own columns (a parameter or metric may not take these names)
SUMMARY_COLUMNS = ("run", "status", "error", "seconds")


@dataclass
class Column:
    """Values of one kind (``float``, ``int``, ``bool``, ``str``) and which of them are missing."""

    kind: str
    values: Any
    missing: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.values)

    def cell(self, i: int) -> Any:
        if self.missing is not None and self.missing[i]:
            return None
        v = self.values[i]
        return v.item() if isinstance(v, np.generic) else v


@dataclass
class Table:
    """Named columns of equal length, in order."""

    columns: dict[str, Column] = field(default_factory=dict)

    @property
    def rows(self) -> int:
        return len(next(iter(self.columns.values()))) if self.columns else 0

    def to_pydict(self) -> dict[str, list[Any]]:
        return {name: [col.cell(i) for i in range(len(col))] for name, col in self.columns.items()}


def _kind_of_values(values: Sequence[Any]) -> str:
    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present):
        return "bool"
    if present and all(isinstance(v, int) and not isinstance(v, bool) for v in present):
        return "int"
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        return "float"
    return "str"


def _column_from(values: Sequence[Any], kind: str | None = None) -> Column:
    kind = kind or _kind_of_values(values)
    missing = np.array([v is None for v in values], dtype=bool)
    dtype = {"float": float, "int": np.int64, "bool": bool}.get(kind)
    if dtype is None:
        data: Any = ["" if v is None else (v if isinstance(v, str) else _text(v)) for v in values]
    else:
        fill = {"float": np.nan, "int": 0, "bool": False}[kind]
        data = np.array([fill if v is None else v for v in values], dtype=dtype)
    return Column(kind, data, missing if missing.any() else None)


def _text(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v) if isinstance(v, float) else str(v)


def _params(results: Sequence[RunResult], types: dict[str, str]) -> dict[str, list[Any]]:
    names: list[str] = []
    for r in results:
        for name, _ in r.settings:
            if name not in names:
                names.append(name)
    return {n: [display_value(dict(r.settings)[n], types.get(n, "auto")) if n in dict(r.settings) else None for r in results] for n in names}


def _merged_kind(kinds: set[str]) -> str:
    if len(kinds) == 1:
        return next(iter(kinds))
    if kinds <= {"int", "float"}:
        return "float"
    if kinds <= {"int", "bool"}:
        return "int"
    return "str"


def results_table(results: Sequence[RunResult], types: dict[str, str], independent: str | None) -> Table:
    """The tidy table of every recorded step of every run (see the module's docstring)."""
    params = _params(results, types)
    order: list[str] = []
    kinds: dict[str, set[str]] = {}
    for r in results:
        for name, kind in zip(r.columns, r.kinds):
            if name in params:
                continue
            if name not in kinds:
                order.append(name)
                kinds[name] = set()
            kinds[name].add("float" if kind == "int" and r.data[r.columns.index(name)].dtype.kind == "f" else kind)
    if independent in order:
        order.remove(independent)
        order.insert(0, independent)
    lengths = [len(r.data[0]) if r.data else 0 for r in results]
    total = sum(lengths)
    table = Table()
    table.columns["run"] = Column("int", np.repeat(np.array([r.run for r in results], dtype=np.int64), lengths))
    for name, values in params.items():
        col = _column_from(values)
        idx = np.repeat(np.arange(len(results)), lengths)
        table.columns[name] = Column(col.kind, col.values[idx] if col.kind != "str" else [col.values[i] for i in idx], col.missing[idx] if col.missing is not None else None)
    for name in order:
        kind = _merged_kind(kinds[name])
        parts: list[Any] = []
        missing: list[np.ndarray] = []
        for r, n in zip(results, lengths):
            if name in r.columns:
                data = r.data[r.columns.index(name)]
                parts.append(np.asarray(data, dtype=object).astype(str) if kind == "str" and not isinstance(data, list) else data)
                missing.append(np.zeros(n, dtype=bool))
            else:
                parts.append(np.full(n, np.nan) if kind != "str" else [""] * n)
                missing.append(np.ones(n, dtype=bool))
        miss = np.concatenate(missing) if missing else np.zeros(0, dtype=bool)
        if kind == "str":
            values: Any = [str(v) for part in parts for v in part]
        else:
            dtype = {"float": float, "int": np.int64, "bool": bool}[kind]
            values = np.concatenate([np.asarray(p).astype(dtype) if len(p) else np.zeros(0, dtype=dtype) for p in parts]) if parts else np.zeros(0, dtype=dtype)
        assert len(values) == total
        table.columns[name] = Column(kind, values, miss if miss.any() else None)
    return table


def summary_table(results: Sequence[RunResult], types: dict[str, str], metric_names: Sequence[str] = ()) -> Table:
    """One row per run: status, error, wall time, final/min/max of each recorded value, metrics."""
    params = _params(results, types)
    table = Table()
    table.columns["run"] = Column("int", np.array([r.run for r in results], dtype=np.int64))
    for name, values in params.items():
        table.columns[name] = _column_from(values)
    table.columns["status"] = _column_from([r.status for r in results], "str")
    table.columns["error"] = _column_from([r.error for r in results], "str")
    table.columns["seconds"] = _column_from([float(r.seconds) for r in results], "float")
    stats: dict[str, list[Any]] = {}
    stat_kinds: dict[str, str] = {}
    order: list[str] = []
    for r in results:
        for name, kind in zip(r.columns, r.kinds):
            if name not in order and name not in params:
                order.append(name)
                stat_kinds[name] = kind
    for name in order:
        numeric = stat_kinds[name] in ("float", "int")
        for stat in ("final", "min", "max") if numeric else ("final",):
            stats[f"{name}.{stat}"] = []
        for r in results:
            data = r.data[r.columns.index(name)] if name in r.columns else None
            have = data is not None and len(data) > 0
            final = (data[-1].item() if isinstance(data[-1], np.generic) else data[-1]) if have else None
            stats[f"{name}.final"].append(final)
            if numeric:
                stats[f"{name}.min"].append(np.min(data).item() if have else None)
                stats[f"{name}.max"].append(np.max(data).item() if have else None)
    for name, values in stats.items():
        table.columns[name] = _column_from(values)
    for name in metric_names:
        table.columns[name] = _column_from([r.metrics.get(name) for r in results])
    return table


# -- writing -------------------------------------------------------------------------------------------


def write_table(table: Table, path: str | Path) -> None:
    """Write as CSV (``.csv``) or Parquet (anything else; needs pyarrow)."""
    path = Path(path)
    if path.suffix.lower() == ".csv":
        _write_csv(table, path)
    else:
        _write_parquet(table, path)


def _write_csv(table: Table, path: Path) -> None:
    cols = list(table.columns.values())
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(list(table.columns))
        for i in range(table.rows):
            w.writerow([_csv_cell(c.cell(i)) for c in cols])


def _csv_cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "1" if v else "0"
    if isinstance(v, float):
        return repr(v)
    return str(v)


def to_arrow(table: Table) -> Any:
    """The table as a ``pyarrow.Table`` (raises ``RuntimeError`` with an install hint without pyarrow)."""
    try:
        import pyarrow as pa
    except ImportError:
        raise RuntimeError(PYARROW_HINT) from None
    arrays = {}
    for name, col in table.columns.items():
        typ = {"float": pa.float64(), "int": pa.int64(), "bool": pa.bool_(), "str": pa.string()}[col.kind]
        values = col.values if col.kind != "str" else list(col.values)
        if col.kind == "str" and col.missing is not None:
            values = [None if m else v for v, m in zip(values, col.missing)]
            arrays[name] = pa.array(values, type=typ)
        else:
            arrays[name] = pa.array(values, type=typ, mask=col.missing)
    return pa.table(arrays)


def _write_parquet(table: Table, path: Path) -> None:
    arrow = to_arrow(table)
    import pyarrow.parquet as pq

    pq.write_table(arrow, path)
