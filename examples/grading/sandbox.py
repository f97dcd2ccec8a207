"""Run a command of a hand-in in an OS sandbox: Debian's bubblewrap, with limits.

Spec code is Python and runs with the rights of whoever runs it: a hand-in can import
``os`` and do anything the teacher can. ``contained(cmd, writable=DIR)`` runs ``cmd`` with

- the whole file system **read-only** but ``DIR`` (its own output folder) and a private,
  empty ``/tmp``;
- **no network** (a network namespace of its own, with no interface up);
- its own process, IPC and UTS namespaces; it dies with the grader (``--die-with-parent``);
- **limits**: ``cpu_seconds`` of CPU time (RLIMIT_CPU), ``memory_mb`` of address space
  (RLIMIT_AS) and ``wall_seconds`` of real time (then it is killed).

It returns a ``Contained``: the status, the output, and ``reason``, the limit it hit in words
(``"used more than 20 s of CPU time"``), or ``""``. Needs ``bwrap`` (``apt-get install
bubblewrap``; ``scripts/setup.sh`` installs it).
"""

from __future__ import annotations

import os
import resource
import shutil
import signal
import subprocess
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Contained", "Limits", "contained", "bwrap_hint"]


@dataclass(frozen=True)
class Limits:
    """Per command: CPU seconds, memory (MB of address space) and wall-clock seconds."""

    cpu_seconds: float = 60.0
    memory_mb: int = 3000
    wall_seconds: float = 120.0


@dataclass
class Contained:
    """What a contained command did: ``status`` (negative: killed by that signal), its
    ``stdout`` and ``stderr``, and ``reason``: the limit it hit, in words (or "")."""

    status: int
    stdout: str
    stderr: str
    reason: str = ""


def bwrap_hint() -> str | None:
    """Why hand-ins cannot be contained here (None when they can)."""
    if shutil.which("bwrap") is None:
        return "grading runs each hand-in in bubblewrap, which is not installed: apt-get install bubblewrap (scripts/setup.sh does)"
    return None


def _python_under_tmp() -> list[Path]:
    """This Python's installation and import path where they lie under ``/tmp`` (a venv made
    there), which the sandbox's empty ``/tmp`` would hide: shown read-only."""
    tmp = Path("/tmp").resolve()
    found: list[Path] = []
    for entry in (sys.prefix, sys.exec_prefix, sys.base_prefix, *sys.path):
        if not entry:
            continue
        path = Path(entry).resolve()
        if path.is_dir() and path != tmp and tmp in path.parents and not any(f == path or f in path.parents for f in found):
            found.append(path)
    return found


def contained(
    cmd: Sequence[str], *, writable: Path, readable: Sequence[Path] = (), limits: Limits = Limits(), cwd: Path | None = None
) -> Contained:
    """Run ``cmd`` in the sandbox (see the module docstring); ``writable`` must exist.

    ``readable``: folders under ``/tmp`` the command must read (the rest of ``/tmp`` is hidden).
    """
    bwrap = shutil.which("bwrap")
    if bwrap is None:
        raise RuntimeError(bwrap_hint())
    writable = writable.resolve()
    args = [
        bwrap, "--ro-bind", "/", "/", "--dev", "/dev", "--proc", "/proc", "--tmpfs", "/tmp",
        *[arg for r in [*readable, *_python_under_tmp()] for arg in ("--ro-bind", str(r.resolve()), str(r.resolve()))],
        "--bind", str(writable), str(writable), "--unshare-all", "--die-with-parent", "--new-session",
        "--chdir", str((cwd or writable).resolve()), "--", *cmd,
    ]
    cpu = max(1, int(limits.cpu_seconds))
    memory = int(limits.memory_mb) * 1024 * 1024

    def apply_limits() -> None:  # in the child, before bwrap starts: inherited by everything it runs
        resource.setrlimit(resource.RLIMIT_CPU, (cpu, cpu + 2))
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))

    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1", EJSRL_PROCESSES="1")
    proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=apply_limits, start_new_session=True, env=env)
    try:
        out, err = proc.communicate(timeout=limits.wall_seconds)
    except subprocess.TimeoutExpired:
        _kill(proc)
        out, err = proc.communicate()
        return Contained(proc.returncode, out, err, f"ran longer than {limits.wall_seconds:g} s and was stopped")
    except BaseException:  # SIGTERM/Ctrl+C of the grader: the hand-in goes with it
        _kill(proc)
        proc.wait()
        raise
    return Contained(proc.returncode, out, err, _reason(proc.returncode, err, limits))


def _kill(proc: subprocess.Popen[str]) -> None:
    """Kill bwrap's process group; the sandbox's processes die with bwrap (its PID namespace ends)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def _reason(status: int, stderr: str, limits: Limits) -> str:
    if status in (-signal.SIGXCPU, 128 + signal.SIGXCPU, -signal.SIGKILL, 128 + signal.SIGKILL) and status != 0:
        return f"used more than {limits.cpu_seconds:g} s of CPU time and was stopped"
    if "MemoryError" in stderr or "Cannot allocate memory" in stderr or "std::bad_alloc" in stderr:
        return f"used more than {limits.memory_mb} MB of memory and was stopped"
    return ""
