"""A sweep whose runs are contained: each run one process in a sandbox, its result sent back as JSON.

``ejsgen sweep SPEC --sandbox`` sweeps a spec nobody here wrote (a student's hand-in): its
build and each of its runs run in an OS sandbox (:mod:`ejsgen._sandbox`: bubblewrap, the
file system read-only but the run's own folder, no network, limits of CPU time, memory,
file size and wall time per run). The parent never imports the app -- importing it runs
the spec's ``imports:`` and module code -- nor unpickles anything a sandbox wrote:

- ``python -P -m ejsrl.app.sweep_sandbox describe APP OUT.json`` writes what the parent
  needs of the model: ``{"variables": {name: type}, "independent": name or null}``;
- ``python -P -m ejsrl.app.sweep_sandbox run APP REQUEST OUT.json`` runs one run
  (``REQUEST``: ``{"run": n, "settings": [[name, text], ...], "duration": T, "variables":
  [...] or null, "every": N}``) exactly as a sweep's worker does
  (:func:`~ejsrl.app.sweep_worker.run_one`) and writes its result as JSON (floats as
  ``repr``, so they read back bit for bit).

The parent reads these files checked field by field (:func:`decode_result`): a hand-in that
writes something else fails its run, it cannot reach the parent. :class:`ContainedRuns`
runs the runs (``workers`` sandboxes at a time, from threads: each waits on its process);
a run that hits a limit, or ends without a result, is a failed run with the reason, and the
others carry on. Each run pays its own interpreter's start (about 0.3 s of CPU): the price
of a process per run, which is what lets a limit stop one run and not the others.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import sys
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ejsrl.app.sweep_design import Run
from ejsrl.app.sweep_worker import (
    LoadedApp,
    RunOptions,
    RunResult,
    app_ref,
    loaded,
    run_one,
)

__all__ = ["ContainedRuns", "ModelFacts", "SandboxError", "decode_result", "encode_result", "main"]

#: the kinds of a recorded column and the JSON values each holds
_KINDS: dict[str, tuple[type, ...]] = {"float": (float, int), "int": (int, float), "bool": (bool,), "str": (str,)}
_STATUSES = ("ok", "stopped", "error")
#: the longest error text kept from a sandbox (a hand-in could write any amount)
MAX_ERROR = 2000


class SandboxError(Exception):
    """The sandboxed app could not be built, described or run at all (the message says why)."""


@dataclass(frozen=True)
class ModelFacts:
    """What the parent knows of a model it does not import: ``VARIABLES`` (name -> type) and
    ``INDEPENDENT`` (the independent variable's name, or None), as a model class has them."""

    VARIABLES: dict[str, str]
    INDEPENDENT: str | None


# -- in the sandbox ----------------------------------------------------------------------------------------


def encode_result(result: RunResult) -> dict[str, Any]:
    """A run's result as JSON-able values (the columns as lists)."""
    return {
        "status": result.status,
        "error": result.error,
        "seconds": result.seconds,
        "columns": list(result.columns),
        "kinds": list(result.kinds),
        "data": [np.asarray(col).tolist() if not isinstance(col, list) else col for col in result.data],
        "metrics": dict(result.metrics),
    }


def _write_json(path: Path, value: Any) -> None:
    tmp = path.with_name(path.name + ".part")
    tmp.write_text(json.dumps(value), encoding="utf-8")
    os.replace(tmp, path)


def main(argv: Sequence[str] | None = None) -> int:
    """``describe APP OUT`` or ``run APP REQUEST OUT`` (see the module docstring)."""
    args = list(sys.argv[1:] if argv is None else argv)
    np.seterr(all="ignore")
    if len(args) == 3 and args[0] == "describe":
        app = loaded(app_ref(args[1]))
        _write_json(Path(args[2]), {"variables": dict(app.model_cls.VARIABLES), "independent": app.model_cls.INDEPENDENT})
        return 0
    if len(args) == 4 and args[0] == "run":
        request = json.loads(args[2])
        run = Run(int(request["run"]), tuple((str(n), str(v)) for n, v in request["settings"]))
        names = request["variables"]
        options = RunOptions(float(request["duration"]), tuple(names) if names is not None else None, int(request["every"]))
        try:
            app = loaded(app_ref(args[1]))
        except Exception as exc:
            result = RunResult(run.run, run.settings, "error", f"error: the app could not be loaded: {type(exc).__name__}: {exc}")
        else:
            result = run_one(app, run, options)
        if result.status == "error":  # where the parent looks for a limit's words (MemoryError, ...)
            print(result.error, file=sys.stderr)
        _write_json(Path(args[3]), encode_result(result))
        return 0
    print("usage: python -m ejsrl.app.sweep_sandbox describe APP OUT.json | run APP REQUEST OUT.json", file=sys.stderr)
    return 2


# -- in the parent: what came back, checked ----------------------------------------------------------------


def _read_json(path: Path, limit: int) -> Any:
    """The JSON in ``path`` (at most ``limit`` bytes), or raise ``ValueError`` saying what is wrong."""
    try:
        size = path.stat().st_size
    except OSError:
        raise ValueError("it wrote no result") from None
    if size > limit:
        raise ValueError(f"its result has {size} bytes, more than {limit}")
    try:
        return json.loads(path.read_bytes())
    except (ValueError, RecursionError) as exc:
        raise ValueError(f"its result is not JSON ({str(exc)[:100]})") from None


def _check(ok: bool, what: str) -> None:
    if not ok:
        raise ValueError(f"its result has {what}")


def decode_result(raw: Any, run: Run) -> RunResult:
    """A run's result from the JSON a sandbox wrote, every field checked (``ValueError`` if not
    what :func:`encode_result` writes); the run's number and settings are the parent's own."""
    _check(isinstance(raw, dict), "no fields")
    status, error, seconds = raw.get("status"), raw.get("error"), raw.get("seconds")
    columns, kinds, data, metrics = raw.get("columns"), raw.get("kinds"), raw.get("data"), raw.get("metrics")
    _check(status in _STATUSES, "an unknown status")
    _check(isinstance(error, str), "an error that is not text")
    _check(isinstance(seconds, (int, float)) and not isinstance(seconds, bool) and math.isfinite(seconds), "a bad duration")
    _check(isinstance(columns, list) and all(isinstance(c, str) for c in columns), "bad column names")
    _check(isinstance(kinds, list) and len(kinds) == len(columns) and all(k in _KINDS for k in kinds), "bad column kinds")
    _check(isinstance(data, list) and len(data) == len(columns), "a column count that does not match")
    rows = len(data[0]) if data else 0
    for col, kind in zip(data, kinds):
        _check(isinstance(col, list) and len(col) == rows, "columns of different lengths")
        allowed = _KINDS[kind]
        _check(all(isinstance(v, allowed) and (kind == "bool" or not isinstance(v, bool)) for v in col), f"a value that is not {kind}")
    _check(isinstance(metrics, dict), "no metrics")
    for name, value in metrics.items():
        _check(isinstance(name, str) and (value is None or isinstance(value, (bool, int, float, str))), "a bad metric")
    return RunResult(
        run.run, run.settings, status, error[:MAX_ERROR], float(seconds), list(columns), list(kinds),
        [_values(col, kind) for col, kind in zip(data, kinds)],
        {n: float(v) if isinstance(v, int) and not isinstance(v, bool) else v for n, v in metrics.items()},
    )


def _values(col: list[Any], kind: str) -> Any:
    """A checked JSON column as the worker's columns are (floats exact, integers, booleans, text)."""
    if kind == "float" or (kind == "int" and any(isinstance(v, float) for v in col)):  # an int that became a float
        return np.array(col, dtype=float)
    if kind == "int":
        return np.array(col, dtype=np.int64)  # OverflowError past 64 bits: the caller's bad result
    return np.array(col, dtype=bool) if kind == "bool" else list(col)


# -- in the parent: the runs -------------------------------------------------------------------------------

#: ``contain(cmd, writable, readable, stop)`` -> an object with ``status``, ``stderr``, ``reason``, ``stopped``
Contain = Callable[[list[str], Path, list[Path], "threading.Event | None"], Any]


class ContainedRuns:
    """Runs of the built app in ``folder``, each in a sandbox of its own made by ``contain``,
    in folders under ``work`` (each run's folder removed once its result is read).

    ``result_limit``: the most bytes of JSON a run's result may have (its file size limit).
    """

    def __init__(self, folder: Path, work: Path, contain: Contain, *, result_limit: int) -> None:
        self.folder = Path(folder).resolve()
        self.work = Path(work).resolve()
        self.contain = contain
        self.result_limit = result_limit
        self.work.mkdir(parents=True, exist_ok=True)

    def _python(self, *args: str) -> list[str]:
        return [sys.executable, "-P", "-m", "ejsrl.app.sweep_sandbox", *args]

    def describe(self) -> LoadedApp:
        """What the sweep needs of the model, read in a sandbox: a ``LoadedApp`` whose
        ``model_cls`` is a :class:`ModelFacts` (``SandboxError`` if it cannot be loaded)."""
        out = self.work / "describe"
        out.mkdir(exist_ok=True)
        done = self.contain(self._python("describe", str(self.folder), str(out / "model.json")), out, [self.folder], None)
        try:
            if done.status != 0 or done.reason:
                raise ValueError(done.reason or _last_line(done.stderr))
            raw = _read_json(out / "model.json", 1 << 20)
            variables, independent = raw.get("variables"), raw.get("independent")
            _check(isinstance(variables, dict) and all(isinstance(n, str) and isinstance(t, str) for n, t in variables.items()), "bad variables")
            _check(independent is None or independent in variables, "a bad independent variable")
        except (ValueError, AttributeError) as exc:
            raise SandboxError(f"the built app could not be loaded in the sandbox: {exc}") from None
        finally:
            shutil.rmtree(out, ignore_errors=True)
        return LoadedApp(ModelFacts(dict(variables), independent), [], None, None, self.folder)

    def run(self, run: Run, options: RunOptions, stop: threading.Event | None) -> RunResult | None:
        """One run in its sandbox: its result, a failed result with the reason, or None when ``stop`` ended it."""
        out = self.work / f"run{run.run}"
        out.mkdir(exist_ok=True)
        request = json.dumps({"run": run.run, "settings": [list(s) for s in run.settings], "duration": options.duration,
                              "variables": list(options.variables) if options.variables is not None else None, "every": options.every})
        try:
            done = self.contain(self._python("run", str(self.folder), request, str(out / "result.json")), out, [self.folder], stop)
            if done.stopped:
                return None
            if done.reason:
                return RunResult(run.run, run.settings, "error", f"error: {done.reason}")
            try:
                return decode_result(_read_json(out / "result.json", self.result_limit), run)
            except (ValueError, OverflowError) as exc:
                why = _last_line(done.stderr) if done.status != 0 else str(exc)
                return RunResult(run.run, run.settings, "error", f"error: {why}"[:MAX_ERROR])
        finally:
            shutil.rmtree(out, ignore_errors=True)

    def execute(self, work: list[list[Run]], options: RunOptions, workers: int, on_results: Callable[[list[RunResult]], None]) -> None:
        """Run the batches' runs, ``workers`` at a time; each batch goes to ``on_results`` (in this
        thread) once all its runs are back. An exception here (the sweep's stop on SIGTERM or
        Ctrl+C) kills every running sandbox before it propagates."""
        stop = threading.Event()
        left = {i: len(batch) for i, batch in enumerate(work)}
        got: dict[int, list[RunResult]] = {i: [] for i in left}
        pool = ThreadPoolExecutor(max(1, workers), thread_name_prefix="ejsrl-sandbox")
        try:
            pending: dict[Future[RunResult | None], int] = {
                pool.submit(self.run, run, options, stop): i for i, batch in enumerate(work) for run in batch
            }
            while pending:
                finished, _ = wait(pending, timeout=0.25, return_when=FIRST_COMPLETED)
                for fut in finished:
                    i = pending.pop(fut)
                    result = fut.result()
                    if result is None:
                        continue
                    got[i].append(result)
                    left[i] -= 1
                    if left[i] == 0:
                        on_results(sorted(got.pop(i), key=lambda r: r.run))
        finally:
            stop.set()
            pool.shutdown(wait=True, cancel_futures=True)


def _last_line(stderr: str) -> str:
    """The error a process ended with: its last line that says error, else its last line."""
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    errors = [line for line in lines if "Error" in line or "error" in line]
    text = (errors or lines or ["it ended without a word"])[-1]
    return (text.removeprefix("error: "))[:MAX_ERROR]


if __name__ == "__main__":
    sys.exit(main())
