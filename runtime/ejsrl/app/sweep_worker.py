"""One run of a sweep, in a worker process: the model imported once, each run a headless run.

A worker imports the app (``app.py`` of a built folder) the first time it sees it and keeps
it (:func:`loaded`); each run is then what ``app.py --headless --duration T --vars ...
--set NAME=VALUE ...`` does: a fresh :class:`~ejsrl.app._loop.App` with the ``--set``
overrides parsed by :func:`~ejsrl.app.cli.parse_set`, run by
:func:`~ejsrl.app.headless.run_headless` into a CSV held in memory, whose values are read
back exactly (``repr`` of a float reads back as the same float). Nothing from one run
reaches the next but the imported module.
"""

from __future__ import annotations

import csv
import hashlib
import importlib.util
import io
import sys
import tempfile
import time
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ejsrl.app.sweep_design import Run

__all__ = ["AppRef", "LoadedApp", "RunOptions", "RunResult", "app_ref", "register", "loaded", "run_one", "run_batch"]

#: files of a built folder a remote worker does not need (it has its own runtime)
_SKIP = ("ejsrl/", "__pycache__/")


@dataclass(frozen=True)
class AppRef:
    """Where a worker finds the app: its folder, a digest of its files, and (for workers on
    other machines) the folder's files as a zip archive."""

    folder: str
    digest: str
    archive: bytes | None = field(default=None, repr=False)

    def with_archive(self) -> AppRef:
        """The same reference carrying the folder's files, for workers that may not see the folder."""
        return AppRef(self.folder, self.digest, _zip_folder(Path(self.folder)))


@dataclass
class LoadedApp:
    """An imported app: what ``ejsrl.app.main`` receives from a generated ``app.py``."""

    model_cls: Any
    view: list[Any]
    sim: Any
    meta: Any
    base_dir: Path


@dataclass(frozen=True)
class RunOptions:
    """What every run of a sweep records: ``duration``, ``variables`` (None: every numeric one), ``every`` N steps."""

    duration: float
    variables: tuple[str, ...] | None = None
    every: int = 1


@dataclass
class RunResult:
    """A finished run: its settings, status (``ok``, ``stopped``: the simulation paused itself,
    or ``error``), the error's text, the recorded columns and the metrics."""

    run: int
    settings: tuple[tuple[str, str], ...]
    status: str
    error: str = ""
    seconds: float = 0.0
    columns: list[str] = field(default_factory=list)
    kinds: list[str] = field(default_factory=list)
    data: list[Any] = field(default_factory=list)
    metrics: dict[str, Any] = field(default_factory=dict)


_CACHE: dict[str, LoadedApp] = {}


def _files(folder: Path) -> list[Path]:
    out = []
    for p in sorted(folder.rglob("*")):
        rel = p.relative_to(folder).as_posix()
        if p.is_file() and not any(rel.startswith(s) or f"/{s}" in rel for s in _SKIP) and not rel.endswith((".pyc", ".pyz")):
            out.append(p)
    return out


def app_ref(folder: str | Path) -> AppRef:
    """A reference to a built app folder (its ``app.py`` and assets), named by a digest of its files."""
    folder = Path(folder).resolve()
    if not (folder / "app.py").is_file():
        raise FileNotFoundError(f"no app.py in {folder}")
    h = hashlib.sha256()
    for p in _files(folder):
        h.update(p.relative_to(folder).as_posix().encode() + b"\0")
        h.update(p.read_bytes())
    return AppRef(str(folder), h.hexdigest())


def _zip_folder(folder: Path) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for p in _files(folder):
            zf.write(p, p.relative_to(folder).as_posix())
    return buf.getvalue()


def register(ref: AppRef, app: LoadedApp) -> None:
    """Make an app this process has already imported the one ``ref`` names (no second import)."""
    _CACHE[ref.digest] = app


def loaded(ref: AppRef) -> LoadedApp:
    """The app ``ref`` names, imported on first use in this process and kept."""
    app = _CACHE.get(ref.digest)
    if app is not None:
        return app
    folder = Path(ref.folder)
    if ref.archive is not None and not (folder / "app.py").is_file():
        folder = Path(tempfile.mkdtemp(prefix="ejsrl-sweep-"))
        with zipfile.ZipFile(io.BytesIO(ref.archive)) as zf:
            zf.extractall(folder)
    name = f"ejs_sweep_app_{ref.digest[:16]}"
    spec = importlib.util.spec_from_file_location(name, folder / "app.py")
    if spec is None or spec.loader is None:
        raise FileNotFoundError(f"no app.py in {folder}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # tracebacks and SPEC_LINES find the module
    spec.loader.exec_module(module)
    from ejsrl.app._loop import SimConfig

    app = LoadedApp(module.Model, module.VIEW, getattr(module, "SIMULATION", SimConfig()), module.META, folder)  # left out when all defaults
    _CACHE[ref.digest] = app
    return app


def _kind(value: Any) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "bool"
    if isinstance(value, (int, np.integer)):
        return "int"
    if isinstance(value, str):
        return "str"
    return "float"


def _column(values: list[str], kind: str) -> Any:
    """A column read back from the CSV: floats (exactly), integers, booleans or text."""
    if kind == "float":
        return np.array([float(v) for v in values], dtype=float)
    if kind == "int":
        try:
            return np.array([int(v) for v in values], dtype=np.int64)
        except ValueError:  # an integer variable that became a float during the run
            return np.array([float(v) for v in values], dtype=float)
    if kind == "bool":
        return np.array([v == "1" for v in values], dtype=bool)
    return list(values)


def _metric_value(value: Any) -> Any:
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(()).item()
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, float, np.integer, np.floating)):
        return float(value)
    if isinstance(value, str):
        return value
    what = f"an array of shape {value.shape}" if isinstance(value, np.ndarray) else f"a {type(value).__name__}"
    raise TypeError(f"it gave {what}; a metric is one number, boolean or text")


def metrics_of(model: Any) -> tuple[dict[str, Any], str]:
    """The spec's ``metrics:`` evaluated on the model's state now; the first error's text, if any."""
    from ejsrl.sim.model import describe_error

    getter = getattr(model, "_ejs_metrics", None)
    if getter is None:
        return {}, ""
    out: dict[str, Any] = {}
    first_error = ""
    for name, fn in getter().items():
        try:
            out[name] = _metric_value(fn())
        except Exception as exc:  # noqa: BLE001 - user code may raise anything
            err = describe_error(exc, type(model))
            where = f"{err.where}: " if err.where else ""
            out[name] = None
            first_error = first_error or f"{where}metric '{name}': {err.message}"
    return out, first_error


def run_one(app: LoadedApp, run: Run, options: RunOptions) -> RunResult:
    """One headless run with the run's ``--set`` settings; never raises for the model's errors."""
    from ejsrl.app._loop import App
    from ejsrl.app.cli import parse_set
    from ejsrl.app.headless import csv_columns
    from ejsrl.sim.model import SetValueError, UserCodeError

    start = time.perf_counter()
    result = RunResult(run.run, run.settings, "error")

    def done(error: str = "") -> RunResult:
        result.error = error.strip()
        result.seconds = time.perf_counter() - start
        return result

    model_cls = app.model_cls
    overrides: dict[str, Any] = {}
    try:
        for item in run.set_args():
            name, value = parse_set(item, model_cls.VARIABLES)
            overrides[name] = value
    except ValueError as exc:
        return done(f"error: {exc}")
    np.seterr(all="ignore")  # as a headless run: a non-finite state is reported, not warned about
    log = io.StringIO()
    try:
        inst = App(model_cls, app.view, sim=app.sim, meta=app.meta, base_dir=app.base_dir, overrides=overrides)
    except SetValueError as exc:
        return done(f"error: {exc}")
    names = list(options.variables) if options.variables is not None else None
    ind = model_cls.INDEPENDENT
    if names is not None and ind is not None and ind not in names:
        names.insert(0, ind)
    if inst.error is not None or ind is None:
        inst.run_headless(options.duration, log=log)
        return done(log.getvalue())
    try:
        getters = csv_columns(inst.model, names)
    except UserCodeError as exc:
        return done(f"error: {exc.message}")
    kinds = [_kind(get()) for _, get in getters]
    buf = io.StringIO()
    status = inst.run_headless(options.duration, csv_file=buf, variables=names, every=options.every, log=log)
    buf.seek(0)
    rows = list(csv.reader(buf))
    header, body = rows[0], rows[1:]
    result.columns = header
    result.kinds = kinds
    result.data = [_column([row[j] for row in body], kind) for j, kind in enumerate(kinds)]
    if status != 0:
        return done("\n".join(line for line in log.getvalue().splitlines() if not line.startswith("alert: ")))
    result.status = "ok" if inst.playing else "stopped"
    result.metrics, metric_error = metrics_of(inst.model)
    if metric_error:
        result.status = "error"
        return done(metric_error)
    return done()


def run_batch(ref: AppRef, runs: Sequence[Run], options: RunOptions) -> list[RunResult]:
    """Several runs in this process (the app imported once): what a pool or Dask task runs."""
    app = loaded(ref)
    return [run_one(app, run, options) for run in runs]
