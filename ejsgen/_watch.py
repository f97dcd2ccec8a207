"""``ejsgen run --watch SPEC``: live editing. Every save of the spec rebuilds the lab and
reloads every open tab, keeping the values the author did not change.

The lab is served from this one process (:class:`ejsrl.app._reload.LiveLab`): the tool is
already imported, so a rebuild is the spec's compilation and the new ``app.py`` loaded as a
module, some tens of milliseconds, not the second a new ``ejsgen run`` takes.

- **What is watched**: the spec, every file it copies into the app (``assets:``, meshes,
  FMUs) and the local Python modules its ``imports:`` name (files outside the Python
  installation). Each is polled :data:`POLL_SECONDS` apart by modification time, size and
  inode (a save by renaming a new file over the old one); a file that moved is read only
  once it has kept them for :data:`SETTLE_SECONDS` (an editor may write in several steps), and a save that leaves the content as it was
  (the same SHA-256) rebuilds nothing.
- **The rule of kept values** (:func:`kept_variables`): a variable keeps its current value
  across the reload when its declaration (initial value or ``expr:``, and its type) is
  the same as before and it reads no variable whose declaration changed; the others take
  their new initial values. The independent variable is always kept, and so is playing
  or paused. The runtime also checks that the kept value has the shape of the new one.
- **A failed build** prints what ``ejsgen validate`` prints, each error followed by the
  offending line of the spec, and the open tabs show the same text instead of the lab; a
  build that fails waits :data:`ERROR_SETTLE_SECONDS` for a second write before saying
  so (half a save is not reported). The next good save brings the labs back.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import dataclasses
import hashlib
import importlib.util
import io
import shutil
import signal
import sys
import sysconfig
import time
import traceback
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from ejsgen.errors import EjsError, SpecError, SpecErrors
from ejsrl._signals import SignalScope

__all__ = ["kept_variables", "FileWatch", "Rebuilder", "Watcher", "error_report", "cmd_watch",
           "POLL_SECONDS", "SETTLE_SECONDS", "ERROR_SETTLE_SECONDS"]

#: seconds between two looks at the watched files
POLL_SECONDS = 0.1
#: a file that changed is read once its time and size have held this long (seconds)
SETTLE_SECONDS = 0.05
#: a build that failed is reported only if no file changed again within this time (seconds)
ERROR_SETTLE_SECONDS = 0.3
#: the longest a file may keep changing before it is read anyway (seconds)
MAX_SETTLE_SECONDS = 2.0


# -- which values are kept -------------------------------------------------------------------------


def _declarations(plan: Any) -> dict[str, tuple[str, tuple[str, ...]]]:
    """Each variable's (value type, initial-value code) in ``plan``, in declaration order."""
    return {v.name: (plan.variables.get(v.name, ""), tuple(line.text for line in v.init)) for v in plan.var_plans}


def _reads(code: Iterable[str]) -> set[str]:
    """The model variables (``self.NAME``) a variable's initial-value code reads."""
    names: set[str] = set()
    for text in code:
        try:
            tree = ast.parse(text)
        except SyntaxError:
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "self" \
                    and isinstance(node.ctx, ast.Load):
                names.add(node.attr)
    return names


def kept_variables(old: Any, new: Any) -> set[str]:
    """The variables of the plan ``new`` that keep their current values after a reload from ``old``.

    Kept: a variable declared in both with the same value type and the same initial value
    (or ``expr:``) that reads no variable whose declaration changed (``v: {expr: zeros(N)}``
    takes its new value when ``N``'s does), and the independent variable whatever its
    declaration. Everything else (a new variable, a changed one) takes its new initial value.
    """
    before, after = _declarations(old), _declarations(new)
    changed = {name for name, decl in after.items() if before.get(name) != decl}
    grew = True
    while grew:  # what reads a changed variable is changed (in declaration order: usually one pass)
        grew = False
        for name, (_vtype, code) in after.items():
            if name not in changed and _reads(code) & changed:
                changed.add(name)
                grew = True
    kept = set(after) - changed
    t = getattr(new, "independent", None)
    if t is not None and t in before and before[t][0] == after.get(t, ("",))[0]:
        kept.add(t)
    return kept


# -- watching files ------------------------------------------------------------------------------------


def _stat(path: Path) -> tuple[int, int, int] | None:
    """(modification time in ns, size, inode): an editor that saves by renaming a new file over
    the old one changes the inode."""
    try:
        st = path.stat()
    except OSError:
        return None
    return (st.st_mtime_ns, st.st_size, st.st_ino)


def _digest(path: Path) -> str | None:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


class FileWatch:
    """Polls a set of files for changes of content (see the module docstring).

    ``sleep`` and ``clock`` are the waits and the monotonic time (tests pass their own).
    """

    def __init__(self, paths: Iterable[Path], *, sleep: Callable[[float], None] = time.sleep,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.sleep, self.clock = sleep, clock
        self.paths: list[Path] = []
        self._stats: dict[Path, tuple[int, int, int] | None] = {}
        self._digests: dict[Path, str | None] = {}
        self.watch(paths)

    def watch(self, paths: Iterable[Path]) -> None:
        """Watch ``paths`` from now on: a file watched already keeps what was last seen of it
        (a save during a build is not missed); a new one is taken as it is now."""
        self.paths = list(dict.fromkeys(Path(p) for p in paths))
        self._stats = {p: self._stats[p] if p in self._stats else _stat(p) for p in self.paths}
        self._digests = {p: self._digests[p] if p in self._digests else _digest(p) for p in self.paths}

    @property
    def saved_at(self) -> float:
        """When the newest watched file was last written (seconds since the epoch)."""
        times = [s[0] for s in self._stats.values() if s is not None]
        return max(times) / 1e9 if times else time.time()

    def stats(self) -> dict[Path, tuple[int, int, int] | None]:
        return {p: _stat(p) for p in self.paths}

    def moved(self) -> bool:
        """Whether a file's time or size differs from the last look (without reading it)."""
        return self.stats() != self._stats

    def changed(self) -> bool:
        """Whether a file's content changed since the last call (waits for it to settle)."""
        stats = self.stats()
        if stats == self._stats:
            return False
        deadline = self.clock() + MAX_SETTLE_SECONDS
        while True:  # an editor may write in steps: read once the file has held still
            self.sleep(SETTLE_SECONDS)
            again = self.stats()
            if again == stats or self.clock() > deadline:
                break
            stats = again
        self._stats = stats
        digests = {p: _digest(p) for p in self.paths}
        if digests == self._digests:
            return False  # saved without a change, or touched
        self._digests = digests
        return True


# -- building ------------------------------------------------------------------------------------------


def error_report(exc: BaseException) -> str:
    """What ``ejsgen validate`` prints for ``exc``, each spec error followed by the line it is
    on and a caret under its column; for other errors, their message."""
    if isinstance(exc, SpecErrors):
        errors: list[SpecError] = list(exc.errors)
    elif isinstance(exc, SpecError):
        errors = [exc]
    elif isinstance(exc, EjsError):
        return str(exc)
    else:
        return "".join(traceback.format_exception_only(type(exc), exc)).strip()
    out: list[str] = []
    for e in errors:
        out.append(e.format())
        line = _spec_line(e.where.file, e.where.line)
        if line is not None:
            out.append(f"    {line}")
            out.append("    " + " " * max(0, e.where.col - 1) + "^")
    return "\n".join(out)


def _spec_line(file: str, line: int) -> str | None:
    try:
        lines = Path(file).read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError:
        return None
    return lines[line - 1].rstrip().expandtabs(4) if 1 <= line <= len(lines) else None


def _installed_paths() -> list[Path]:
    """Where installed code lives: the standard library, every site-packages folder (the
    user's too) and ejsgen's own packages (an editable install lives in a checkout)."""
    import site

    import ejsgen
    import ejsrl

    paths = {sysconfig.get_paths()[k] for k in ("stdlib", "platstdlib", "purelib", "platlib")}
    paths.add(site.getusersitepackages())
    paths.update(p for p in sys.path if Path(p).name in ("site-packages", "dist-packages"))
    found = [Path(p).resolve() for p in paths if p]
    return found + [Path(m.__file__).resolve().parent for m in (ejsgen, ejsrl)]


def local_modules(plan: Any) -> dict[str, Path]:
    """The modules the spec's ``imports:`` name that are files outside the Python
    installation and outside ejsgen (the author's own): module name -> file. They are
    watched, and imported afresh for every build."""
    installed = _installed_paths()
    out: dict[str, Path] = {}
    for text in getattr(plan, "user_imports", []):
        try:
            stmt = ast.parse(text).body[0]
        except (SyntaxError, IndexError):
            continue
        if isinstance(stmt, ast.ImportFrom) and stmt.module:
            names = [stmt.module]
        elif isinstance(stmt, ast.Import):
            names = [a.name for a in stmt.names]
        else:
            continue
        for name in names:
            if name.split(".")[0] in ("ejsrl", "ejsgen"):
                continue
            try:
                found = importlib.util.find_spec(name)
            except (ImportError, ValueError):
                continue
            origin = getattr(found, "origin", None)
            if not origin or not origin.endswith(".py"):
                continue
            path = Path(origin).resolve()
            if not any(path.is_relative_to(p) for p in installed):
                out[name] = path
    return out


def write_live_app(plan: Any, folder: Path) -> None:
    """Write ``app.py`` and the spec's files into ``folder``: a built app less its copy of
    the runtime (this process imports the installed one) and its README."""
    from ejsgen.generate import _asset_dest, _check_compiles, render_app

    text = render_app(plan)
    _check_compiles(text, "app.py")
    folder.mkdir(parents=True)
    (folder / "app.py").write_text(text, encoding="utf-8")
    for src, rel in plan.assets:
        dest = _asset_dest(folder, src, rel)
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, dest, follow_symlinks=False)


@dataclasses.dataclass
class Outcome:
    """One rebuild: ``build`` (an ``ejsrl.app._reload.Build``) and ``plan`` when it built,
    else ``error`` (the report); ``seconds``: how long building and loading took."""

    plan: Any = None
    build: Any = None
    error: str | None = None
    seconds: float = 0.0


class Rebuilder:
    """Builds the spec into numbered folders under ``root`` and loads each new app.

    ``sets``: the ``--set NAME=VALUE`` texts, parsed for every build's variables.
    """

    def __init__(self, spec: Path, root: Path, sets: list[str]) -> None:
        self.spec, self.root, self.sets = spec, root, sets
        self.count = 0
        self.modules: dict[str, Path] = {}

    def files(self, plan: Any) -> list[Path]:
        """The files to watch for ``plan`` (the last good build's): the spec, its copied files, its local modules."""
        return [self.spec, *(Path(src) for src, _rel in plan.assets), *self.modules.values()]

    def rebuild(self) -> Outcome:
        from ejsgen.cli import load_plan
        from ejsrl.app._reload import load_build
        from ejsrl.app.cli import parse_set

        start = time.perf_counter()
        try:
            plan = load_plan(self.spec)
            self.count += 1
            folder = self.root / f"build-{self.count}"
            write_live_app(plan, folder)
            self.modules = local_modules(plan)
            for name in list(sys.modules):  # the author's own modules are read again
                if any(name == m or name.startswith(m + ".") for m in self.modules):
                    del sys.modules[name]
            try:
                build = load_build(folder)
            except Exception as exc:  # noqa: BLE001 - module-level code of an import, say
                raise EjsError(f"{self.spec}: error: the built app does not load: {error_report(exc)}") from exc
            overrides: dict[str, Any] = {}
            for item in self.sets:
                try:
                    name, value = parse_set(item, build.model_cls.VARIABLES)
                except ValueError as exc:
                    raise EjsError(f"{self.spec}: error: {exc}") from None
                overrides[name] = value
            build = dataclasses.replace(build, overrides=overrides)
        except Exception as exc:  # noqa: BLE001 - whatever a half-written spec does, the server stays up
            return Outcome(error=error_report(exc), seconds=time.perf_counter() - start)
        return Outcome(plan=plan, build=build, seconds=time.perf_counter() - start)

    def drop_older(self, keep: Path) -> None:
        """Remove the build folders other than ``keep`` (no session uses them any more)."""
        for folder in self.root.glob("build-*"):
            if folder != keep:
                shutil.rmtree(folder, ignore_errors=True)


# -- the command ---------------------------------------------------------------------------------------


class _Stop(SignalScope):
    """SIGINT and SIGTERM raise ``KeyboardInterrupt`` in the main thread (the watch loop stops)."""

    def __init__(self) -> None:
        super().__init__()
        self.signum: int | None = None

    def _handle(self, signum: int, frame: object) -> None:
        if self.signum is None:
            self.signum = signum
            raise KeyboardInterrupt


def _refuse(args: argparse.Namespace) -> str | None:
    """Why the app options cannot go with ``--watch`` (None: they can)."""
    if args.headless or args.sweep or any(v is not None for v in (args.duration, args.csv, args.vars)):
        return "--watch serves the lab for live editing; run headless without --watch"
    if args.shared:
        return "--watch gives every tab a simulation of its own; leave --shared out"
    if args.processes is not None and args.processes != 1:
        return "--watch serves from one process (each rebuild is loaded into it); leave --processes out"
    if args.max_sessions is not None and args.max_sessions < 1:
        return "--max-sessions must be at least 1"
    if args.grace < 0 or args.grace != args.grace:
        return "--grace must be a number of seconds >= 0"
    return None


def _stamp() -> str:
    return time.strftime("%H:%M:%S")


def cmd_watch(spec: str, app_args: list[str], *, output: str | None = None,
              temporary: Callable[[str], Any] | None = None) -> int:
    """Serve ``spec`` and rebuild it on every save until SIGINT/SIGTERM; the exit status
    (2 for options that cannot go with ``--watch``, 128 + the signal's number when stopped).
    ``output``: also write the full app there after every good build (``-o DIR``);
    ``temporary(prefix)``: makes the folder the builds go to (a ``TemporaryDirectory``)."""
    import tempfile

    import numpy as np

    from ejsrl.app._loop import announce
    from ejsrl.app._reload import DEFAULT_SESSIONS, LiveLab
    from ejsrl.app.cli import _parser
    from ejsrl.view._guard import parse_origin

    path = Path(spec)
    args = _parser(path.name).parse_args(app_args)
    problem = _refuse(args)
    try:
        origins = [parse_origin(o) for o in args.allow_origin]
    except ValueError as exc:
        problem = problem or str(exc)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    np.seterr(all="ignore")  # as a served app: a state that becomes non-finite is reported instead
    stop = _Stop()
    lab = LiveLab(max_sessions=args.max_sessions or DEFAULT_SESSIONS, grace=args.grace)
    make_tmp = temporary or (lambda prefix: tempfile.TemporaryDirectory(prefix=prefix))
    with stop, make_tmp("ejsgen-watch-") as tmp:
        try:
            rebuilder = Rebuilder(path, Path(tmp), args.set)
            first = rebuilder.rebuild()
            watcher = Watcher(rebuilder, lab, first, output=output)
            title = first.build.meta.title if first.build is not None else path.name
            watcher.start(first)  # the build (or its error) is there before the first tab connects
            server = lab.start(args.host, args.port, allow_origins=origins, title=title)
            said = io.StringIO()
            with contextlib.redirect_stdout(said):  # where it serves (its warnings go to stderr as they are)
                announce(title, args.host, server.get_port(), places=lab.max_sessions, asked_port=args.port)
            for line in said.getvalue().splitlines():
                if "--shared" not in line:  # not with --watch
                    print(line)
            extra = len(watcher.watch.paths) - 1
            also = f" and the {extra} file{'s' if extra != 1 else ''} it names" if extra else ""
            print(f"  live editing: watching {path}{also}; every save rebuilds the lab and reloads its tabs "
                  f"(one process, up to {lab.max_sessions} tabs: --max-sessions N)", flush=True)
            watcher.run()
        except KeyboardInterrupt:
            pass
        finally:
            lab.stop()
    signum = stop.signum if stop.signum is not None else signal.SIGINT
    print(f"ejsgen run: stopped by {signal.Signals(signum).name}", file=sys.stderr, flush=True)
    return 128 + int(signum)


class Watcher:
    """The watch loop: looks at the files, rebuilds on a change, and swaps the build into
    ``lab`` (an ``ejsrl.app._reload.LiveLab``) or shows it the error.

    ``first``: the first build's outcome; ``output``: also write the full app there after
    every good build; ``sleep``: the waits (tests pass their own); ``log``: where the
    terminal's lines go (errors to ``err``).
    """

    def __init__(self, rebuilder: Rebuilder, lab: Any, first: Outcome, *, output: str | None = None,
                 sleep: Callable[[float], None] = time.sleep, log: Any = None, err: Any = None) -> None:
        self.rebuilder, self.lab, self.output, self.sleep = rebuilder, lab, output, sleep
        self.log = log if log is not None else sys.stdout
        self.err = err if err is not None else sys.stderr
        self.good = first if first.build is not None else None
        self.watch = FileWatch(rebuilder.files(first.plan) if first.plan is not None else [rebuilder.spec], sleep=sleep)
        #: the last good rebuild's line for the terminal (tests read its figures)
        self.last_report: Any = None

    def start(self, first: Outcome) -> None:
        """Serve the first build, or show its error."""
        if first.build is not None:
            self.lab.swap(first.build, set())
            _write_output(first.plan, self.output, self.err)
        else:
            self.lab.show_error(first.error or "")
            print(first.error, file=self.err, flush=True)

    def run(self) -> None:
        """Look every :data:`POLL_SECONDS` until interrupted."""
        while True:
            self.sleep(POLL_SECONDS)
            self.poll_once()

    def poll_once(self) -> str | None:
        """One look: ``"rebuilt"``, ``"error"`` (shown), ``"again"`` (a failed build of a file
        written again meanwhile: the next look builds it), or None (nothing changed)."""
        from ejsrl.app._reload import forget_build

        if not self.watch.changed():
            return None
        saved = self.watch.saved_at
        outcome = self.rebuilder.rebuild()
        if outcome.build is None:
            self.sleep(ERROR_SETTLE_SECONDS)
            if self.watch.moved():
                return "again"
            self.lab.show_error(outcome.error or "")
            print(f"[{_stamp()}] {self.rebuilder.spec}: the build failed; the open tabs show this until it is fixed:",
                  file=self.err)
            print(outcome.error, file=self.err, flush=True)
            return "error"
        good = self.good
        kept = kept_variables(good.plan, outcome.plan) if good is not None else set()
        report = self.lab.swap(outcome.build, kept)
        self.last_report = (outcome, report, time.time() - saved)
        print(f"[{_stamp()}] " + rebuilt_line(self.rebuilder.spec, outcome, report, good, time.time() - saved),
              file=self.log, flush=True)
        if good is not None:
            forget_build(good.build)
        self.rebuilder.drop_older(outcome.build.base_dir)
        self.watch.watch(self.rebuilder.files(outcome.plan))
        self.good = outcome
        _write_output(outcome.plan, self.output, self.err)
        return "rebuilt"


def rebuilt_line(spec: Path, outcome: Outcome, report: Any, good: Outcome | None, since_save: float) -> str:
    """The terminal's line for a good rebuild: its times, the tabs reloaded, what took new values."""
    fresh: list[str] = []
    if good is not None and report.carried is not None:
        carried = set(report.carried)
        fresh = [v.name for v in outcome.plan.var_plans if v.name not in carried]
    tabs = f"{report.tabs} tab{'s' if report.tabs != 1 else ''} reloaded"
    values = f"; new initial values: {', '.join(fresh)}" if fresh else ""
    return (f"{spec}: rebuilt in {outcome.seconds + report.seconds:.3f} s (build {outcome.seconds:.3f} s, "
            f"reload {report.seconds:.3f} s; {since_save:.3f} s after the save): {tabs}{values}")


def _write_output(plan: Any, output: str | None, err: Any) -> None:
    if output is None or plan is None:
        return
    from ejsgen.generate import write_app

    try:
        write_app(plan, Path(output))
    except EjsError as exc:
        print(f"warning: could not write {output}: {exc}", file=err, flush=True)
