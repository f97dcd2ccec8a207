"""Headless runs: the simulation without a browser, for a duration or a number of steps,
optionally into a CSV file.

``run_headless(app, duration, ...)`` is what ``--headless --duration T | --steps N
[--csv FILE] [--vars a,b,q[0]] [--every N]`` runs; ``csv_columns`` says which columns a
CSV has (``split_vars`` splits ``--vars``).
"""

from __future__ import annotations

import csv
import os
import re
import signal
import stat
import sys
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, TextIO

import numpy as np

from ejsrl.app._rowfile import CannotWrite, RowFile
from ejsrl.sim.model import ModelBase, UserCodeError

if TYPE_CHECKING:
    from ejsrl.app._loop import App

__all__ = ["run_headless", "csv_columns", "split_vars", "evolves", "refusal"]

MAX_CSV_COLUMNS = 1_000_000
"""Most columns a CSV row may have (a 1000x1000 array named in --vars; a 640x480 RGB
image is 921,600): an array past this is refused in plain words, not spread until memory ends."""


def run_headless(
    app: App,
    duration: float | None,
    *,
    csv_file: TextIO | None = None,
    variables: Sequence[str] | None = None,
    every: int = 1,
    log: TextIO | None = None,
    steps: int | None = None,
) -> int:
    """Run ``app`` for ``duration`` units of the independent variable, or for ``steps``
    steps (each: the evolution's pages, then the fixed relations), whichever ends first;
    returns the exit status.

    A model with no independent variable (no ODE page, no ``t``) runs only for ``steps``;
    with neither given, a model that does not evolve at all (no evolution page, program or
    FMU) writes the one row after ``init`` and returns 0, and any other says to give
    ``--steps N`` (status 2).

    Rows go to ``csv_file`` (every ``every`` steps; the ``variables``, by default every
    numeric one), alerts and errors to ``log`` (standard error by default).

    When ``interrupted`` becomes a signal's number (``main`` sets it on SIGINT/SIGTERM),
    the run stops after the step in progress, with every row written so far flushed,
    and returns 128 + that number.

    A CSV in a regular file ends on a whole row whatever happens: when the disk fills (or
    any write fails) the file is cut back to its last whole row, ``error: cannot write
    FILE: <reason>`` goes to ``log``, and the status is 1.
    """
    log = log if log is not None else sys.stderr
    rows = _sink(csv_file)
    try:
        status = _run(app, duration, steps, rows, variables, every, log)
        if rows is not None:
            rows.flush()
        return status
    except CannotWrite as exc:
        print(exc.line(), file=log)
        return 1


def evolves(model: ModelBase) -> bool:
    """Whether stepping ``model`` can change it: an evolution page, a program or an FMU."""
    return bool(model._ejs_pages or model.PROGRAMS or model._ejs_fmus is not None)


def refusal(model: ModelBase, duration: float | None, steps: int | None) -> str | None:
    """Why ``model`` cannot run for ``duration``/``steps`` (an ``error: ...`` line), or None."""
    if model.INDEPENDENT is None and (duration is not None or (steps is None and evolves(model))):
        return (
            "error: this model has no independent variable (no ODE page and no variable 't'), so a duration "
            "has no meaning: run it for a number of steps with --steps N (each step runs its evolution and "
            "fixed relations once)"
        )
    if duration is None and steps is None and model.INDEPENDENT is not None:
        return "error: --headless needs how long to run: --duration T (in units of the independent variable) or --steps N"
    return None


def _run(
    app: App, duration: float | None, steps: int | None, rows: _Rows | None, variables: Sequence[str] | None,
    every: int, log: TextIO,
) -> int:
    model = app.model
    if app.error is not None:
        print(_format_error(app.error), file=log)
        return 1
    why = refusal(model, duration, steps)
    if why is not None:
        print(why, file=log)
        return 2
    columns = csv_columns(model, variables)
    writer = rows
    if writer is not None:
        for note in left_out(model) if variables is None else []:
            print(note, file=log)
        writer.write_row([name for name, _ in columns])
        writer.write_row(_row(model, columns))
    timed = model.INDEPENDENT is not None and duration is not None
    t_start = (model._ejs_time() or 0.0) if timed else 0.0
    t_end = t_start + (duration or 0.0)
    max_steps = 0 if steps is None and not timed else steps
    done = 0
    app.playing = True
    last_t = t_start
    while True:
        if app.interrupted is not None:
            return _report_interrupt(app, rows, log)
        if max_steps is not None and done >= max_steps:
            break
        t = (model._ejs_time() or 0.0) if timed else 0.0
        if timed and t >= t_end - 1e-9 * max(1.0, abs(t_end)):
            break
        if app._run_steps(1) == 0:
            break
        done += 1
        if writer is not None and done % every == 0:
            writer.write_row(_row(model, columns))
        for text in app.pop_alerts():
            print(f"alert: {text}", file=log)
        if app.error is not None or not app.playing:
            break
        if not timed:
            continue
        t_new = model._ejs_time() or 0.0
        if t_new <= last_t:
            print(f"error: the independent variable '{model.INDEPENDENT}' did not advance in a step (t = {t_new:g})", file=log)
            return 2
        last_t = t_new
    for text in app.pop_alerts():
        print(f"alert: {text}", file=log)
    if app.error is not None:
        print(_format_error(app.error), file=log)
        return 1
    if not app.playing:
        where = f"{model.INDEPENDENT} = {model._ejs_time():g}" if model.INDEPENDENT is not None else f"step {done}"
        print(f"stopped at {where} (the simulation paused itself)", file=log)
    return 0


class _Rows:
    """CSV rows into a stream that is not a regular file (standard output, a pipe)."""

    def __init__(self, fh: TextIO) -> None:
        self.fh = fh
        self.writer = csv.writer(fh, lineterminator="\n")

    def write_row(self, row: Sequence[Any]) -> None:
        self.writer.writerow(row)

    def flush(self) -> None:
        self.fh.flush()


def _sink(csv_file: TextIO | None) -> _Rows | RowFile | None:
    """Where rows go: a ``RowFile`` (whole rows only) for a regular file, else the stream."""
    if csv_file is None:
        return None
    try:
        regular = stat.S_ISREG(os.fstat(csv_file.fileno()).st_mode)
    except (OSError, ValueError, AttributeError):  # io.StringIO and the like have no descriptor
        regular = False
    return RowFile.over(csv_file) if regular else _Rows(csv_file)


def _report_interrupt(app: App, csv_file: _Rows | RowFile | None, log: TextIO) -> int:
    signum = app.interrupted or signal.SIGTERM
    if csv_file is not None:
        csv_file.flush()
    t = app.model._ejs_time()
    where = f"{app.model.INDEPENDENT} = {t:g}" if t is not None else "the step in progress"
    print(
        f"stopped by {signal.Signals(signum).name} at {where}"
        + ("; the CSV holds the rows written so far" if csv_file is not None else ""),
        file=log,
    )
    return 128 + int(signum)


def _format_error(err: UserCodeError) -> str:
    return f"{err.where}: error: {err.message}" if err.where else f"error: {err.message}"


# -- CSV ---------------------------------------------------------------------------------------------


def split_vars(text: str) -> list[str]:
    """``--vars`` as names: split at the commas outside brackets (``q[0],t`` -> ``q[0]``, ``t``)."""
    out, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        depth += ch == "["
        depth -= ch == "]"
        if ch == "," and depth <= 0:
            out.append(text[start:i])
            start = i + 1
    out.append(text[start:])
    return [n.strip() for n in out if n.strip()]


_SELECTOR = re.compile(r"\s*([A-Za-z_]\w*)\s*((?:\[[^\[\]]*\]\s*)+)\Z")
_INDEX = re.compile(r"[-+]?\d+\Z")


def _parse_selector(name: str) -> tuple[str, tuple[int | slice, ...]] | None:
    """``q[0]``, ``m[1][2]``, ``q[1:3]``, ``q[::2]``, ``m[0][:]`` as (variable, index);
    None if ``name`` has no brackets. Raises ValueError for a bracket that is not an int or
    a slice of ints."""
    m = _SELECTOR.match(name)
    if m is None:
        return None
    key: list[int | slice] = []
    for part in re.findall(r"\[([^\[\]]*)\]", m.group(2)):
        bits = [b.strip() for b in part.split(":")]
        if len(bits) == 1 and _INDEX.match(bits[0]):
            key.append(int(bits[0]))
        elif 2 <= len(bits) <= 3 and all(b == "" or _INDEX.match(b) for b in bits):
            ints = [int(b) if b else None for b in bits]
            if len(ints) == 3 and ints[2] == 0:
                raise ValueError("a slice's step cannot be 0")
            key.append(slice(*ints))
        else:
            raise ValueError(f"[{part}] is not an index (an int, or a slice such as 1:3)")
    return m.group(1), tuple(key)


def _selected(model: ModelBase, name: str, types: dict[str, str]) -> list[tuple[str, Callable[[], Any]]] | None:
    """The columns ``name`` selects when it names array elements (``q[0]``, ``q[1:3]``), each
    headed as the default CSV heads it (``q[1]``, ``m[0][2]``); None if it has no brackets."""
    from ejsrl._suggest import did_you_mean

    try:
        parsed = _parse_selector(name)
    except ValueError as exc:
        raise UserCodeError(f"--vars: '{name}': {exc}") from None
    if parsed is None:
        return None
    var, key = parsed
    if var not in types:
        raise UserCodeError(f"--vars: unknown variable '{var}' in '{name}'{did_you_mean(var, types)}")
    value = getattr(model, var)
    if not (isinstance(value, np.ndarray) and value.dtype.kind in "biuf"):
        raise UserCodeError(f"--vars: '{name}': '{var}' is not an array of numbers, so it has no elements to pick")
    if len(key) > value.ndim:
        shape = " x ".join(map(str, value.shape))
        raise UserCodeError(f"--vars: '{name}' has {len(key)} indices, but '{var}' has {value.ndim} ({shape} values)")
    for axis, k in enumerate(key):
        if isinstance(k, int) and not -value.shape[axis] <= k < value.shape[axis]:
            raise UserCodeError(
                f"--vars: '{name}': index {k} is out of range: '{var}' has {value.shape[axis]} values along "
                f"that axis (0 to {value.shape[axis] - 1})"
            )
    flat = np.arange(value.size).reshape(value.shape)[key]
    picked = [tuple(int(i) for i in np.unravel_index(int(f), value.shape)) for f in np.ravel(flat)]
    if not picked:
        raise UserCodeError(f"--vars: '{name}' selects no element of '{var}'{_shape(value) or f' ({value.size} values)'}")
    return [
        (f"{var}[{']['.join(map(str, idx))}]", (lambda idx=idx: getattr(model, var)[idx]))
        for idx in picked
    ]


def csv_columns(model: ModelBase, names: Sequence[str] | None = None) -> list[tuple[str, Callable[[], Any]]]:
    """The CSV columns: (header, getter). Arrays are spread as ``q[0]``, ``q[1]``, ...

    A name may pick elements of an array as those headers name them: ``q[0]``, ``m[1][2]``,
    or slices of ints (``q[1:3]``, ``q[::2]``, ``m[0][:]``), each element its column, headed
    by its full index (``q[1]``, ``q[2]``), negative indices counted from the end.

    With no ``names``, every numeric variable (numbers and arrays of numbers, ``expr:``
    variables included; not booleans, text, images or arrays of more than
    ``MAX_CSV_COLUMNS`` values: see ``left_out``) in declaration order. Named variables may
    also be booleans (written 0/1), arrays of booleans and text; naming any other kind of
    value (a robot, say) raises ``UserCodeError``.
    """
    types = model.VARIABLES
    if names is None:
        names = [
            n
            for n, kind in types.items()
            if kind in ("float", "int", "array", "auto") and _is_numeric(getattr(model, n)) and not is_image(getattr(model, n))
            and not _too_wide(getattr(model, n))
        ]
    else:
        for n in names:
            if n not in types and _SELECTOR.match(n) is None:
                from ejsrl._suggest import did_you_mean

                raise UserCodeError(f"--vars: unknown variable '{n}'{did_you_mean(n, types)}")
    columns: list[tuple[str, Callable[[], Any]]] = []
    count = 0
    for n in names:
        picked = _selected(model, n, types) if n not in types else None
        if picked is not None:
            count += len(picked)
            if count > MAX_CSV_COLUMNS:
                raise UserCodeError(f"--vars: '{n}' would make a CSV row of more than {MAX_CSV_COLUMNS:,} columns; pick fewer elements")
            columns.extend(picked)
            continue
        value = getattr(model, n)
        if isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
            count += value.size
            if count > MAX_CSV_COLUMNS:
                raise UserCodeError(
                    f"'{n}' is an array of {value.size:,} values{_shape(value)}: spread one "
                    f"value a column, a CSV row would have more than {MAX_CSV_COLUMNS:,} columns; name fewer "
                    "variables with --vars, or save the array from the spec's code (np.save) and read it with NumPy"
                )
            for idx in np.ndindex(value.shape):
                label = f"{n}[{']['.join(str(i) for i in idx)}]"
                columns.append((label, (lambda n=n, idx=idx: getattr(model, n)[idx])))
        elif isinstance(value, (bool, int, float, str, np.bool_, np.integer, np.floating)):
            columns.append((n, (lambda n=n: getattr(model, n))))
        else:
            what = f"an array of {value.dtype}" if isinstance(value, np.ndarray) else f"a {type(value).__name__}"
            raise UserCodeError(
                f"--vars: '{n}' holds {what}; the CSV takes numbers, booleans, text and arrays of numbers"
            )
    return columns


def left_out(model: ModelBase) -> list[str]:
    """The numeric arrays the default CSV leaves out for their size, as notes for the user."""
    return [
        f"note: '{n}' ({getattr(model, n).size:,} values) is left out of the CSV: one value a column, a row "
        f"would have more than {MAX_CSV_COLUMNS:,} columns; save it from the spec's code (np.save) instead"
        for n, kind in model.VARIABLES.items()
        if kind in ("array", "auto") and _is_numeric(getattr(model, n)) and _too_wide(getattr(model, n))
    ]


def _shape(value: np.ndarray) -> str:
    return f" ({' x '.join(map(str, value.shape))})" if value.ndim > 1 else ""


def _too_wide(value: Any) -> bool:
    return isinstance(value, np.ndarray) and value.size > MAX_CSV_COLUMNS


def is_image(value: Any) -> bool:
    """An H×W or H×W×C array of bytes: a camera image, left out of the default CSV (one
    640×480 RGB frame would be 921,600 columns); named in ``--vars`` it is written."""
    return isinstance(value, np.ndarray) and value.dtype == np.uint8 and value.ndim in (2, 3)


def _is_numeric(value: Any) -> bool:
    """A number (not a boolean) or an array of numbers."""
    if isinstance(value, np.ndarray):
        return value.dtype.kind in "iuf"
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def _row(model: ModelBase, columns: list[tuple[str, Callable[[], Any]]]) -> list[str]:
    out = []
    for _, get in columns:
        v = get()
        if isinstance(v, (bool, np.bool_)):
            out.append("1" if v else "0")
        elif isinstance(v, (int, np.integer)):
            out.append(str(int(v)))
        elif isinstance(v, str):
            out.append(v)  # the csv writer quotes it if it needs quotes
        else:
            out.append(repr(float(v)))
    return out
