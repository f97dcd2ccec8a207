"""A sweep's finished runs on disk as they finish, so that nothing is lost and a sweep resumes.

``ejsgen sweep ... --out runs.parquet`` keeps its finished runs in ``runs.parquet.parts/``
while it works: one file per finished batch (``b00000120-00000159.npz``: the runs 120 to
159, each a contiguous range), written to a temporary name and renamed, so a file is whole
or absent whatever stops the sweep (SIGKILL, OOM, a lost Dask scheduler, a full disk).
``sweep.json`` there names the sweep (a digest of the app's files, the runs' settings and
what each run records): ``--resume`` continues only the same sweep, running only the runs
no file holds. When every run is in, the tables are assembled from the files one batch at
a time (:func:`assemble`), so the parent's memory does not grow with the number of runs,
and the folder is removed.

A batch file is an ``.npz`` (no pickles): ``meta`` (JSON, as bytes) holds each run's
settings, status, error, wall time, column names and kinds, metrics and text columns, and
where each numeric column lies in ``f`` (floats), ``i`` (integers) or ``b`` (booleans).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ejsrl.app._rowfile import CannotWrite, RowFile, reason_of
from ejsrl.app.sweep_design import Run
from ejsrl.app.sweep_table import (
    Column,
    Table,
    _csv_cell,
    _merged_kind,
    _text,
    results_table,
    summary_table,
    to_arrow,
)
from ejsrl.app.sweep_worker import RunOptions, RunResult

__all__ = ["Journal", "JournalError", "Tally", "sweep_key", "parts_folder", "assemble", "writing_reason"]

_NAME = re.compile(r"^b(\d{8})-(\d{8})\.npz$")


class JournalError(Exception):
    """A parts folder that cannot be used as asked (nothing to resume, another sweep's parts)."""


def parts_folder(out: str | Path) -> Path:
    """``runs.parquet`` -> ``runs.parquet.parts`` (beside the results table)."""
    out = Path(out)
    return out.with_name(out.name + ".parts")


def sweep_key(app_digest: str, runs: Sequence[Run], options: RunOptions) -> str:
    """A digest of what makes a sweep's runs what they are: the app, each run's settings, the options."""
    h = hashlib.sha256(app_digest.encode())
    h.update(json.dumps([[r.run, [list(s) for s in r.settings]] for r in runs]).encode())
    h.update(json.dumps(asdict(options)).encode())
    return h.hexdigest()


class Journal:
    """The parts folder of one sweep: ``folder``, the sweep's ``key`` and its number of runs ``total``."""

    def __init__(self, folder: Path, key: str, total: int) -> None:
        self.folder = folder
        self.key = key
        self.total = total

    @classmethod
    def start(cls, folder: Path, key: str, total: int, *, resume: bool) -> Journal:
        """Open for a new sweep (any earlier parts are removed) or, with ``resume``, the
        stopped sweep's parts (``JournalError`` if there are none or they are another sweep's)."""
        manifest = folder / "sweep.json"
        if resume:
            try:
                old = json.loads(manifest.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                raise JournalError(f"--resume: no stopped sweep to continue in {folder} (run without --resume to start one)") from None
            if old.get("key") != key or old.get("runs") != total:
                raise JournalError(
                    f"--resume: {folder} holds the runs of another sweep (a different app, parameters or options); "
                    "give the same options as the stopped sweep, or run without --resume to start again"
                )
            return cls(folder, key, total)
        if folder.exists():
            shutil.rmtree(folder)
        folder.mkdir(parents=True)
        _write_atomic(manifest, json.dumps({"key": key, "runs": total}).encode())
        return cls(folder, key, total)

    def files(self) -> list[tuple[int, int, Path]]:
        """The whole batch files, as (first run, last run, path), in run order."""
        out = []
        for p in self.folder.iterdir():
            m = _NAME.match(p.name)
            if m:
                out.append((int(m.group(1)), int(m.group(2)), p))
        return sorted(out)

    def done(self) -> set[int]:
        """The run numbers some batch file holds."""
        runs: set[int] = set()
        for first, last, _ in self.files():
            runs.update(range(first, last + 1))
        return runs

    def write(self, results: Sequence[RunResult]) -> None:
        """Keep a finished batch (runs of one contiguous range); raises ``CannotWrite``."""
        if not results:
            return
        ordered = sorted(results, key=lambda r: r.run)
        first, last = ordered[0].run, ordered[-1].run
        path = self.folder / f"b{first:08d}-{last:08d}.npz"
        _write_atomic(path, _encode(ordered))

    def read(self, path: Path) -> list[RunResult]:
        """The runs of one batch file."""
        return _decode(path)

    def remove(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)


def contiguous_batches(runs: Sequence[Run], size: int) -> list[list[Run]]:
    """``runs`` (in order) in batches of at most ``size`` whose run numbers are contiguous,
    so every batch file of a resumed sweep covers a range no other file overlaps."""
    out: list[list[Run]] = []
    for run in runs:
        if out and len(out[-1]) < size and out[-1][-1].run + 1 == run.run:
            out[-1].append(run)
        else:
            out.append([run])
    return out


# -- a batch file ----------------------------------------------------------------------------------------


_DTYPES = {"f": np.float64, "i": np.int64, "b": np.bool_}


def _encode(results: Sequence[RunResult]) -> bytes:
    """A batch as three flat arrays (floats, integers, booleans) and the JSON that slices them."""
    import io

    chunks: dict[str, list[np.ndarray]] = {k: [] for k in _DTYPES}
    sizes = dict.fromkeys(_DTYPES, 0)
    meta = []
    for r in results:
        text_columns: dict[str, list[str]] = {}
        slices: dict[str, list[Any]] = {}
        for j, data in enumerate(r.data):
            if isinstance(data, list):
                text_columns[str(j)] = [str(v) for v in data]
                continue
            arr = np.asarray(data)
            code = "b" if arr.dtype.kind == "b" else "i" if arr.dtype.kind in "iu" else "f"
            arr = arr.astype(_DTYPES[code], copy=False).ravel()
            slices[str(j)] = [code, sizes[code], arr.size]
            chunks[code].append(arr)
            sizes[code] += arr.size
        meta.append({
            "run": r.run, "settings": [list(s) for s in r.settings], "status": r.status, "error": r.error,
            "seconds": r.seconds, "columns": r.columns, "kinds": r.kinds, "metrics": r.metrics, "text": text_columns,
            "slices": slices,
        })
    arrays = {code: (np.concatenate(parts) if parts else np.zeros(0, dtype=_DTYPES[code])) for code, parts in chunks.items()}
    arrays["meta"] = np.frombuffer(json.dumps(meta).encode("utf-8"), dtype=np.uint8)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def _decode(path: Path) -> list[RunResult]:
    with np.load(path, allow_pickle=False) as npz:
        meta = json.loads(npz["meta"].tobytes().decode("utf-8"))
        flat = {code: npz[code] for code in _DTYPES}
    out = []
    for m in meta:
        data: list[Any] = []
        for j in range(len(m["columns"])):
            if str(j) in m["text"]:
                data.append(m["text"][str(j)])
            else:
                code, offset, size = m["slices"][str(j)]
                data.append(flat[code][offset : offset + size].copy())
        out.append(RunResult(
            m["run"], tuple(tuple(s) for s in m["settings"]), m["status"], m["error"], m["seconds"],
            list(m["columns"]), list(m["kinds"]), data, dict(m["metrics"]),
        ))
    return out


def _write_atomic(path: Path, data: bytes) -> None:
    """``data`` into ``path`` whole or not at all (a temporary name, then a rename); ``CannotWrite``."""
    tmp = path.with_name(path.name + ".tmp")
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        try:
            view = memoryview(data)
            while view:
                n = os.write(fd, view)
                view = view[n:]
        finally:
            os.close(fd)
        os.replace(tmp, path)
    except OSError as exc:
        with _quiet():
            os.unlink(tmp)
        raise CannotWrite(str(path), reason_of(exc)) from None


class _quiet:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: Any) -> bool:
        return exc[0] is not None and issubclass(exc[0], OSError)


# -- assembling the tables ------------------------------------------------------------------------------


def writing_reason(exc: BaseException) -> str:
    """An error from writing a file in words: pyarrow's ``[errno 28] ...`` becomes ``No space left on device``."""
    if isinstance(exc, OSError) and exc.errno:
        return os.strerror(exc.errno)
    m = re.search(r"errno (\d+)", str(exc), re.IGNORECASE)
    return os.strerror(int(m.group(1))) if m else (str(exc) or type(exc).__name__)


def _read_meta(path: Path) -> list[dict[str, Any]]:
    """The JSON part of a batch file (its arrays are not read)."""
    with np.load(path, allow_pickle=False) as npz:
        return json.loads(npz["meta"].tobytes().decode("utf-8"))


def _schema(journal: Journal, types: dict[str, str], independent: str | None) -> tuple[dict[str, str], dict[str, str], Tally]:
    """The columns (name -> kind, in order) of the results and the summary over every batch,
    read from the batch files' JSON alone (no arrays), and the runs' tally.

    The kinds are those :func:`results_table` and :func:`summary_table` give: a recorded
    column's kind (``float`` for an integer variable that became a float), a statistic's
    kind that of its values, a parameter's and a metric's that of their values.
    """
    res_params: list[str] = []
    res_other: list[str] = []
    sum_stats: list[str] = []
    sum_metrics: list[str] = []
    res_kinds: dict[str, set[str]] = {}
    sum_kinds: dict[str, set[str]] = {}
    tally = Tally()

    def note(kinds: dict[str, set[str]], order: list[str], name: str, kind: str | None) -> None:
        if name not in kinds:
            kinds[name] = set()
            order.append(name)
        if kind is not None:
            kinds[name].add(kind)

    for _, _, path in journal.files():
        meta = _read_meta(path)
        lite = [RunResult(m["run"], tuple(tuple(x) for x in m["settings"]), m["status"], m["error"], m["seconds"],
                          metrics=dict(m["metrics"])) for m in meta]
        tally.runs += len(lite)
        for r in lite:
            if r.status == "error":
                tally.failed += 1
                if len(tally.first_failed) < 5:
                    tally.first_failed.append(r)
        params = {n for r in lite for n, _ in r.settings}
        metrics = list(dict.fromkeys(n for r in lite for n in r.metrics))
        bare = summary_table(lite, types, metrics)  # parameters and metrics; no recorded columns
        for name, col in bare.columns.items():
            known = col.kind if col.missing is None or not col.missing.all() else None
            if name in params:
                note(res_kinds, res_params, name, col.kind)
                note(sum_kinds, [], name, known)
            elif name in metrics:
                note(sum_kinds, sum_metrics, name, known)
        for m in meta:
            for j, (name, kind) in enumerate(zip(m["columns"], m["kinds"])):
                if name in params:
                    continue
                code = m["slices"].get(str(j), ["s"])[0]
                note(res_kinds, res_other, name, "float" if kind == "int" and code == "f" else kind)
                value_kind = {"f": "float", "i": "int", "b": "bool"}.get(code, "str")
                for stat in ("final", "min", "max") if kind in ("float", "int") else ("final",):
                    note(sum_kinds, sum_stats, f"{name}.{stat}", value_kind if m["slices"].get(str(j), [0, 0, 1])[2] or code == "s" else None)
    tally.ok = tally.runs - tally.failed
    if independent in res_other:
        res_other.remove(independent)
        res_other.insert(0, independent)
    results_schema = {"run": "int"}
    results_schema.update({n: _merged_kind(res_kinds[n] or {"float"}) for n in res_params + res_other})
    summary_schema = {"run": "int"}
    summary_schema.update({n: _merged_kind(sum_kinds[n] or {"float"}) for n in res_params})
    summary_schema.update({"status": "str", "error": "str", "seconds": "float"})
    summary_schema.update({n: _merged_kind(sum_kinds[n] or {"float"}) for n in sum_stats + sum_metrics})
    return results_schema, summary_schema, tally


def conform(table: Table, schema: dict[str, str]) -> Table:
    """``table`` with exactly the columns of ``schema``, in its order and kinds (absent ones missing)."""
    rows = table.rows
    out = Table()
    for name, kind in schema.items():
        col = table.columns.get(name)
        if col is None:
            fill: Any = [""] * rows if kind == "str" else np.zeros(rows, dtype={"float": float, "int": np.int64, "bool": bool}[kind])
            out.columns[name] = Column(kind, fill, np.ones(rows, dtype=bool) if rows else None)
        elif col.kind == kind:
            out.columns[name] = col
        elif kind == "str":
            cells = [col.cell(i) for i in range(rows)]
            out.columns[name] = Column("str", ["" if v is None else (v if isinstance(v, str) else _text(v)) for v in cells], col.missing)
        else:
            dtype = {"float": float, "int": np.int64, "bool": bool}[kind]
            out.columns[name] = Column(kind, np.asarray(col.values).astype(dtype), col.missing)
    return out


class _TableFile:
    """One table written a batch at a time: Parquet (a row group a batch) or CSV (whole rows)."""

    def __init__(self, path: Path, schema: dict[str, str]) -> None:
        self.path = path
        self.csv = path.suffix.lower() == ".csv"
        self.schema = schema
        self.rows = 0
        self._writer: Any = None
        self._fd: int | None = None
        self._file: RowFile | None = None
        try:
            if self.csv:
                self._fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
                self._file = RowFile(self._fd, str(path))
                self._file.write_row(list(schema))
            else:
                import pyarrow.parquet as pq

                empty = to_arrow(conform(Table(), schema))
                self._writer = pq.ParquetWriter(str(path), empty.schema)
        except CannotWrite:
            raise
        except OSError as exc:
            raise CannotWrite(str(path), writing_reason(exc)) from None

    def write(self, table: Table) -> None:
        try:
            if self._file is not None:
                cols = list(table.columns.values())
                for i in range(table.rows):
                    self._file.write_row([_csv_cell(c.cell(i)) for c in cols])
            else:
                self._writer.write_table(to_arrow(table))
        except CannotWrite:
            raise
        except OSError as exc:
            raise CannotWrite(str(self.path), writing_reason(exc)) from None
        self.rows += table.rows

    def close(self) -> None:
        try:
            if self._file is not None:
                self._file.flush()
            if self._writer is not None:
                writer, self._writer = self._writer, None
                writer.close()
        except CannotWrite:
            raise
        except OSError as exc:
            raise CannotWrite(str(self.path), writing_reason(exc)) from None
        finally:
            if self._fd is not None:
                os.close(self._fd)
                self._fd = None

    def abandon(self) -> None:
        """After a failure: close what is open and remove the cut file."""
        with _quiet():
            if self._writer is not None:
                self._writer.close()
        if self._fd is not None:
            with _quiet():
                os.close(self._fd)
        with _quiet():
            os.unlink(self.path)


@dataclass
class Tally:
    """What the assembled tables hold: ``runs``, ``ok`` (not failed), result ``rows``, the first
    ``first_failed`` runs that failed (without their data) and the ``summary`` if kept."""

    runs: int = 0
    ok: int = 0
    rows: int = 0
    failed: int = 0
    first_failed: list[RunResult] = field(default_factory=list)
    summary: Table | None = None


ROW_GROUP_CELLS = 1 << 18
"""Cells (rows x columns, ~2 MB) collected before they are written as one Parquet row group:
the memory a table being written holds, whatever the number of runs."""


def assemble(
    journal: Journal, out: Path, summary_out: Path, types: dict[str, str], independent: str | None, *, keep_summary: bool = False
) -> Tally:
    """Write the results and summary tables from the batch files, one batch at a time.

    Returns a ``Tally`` (the summary as one table if ``keep_summary``). On a failed write
    the cut files are removed and ``CannotWrite`` raised (the batch files stay).
    """
    results_schema, summary_schema, tally = _schema(journal, types, independent)
    files: list[_TableFile] = []
    kept: list[Table] = []
    try:
        files.append(_TableFile(out, results_schema))
        files.append(_TableFile(summary_out, summary_schema))
        pending: dict[int, list[Table]] = {0: [], 1: []}
        rows = {0: 0, 1: 0}
        for _, _, path in journal.files():
            results = journal.read(path)
            metrics = list(dict.fromkeys(n for r in results for n in r.metrics))
            tables = (conform(results_table(results, types, independent), results_schema),
                      conform(summary_table(results, types, metrics), summary_schema))
            del results
            if keep_summary:
                kept.append(tables[1])
            for k, table in enumerate(tables):
                pending[k].append(table)
                rows[k] += table.rows
                if rows[k] * len(files[k].schema) >= ROW_GROUP_CELLS or files[k].csv:
                    files[k].write(concat(pending[k], (results_schema, summary_schema)[k]))
                    pending[k], rows[k] = [], 0
        for k, f in enumerate(files):
            if pending[k] or f.rows == 0:
                f.write(concat(pending[k], (results_schema, summary_schema)[k]))
            f.close()
    except CannotWrite:
        for f in files:
            f.abandon()
        raise
    tally.rows = files[0].rows
    tally.summary = concat(kept, summary_schema) if keep_summary else None
    return tally


def concat(tables: Sequence[Table], schema: dict[str, str]) -> Table:
    """Tables of one schema, one after the other."""
    out = Table()
    for name, kind in schema.items():
        cols = [t.columns[name] for t in tables]
        if kind == "str":
            values: Any = [v for c in cols for v in c.values]
        else:
            dtype = {"float": float, "int": np.int64, "bool": bool}[kind]
            values = np.concatenate([np.asarray(c.values, dtype=dtype) for c in cols]) if cols else np.zeros(0, dtype=dtype)
        masks = [c.missing if c.missing is not None else np.zeros(len(c), dtype=bool) for c in cols]
        missing = np.concatenate(masks) if masks else np.zeros(0, dtype=bool)
        out.columns[name] = Column(kind, values, missing if missing.any() else None)
    return out


def iter_results(journal: Journal) -> Iterator[RunResult]:
    """Every kept run, in run order (one batch in memory at a time)."""
    for _, _, path in journal.files():
        yield from journal.read(path)
