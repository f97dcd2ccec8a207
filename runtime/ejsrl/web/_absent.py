"""What viser's modules import but a browser build has no use for, made importable there.

The WebAssembly Python has no sockets and no threads, so viser's websocket server
(``websockets``), its compression (``zstandard``) and its console printing (``rich``) cannot
run; the page's own channel (:mod:`ejsrl.web._server`) takes their place. viser imports them at
module level, though, so :func:`install` registers:

- ``msgspec`` with ``msgspec.msgpack`` = :mod:`ejsrl.web._msgpack` (a real codec: the guard and
  viser's ``Message.deserialize`` decode every client message with it);
- for every name in :data:`ABSENT` (only where the real package cannot be imported), a module
  whose every attribute is a class that raises :class:`NotInBrowser` when used, naming the
  module. Importing succeeds; using one says plainly that it does not run in a browser;
- except for :data:`QUIET` packages (console decoration: viser's banner through ``rich``),
  whose every attribute does nothing: a browser tab has no terminal to print to.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import sys
import types
from typing import Any

__all__ = ["ABSENT", "NotInBrowser", "install"]

#: top-level packages imported by viser (or the runtime) that cannot run in a browser
ABSENT = ("websockets", "zstandard", "rich", "cv2", "ssl")
#: a package that imports but cannot work without this extension module (``ssl`` without ``_ssl``)
NEEDS = {"ssl": "_ssl"}
#: of those, the ones whose use does nothing instead of raising (they only print to a terminal)
QUIET = ("rich",)


class NotInBrowser(RuntimeError):
    """A feature that needs what a browser build does not have (sockets, threads, OpenCV)."""


def _placeholder(module: str, name: str) -> type:
    def refuse(*_args: Any, **_kwargs: Any) -> Any:
        raise NotInBrowser(f"{module}.{name} is not available in a lab running in the browser (ejsgen build --web)")

    return type(name, (), {"__new__": lambda cls, *a, **k: refuse(), "__init_subclass__": classmethod(lambda cls, **k: None),
                           "__module__": module, "__call__": refuse})


class _Quiet:
    """Anything from a :data:`QUIET` package: made, called, read or used as a context, it does nothing."""

    def __init__(self, *_args: Any, **_kwargs: Any) -> None:
        return None

    def __call__(self, *_args: Any, **_kwargs: Any) -> _Quiet:
        return _Quiet()

    def __getattr__(self, name: str) -> _Quiet:
        return _Quiet()

    def __enter__(self) -> _Quiet:
        return self

    def __exit__(self, *_exc: Any) -> None:
        return None


class _Absent(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    def __init__(self, missing: tuple[str, ...]) -> None:
        self.missing = missing

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> importlib.machinery.ModuleSpec | None:
        if name.split(".")[0] not in self.missing:
            return None
        return importlib.machinery.ModuleSpec(name, self, is_package=True)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        module = types.ModuleType(spec.name, f"{spec.name}: not available in a browser build")
        module.__path__ = []  # a package, so its submodules import too
        if spec.name.split(".")[0] in QUIET:
            module.__getattr__ = lambda name: _Quiet()  # type: ignore[method-assign]
        else:
            module.__getattr__ = lambda name, m=spec.name: _placeholder(m, name)  # type: ignore[method-assign]
        return module

    def exec_module(self, module: types.ModuleType) -> None:
        return None


def install() -> None:
    """Make ``msgspec.msgpack`` and the :data:`ABSENT` packages importable (idempotent). A
    package that really is importable is left alone."""
    from ejsrl.web import _msgpack

    if "msgspec" not in sys.modules and importlib.util.find_spec("msgspec") is None:
        msgspec = types.ModuleType("msgspec", "msgspec.msgpack for a browser build (ejsrl.web._msgpack)")
        msgspec.msgpack = _msgpack  # type: ignore[attr-defined]
        msgspec.DecodeError = _msgpack.DecodeError  # type: ignore[attr-defined]
        msgspec.EncodeError = _msgpack.EncodeError  # type: ignore[attr-defined]
        sys.modules["msgspec"] = msgspec
        sys.modules["msgspec.msgpack"] = _msgpack
    if not any(isinstance(f, _Absent) for f in sys.meta_path):
        missing = tuple(n for n in ABSENT if n not in sys.modules and not _importable(n))
        if missing:
            sys.meta_path.insert(0, _Absent(missing))  # answers only for what cannot be imported here


def _importable(name: str) -> bool:
    """Whether ``name`` (and the extension module it needs, see :data:`NEEDS`) can be imported."""
    needed = NEEDS.get(name)
    if needed is not None and importlib.util.find_spec(needed) is None:
        return False
    return importlib.util.find_spec(name) is not None
