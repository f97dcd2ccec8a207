"""Package re-exports imported on first use (PEP 562 module ``__getattr__``).

A package such as ``ejsrl.vision`` re-exports names from modules that need OpenCV. Imported
eagerly, the package (and everything that imports any of its modules, e.g. the world's
renderer importing ``ejsrl.vision.camera``) needs OpenCV too, and every app pays for
importing it at start-up. With ``lazy_exports`` the package imports nothing: each name is
imported from its module the first time it is read, then kept in the package's namespace, so
``from ejsrl.vision import CameraModel`` works where OpenCV does not (a browser's WebAssembly
Python), and ``from ejsrl.vision import canny`` fails there with OpenCV's ``ImportError``.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from collections.abc import Callable, Iterable, Mapping
from typing import Any

__all__ = ["lazy_exports"]


def lazy_exports(package: str, exports: Mapping[str, Iterable[str]]) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for ``package`` (its ``__name__``); the package keeps its own ``__all__``.

    ``exports`` maps a module (absolute, or relative to the package: ``".camera"``) to the
    names the package re-exports from it. Reading a listed name imports its module (an
    ``ImportError`` there, e.g. no ``cv2``, propagates as such); reading a submodule's name
    (``ejsrl.vision.markers``) imports it, as the eager package did; any other name is an
    ``AttributeError``, so ``hasattr`` works.
    """
    where = {name: module for module, names in exports.items() for name in names}
    namespace = sys.modules[package].__dict__

    def __getattr__(name: str) -> Any:
        module = where.get(name)
        if module is not None:
            value = getattr(importlib.import_module(module, package), name)
        elif not name.startswith("__") and importlib.util.find_spec(f"{package}.{name}") is not None:
            value = importlib.import_module(f"{package}.{name}")
        else:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(where))

    return __getattr__, __dir__
