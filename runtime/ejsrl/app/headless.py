"""Headless runs: the simulation without a browser, for a duration, optionally into a CSV file.

``run_headless(app, duration, ...)`` is what ``--headless --duration T [--csv FILE]
[--vars a,b,q] [--every N]`` runs; ``csv_columns`` says which columns a CSV has.
"""

from __future__ import annotations

import csv
import signal
import sys
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, TextIO

import numpy as np

from ejsrl.sim.model import ModelBase, UserCodeError

if TYPE_CHECKING:
    from ejsrl.app._loop import App

__all__ = ["run_headless", "csv_columns"]


def run_headless(
    app: App,
    duration: float,
    *,
    csv_file: TextIO | None = None,
    variables: Sequence[str] | None = None,
    every: int = 1,
    log: TextIO | None = None,
) -> int:
    """Run ``app`` for ``duration`` units of the independent variable; returns the exit status.

    Rows go to ``csv_file`` (every ``every`` steps; the ``variables``, by default every
    numeric one), alerts and errors to ``log`` (standard error by default).

    When ``interrupted`` becomes a signal's number (``main`` sets it on SIGINT/SIGTERM),
    the run stops after the step in progress, with every row written so far flushed,
    and returns 128 + that number.
    """
    log = log if log is not None else sys.stderr
    model = app.model
    if app.error is not None:
        print(_format_error(app.error), file=log)
        return 1
    if model.INDEPENDENT is None:
        print("error: this model has no independent variable (no ODE page and no variable 't')", file=log)
        return 2
    columns = csv_columns(model, variables)
    writer = csv.writer(csv_file, lineterminator="\n") if csv_file is not None else None
    if writer is not None:
        writer.writerow([name for name, _ in columns])
        writer.writerow(_row(model, columns))
    t_start = model._ejs_time() or 0.0
    t_end = t_start + duration
    steps = 0
    app.playing = True
    last_t = t_start
    while True:
        if app.interrupted is not None:
            return _report_interrupt(app, csv_file, log)
        t = model._ejs_time() or 0.0
        if t >= t_end - 1e-9 * max(1.0, abs(t_end)):
            break
        if app._run_steps(1) == 0:
            break
        steps += 1
        t_new = model._ejs_time() or 0.0
        if writer is not None and steps % every == 0:
            writer.writerow(_row(model, columns))
        for text in app.pop_alerts():
            print(f"alert: {text}", file=log)
        if app.error is not None or not app.playing:
            break
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
        print(f"stopped at {model.INDEPENDENT} = {model._ejs_time():g} (the simulation paused itself)", file=log)
    return 0


def _report_interrupt(app: App, csv_file: TextIO | None, log: TextIO) -> int:
    signum = app.interrupted or signal.SIGTERM
    if csv_file is not None:
        csv_file.flush()
    t = app.model._ejs_time()
    print(
        f"stopped by {signal.Signals(signum).name} at {app.model.INDEPENDENT} = {t:g}"
        + ("; the CSV holds the rows written so far" if csv_file is not None else ""),
        file=log,
    )
    return 128 + int(signum)


def _format_error(err: UserCodeError) -> str:
    return f"{err.where}: error: {err.message}" if err.where else f"error: {err.message}"


# -- CSV ---------------------------------------------------------------------------------------------


def csv_columns(model: ModelBase, names: Sequence[str] | None = None) -> list[tuple[str, Callable[[], Any]]]:
    """The CSV columns: (header, getter). Arrays are spread as ``q[0]``, ``q[1]``, ...

    With no ``names``, every numeric variable (numbers and arrays of numbers, ``expr:``
    variables included; not booleans, text or images) in declaration order. Named variables may
    also be booleans (written 0/1), arrays of booleans and text; naming any other kind of
    value (a robot, say) raises ``UserCodeError``.
    """
    types = model.VARIABLES
    if names is None:
        names = [
            n
            for n, kind in types.items()
            if kind in ("float", "int", "array", "auto") and _is_numeric(getattr(model, n)) and not is_image(getattr(model, n))
        ]
    else:
        for n in names:
            if n not in types:
                from ejsrl._suggest import did_you_mean

                raise UserCodeError(f"--vars: unknown variable '{n}'{did_you_mean(n, types)}")
    columns: list[tuple[str, Callable[[], Any]]] = []
    for n in names:
        value = getattr(model, n)
        if isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
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
