"""Run a command of a spec you did not write in an OS sandbox: Debian's bubblewrap, with limits.

Spec code is Python and runs with the rights of whoever runs it: a hand-in can import
``os`` and do anything the teacher can. ``contained(cmd, writable=DIR)`` runs ``cmd`` with

- only the system's folders (programs, libraries, settings: :data:`SYSTEM_DIRS`, secrets such
  as ``/etc/shadow`` hidden), this Python and its packages, and what the caller shows
  (``readable``: the hand-in, see :func:`handin_files`), all **read-only**; ``DIR`` (its own
  output folder) writable; a private, empty ``/tmp`` (a tmpfs of at most ``Limits.file_mb``).
  Homes, ``/work``, ``/srv``, other hand-ins are not there at all: a hand-in reads nothing
  of the teacher's;
- **no network** (a network namespace of its own, with no interface up);
- its own process, IPC and UTS namespaces; it dies with its parent (``--die-with-parent``);
- **limits**: ``cpu_seconds`` of CPU time (RLIMIT_CPU), ``memory_mb`` of address space
  (RLIMIT_AS), ``file_mb`` per file written (RLIMIT_FSIZE) and ``wall_seconds`` of real time
  (then it is killed), set by util-linux's ``prlimit`` before ``bwrap`` starts (so a parent
  with threads forks nothing that runs Python).

It returns a ``Contained``: the status, the end of its output, and ``reason``, the limit it
hit in words (``"used more than 20 s of CPU time and was stopped"``), or ``""``. Its output
goes to files of the parent's (at most ``file_mb`` each), of which only the last
``TAIL_BYTES`` are read: a command that prints without end cannot fill the parent's memory.
A ``stop`` event (set by another thread) kills it at once; so does an exception in the
waiting thread (SIGTERM or Ctrl+C of the parent).

Used by ``ejsgen sweep --sandbox`` (:mod:`ejsgen.sweep`) and the grading recipe
(``examples/grading/grade.py``). Needs ``bwrap`` (``apt-get install bubblewrap``;
``scripts/setup.sh`` installs it).
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO

__all__ = ["SYSTEM_DIRS", "TAIL_BYTES", "Contained", "Limits", "bwrap_hint", "contained", "handin_files"]

TAIL_BYTES = 64 * 1024
"""How much of the end of a contained command's standard output and error is kept."""


@dataclass(frozen=True)
class Limits:
    """Per command: CPU seconds, memory (MB of address space), wall-clock seconds, and MB per
    file written (its private ``/tmp`` holds at most that much too)."""

    cpu_seconds: float = 60.0
    memory_mb: int = 3000
    wall_seconds: float = 120.0
    file_mb: int = 1000


@dataclass
class Contained:
    """What a contained command did: ``status`` (negative: killed by that signal), the last
    ``TAIL_BYTES`` of its ``stdout`` and ``stderr``, ``reason``: the limit it hit, in words (or
    ""), and ``stopped``: killed because the ``stop`` event was set."""

    status: int
    stdout: str
    stderr: str
    reason: str = ""
    stopped: bool = False


def bwrap_hint(what: str = "grading") -> str | None:
    """Why specs cannot be contained here (None when they can); ``what`` names the user."""
    if shutil.which("bwrap") is None:
        return f"{what} runs each hand-in in bubblewrap, which is not installed: apt-get install bubblewrap (scripts/setup.sh does)"
    if shutil.which("prlimit") is None:
        return f"{what} sets each hand-in's limits with prlimit, which is not installed: apt-get install util-linux"
    return None


def _packages() -> list[Path]:
    """The folders ejsgen, its templates and ejsrl are imported from: an editable install finds
    them through a finder of its own (not ``sys.path``), whose targets must be shown."""
    import ejsrl

    import ejsgen
    import ejsgen.templates

    return [Path(p).resolve() for m in (ejsgen, ejsgen.templates, ejsrl) for p in m.__path__]


#: the system's folders a contained command sees (read-only): programs, libraries, settings;
#: not homes (/root, /home), /work, /srv, /var, /mnt, /opt, ...: a hand-in reads nothing of the
#: teacher's, nor another student's
SYSTEM_DIRS = ("/usr", "/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32", "/etc", "/sys")
#: inside those, what is hidden all the same (secrets readable by root)
SECRETS = ("/etc/shadow", "/etc/gshadow", "/etc/shadow-", "/etc/gshadow-", "/etc/ssh", "/etc/sudoers", "/etc/sudoers.d",
           "/etc/ssl/private")


def handin_files(spec: Path) -> list[Path]:
    """What of a hand-in a contained build may read: its folder when the spec is the only spec
    in it (a hand-in brings its meshes and data files in a folder of its own), else only the
    spec file (hand-ins side by side in one folder must not read each other)."""
    spec = spec.resolve()
    others = [p for p in spec.parent.glob("*.ejs.y*ml") if p.resolve() != spec]
    return [spec] if others else [spec.parent]


def _python_dirs() -> list[Path]:
    """This Python's installation (its prefixes, site-packages and ``PYTHONPATH``) and the
    ejsgen/ejsrl packages, wherever they are (a venv, pyenv under /root, a checkout under /tmp),
    shown read-only, not the folders around them (the script's folder, a teacher's checkout
    holding the reference, are not there)."""
    import site

    entries = [sys.prefix, sys.exec_prefix, sys.base_prefix, *site.getsitepackages(),
               *os.environ.get("PYTHONPATH", "").split(os.pathsep), *_packages()]
    found: list[Path] = []
    for entry in entries:
        if not entry:
            continue
        path = Path(entry).resolve()
        if path.is_dir() and path != Path("/") and not any(f == path or f in path.parents for f in found):
            found = [f for f in found if path not in f.parents]
            found.append(path)
    return found


def _mounts(shown: Sequence[Path]) -> list[str]:
    """bwrap's arguments for the system's folders, the secrets hidden in them, and ``shown``."""
    args: list[str] = []
    for folder in SYSTEM_DIRS:
        if os.path.islink(folder):  # Debian's /bin -> usr/bin
            args += ["--symlink", os.readlink(folder), folder]
        elif os.path.isdir(folder):
            args += ["--ro-bind", folder, folder]
    for secret in SECRETS:
        if os.path.isdir(secret) and not os.path.islink(secret):
            args += ["--tmpfs", secret, "--remount-ro", secret]
        elif os.path.lexists(secret):
            args += ["--ro-bind", "/dev/null", secret]
    for path in shown:
        args += ["--ro-bind", str(path), str(path)]
    return args


def _command(cmd: Sequence[str], writable: Path, readable: Sequence[Path], limits: Limits, cwd: Path | None) -> list[str]:
    """``prlimit ... bwrap ... -- cmd``: the limits first (inherited by everything bwrap runs)."""
    bwrap, prlimit = shutil.which("bwrap"), shutil.which("prlimit")
    if bwrap is None or prlimit is None:
        raise RuntimeError(bwrap_hint("the sandbox"))
    cpu = max(1, int(limits.cpu_seconds))
    memory = int(limits.memory_mb) * 1024 * 1024
    fsize = int(limits.file_mb) * 1024 * 1024
    shown = [p.resolve() for p in [*_python_dirs(), *readable]]
    return [
        prlimit, f"--cpu={cpu}:{cpu + 2}", f"--as={memory}:{memory}", f"--fsize={fsize}:{fsize}", "--core=0:0", "--",
        bwrap, *_mounts(shown), "--dev", "/dev", "--proc", "/proc", "--size", str(fsize), "--tmpfs", "/tmp",
        *[arg for r in shown if Path("/tmp") in r.parents for arg in ("--ro-bind", str(r), str(r))],
        "--remount-ro", "/", "--bind", str(writable), str(writable), "--unshare-all", "--die-with-parent", "--new-session",
        "--chdir", str((cwd or writable).resolve()), "--", *cmd,
    ]


def contained(
    cmd: Sequence[str],
    *,
    writable: Path,
    readable: Sequence[Path] = (),
    limits: Limits = Limits(),
    cwd: Path | None = None,
    stop: threading.Event | None = None,
    env: Mapping[str, str] | None = None,
) -> Contained:
    """Run ``cmd`` in the sandbox (see the module docstring); ``writable`` must exist.

    ``readable``: folders under ``/tmp`` the command must read (the rest of ``/tmp`` is hidden);
    ``env``: variables added to this process's environment.
    """
    writable = writable.resolve()
    args = _command(cmd, writable, readable, limits, cwd)
    environ = dict(os.environ, PYTHONDONTWRITEBYTECODE="1", EJSRL_PROCESSES="1", **(env or {}))
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=out, stderr=err, start_new_session=True, env=environ)
        reason, stopped = "", False
        try:
            deadline = time.monotonic() + limits.wall_seconds
            while True:
                try:
                    proc.wait(timeout=max(0.0, min(0.2, deadline - time.monotonic())))
                    break
                except subprocess.TimeoutExpired:
                    if stop is not None and stop.is_set():
                        stopped, reason = True, "stopped"
                    elif time.monotonic() >= deadline:
                        reason = f"ran longer than {limits.wall_seconds:g} s and was stopped"
                    else:
                        continue
                    _kill(proc)
                    proc.wait()
                    break
        except BaseException:  # SIGTERM/Ctrl+C of the parent: the contained command goes with it
            _kill(proc)
            proc.wait()
            raise
        stdout, stderr = _tail(out), _tail(err)
    return Contained(proc.returncode, stdout, stderr, reason or _reason(proc.returncode, stderr, limits), stopped)


def _tail(fh: IO[bytes]) -> str:
    size = fh.seek(0, os.SEEK_END)
    fh.seek(max(0, size - TAIL_BYTES))
    return fh.read().decode("utf-8", errors="replace")


def _kill(proc: subprocess.Popen[bytes]) -> None:
    """Kill bwrap's process group; the sandbox's processes die with bwrap (its PID namespace ends)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def _reason(status: int, stderr: str, limits: Limits) -> str:
    """The limit a command that ended by itself hit, in words ("" when none)."""
    if status in (-signal.SIGXCPU, 128 + signal.SIGXCPU, -signal.SIGKILL, 128 + signal.SIGKILL):
        return f"used more than {limits.cpu_seconds:g} s of CPU time and was stopped"
    if status in (-signal.SIGXFSZ, 128 + signal.SIGXFSZ) or "File too large" in stderr:
        return f"wrote a file larger than {limits.file_mb} MB and was stopped"
    if "MemoryError" in stderr or "Cannot allocate memory" in stderr or "std::bad_alloc" in stderr:
        return f"used more than {limits.memory_mb} MB of memory and was stopped"
    if "No space left on device" in stderr:
        return f"filled its {limits.file_mb} MB /tmp and was stopped"
    for name in ("ejsgen", "ejsrl"):
        if f"No module named {name}" in stderr or f"No module named '{name}'" in stderr:
            return (f"could not import {name} in the sandbox, which shows the file system read-only with an empty /tmp: "
                    f"install ejsgen where the sandbox sees it (a checkout and venv outside /tmp, then pip install -e .)")
    return ""
