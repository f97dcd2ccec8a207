"""The names spec code sees without imports, and the names a generated app uses itself.

One place for what ejsgen must know about names:

- the **prelude**: ``np``, the ``math`` names (:data:`MATH_NAMES`), and the methods of
  ``ModelBase`` that user code calls as bare names, each marked here with
  :func:`prelude` (``"control"``: play, pause...; ``"program"``: start/stop a robot program;
  ``"world"``: the named scene objects), and the motion commands of robot programs (the
  methods of ``ejsrl.sim.programs.Program`` marked ``"command"``);
- the names the generated app defines, which a spec's names must not take over:
  every attribute of ``ModelBase`` (variables and custom functions become attributes of the
  model), and every module-level name of ``app.py`` plus the parameters and locals of its
  generated methods (the spec's imports become module globals of ``app.py``).

The prelude lists are read from the marked methods, so a control added to ``ModelBase``
with ``@prelude("control")`` is known to the compiler, documented and reserved at once.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

__all__ = [
    "prelude",
    "PreludeName",
    "MATH_NAMES",
    "MATH_CONSTANTS",
    "PRELUDE_KINDS",
    "prelude_entries",
    "control_names",
    "command_names",
    "prelude_names",
    "model_attributes",
    "APP_GLOBALS",
    "METHOD_LOCALS",
    "PROGRAM_RUNNER",
    "RUNTIME_PREFIX",
]

F = TypeVar("F", bound=Callable[..., Any])

#: the kinds of prelude methods, in the order the language reference lists them
PRELUDE_KINDS: tuple[str, ...] = ("control", "program", "world", "command")
_MARK = "__ejs_prelude__"

#: the ``math`` names in the prelude (module globals of every app: ``from math import ...``)
MATH_NAMES: tuple[str, ...] = tuple(
    "sin cos tan asin acos atan atan2 sinh cosh tanh exp log log10 sqrt hypot floor ceil radians degrees pi e inf".split()
)
#: the math names that are numbers, not functions
MATH_CONSTANTS: frozenset[str] = frozenset({"pi", "e", "inf"})
_CONSTANT_DOCS = {"pi": "π = 3.14159...", "e": "e = 2.71828...", "inf": "floating-point positive infinity"}

#: names starting with this belong to the runtime (attributes such as ``_ejs_ctl``, ``_ejs_layout0``)
RUNTIME_PREFIX = "_ejs"

#: the module-level names every generated ``app.py`` binds besides the math names (its imports
#: and definitions; see templates/app.py.j2), including the imports the compiler adds for some
#: specs only (``runtime_imports``).
APP_GLOBALS: frozenset[str] = frozenset(
    {
        "annotations",  # from __future__ import annotations
        "np",
        "AppMeta",
        "SimConfig",
        "main",
        "CodePage",
        "EventDef",
        "ModelBase",
        "OdePage",
        "StateLayout",
        "E",
        "Model",
        "VIEW",
        "SIMULATION",
        "META",
        "ProgramDef",  # apps with robot programs
        "asset",  # apps whose code reads an asset: asset = app_assets(__file__)
        "app_assets",
    }
)

#: parameters and locals of the generated methods into which the spec's code and expressions
#: are written (``self``; ``t, y`` of an ODE page's rates, events and load; ``value`` of a view
#: setter; ``cmd`` of a program; ``pages``, ``layout``, ``out``, ``rates``): a module global of
#: the same name (an import) would be hidden inside them.
#: the parameter of a program's generator method through which its motion commands run
PROGRAM_RUNNER = "cmd"
METHOD_LOCALS: frozenset[str] = frozenset({"self", "t", "y", "value", PROGRAM_RUNNER, "pages", "layout", "out", "rates"})


def prelude(kind: str) -> Callable[[F], F]:
    """Mark a method as a prelude name that spec code calls by its bare name.

    ``kind`` is one of :data:`PRELUDE_KINDS`; the method's docstring (its first line) is
    what the language reference says about it.
    """
    if kind not in PRELUDE_KINDS:
        raise ValueError(f"prelude kind is one of {PRELUDE_KINDS}, not {kind!r}")

    def mark(fn: F) -> F:
        setattr(fn, _MARK, kind)
        return fn

    return mark


@dataclass(frozen=True)
class PreludeName:
    """A prelude name: ``kind`` (``"numpy"``, ``"math"`` or one of :data:`PRELUDE_KINDS`),
    the first line of its doc, and the function (None for ``np`` and math constants)."""

    name: str
    kind: str
    doc: str
    fn: Callable[..., Any] | None = None


def _first_line(fn: Any) -> str:
    import inspect

    return (inspect.getdoc(fn) or "").split("\n\n")[0].strip()


def _marked(cls: type, kinds: tuple[str, ...]) -> list[PreludeName]:
    found: list[PreludeName] = []
    seen: set[str] = set()
    for klass in cls.__mro__:
        for name, value in vars(klass).items():
            kind = getattr(value, _MARK, None)
            if kind in kinds and name not in seen:
                seen.add(name)
                found.append(PreludeName(name, kind, _first_line(value), value))
    return sorted(found, key=lambda p: PRELUDE_KINDS.index(p.kind))  # stable: definition order within a kind


def prelude_entries() -> list[PreludeName]:
    """Every prelude name, in the order the language reference lists them."""
    from ejsrl.sim.model import ModelBase
    from ejsrl.sim.programs import Program

    out = [PreludeName("np", "numpy", "NumPy (`np.array`, `np.linalg.norm`, ...)")]
    for name in MATH_NAMES:
        if name in MATH_CONSTANTS:
            out.append(PreludeName(name, "math", _CONSTANT_DOCS[name]))
        else:
            fn = getattr(math, name)
            out.append(PreludeName(name, "math", _first_line(fn), fn))
    out += _marked(ModelBase, ("control", "program", "world"))
    out += _marked(Program, ("command",))
    return out


def control_names() -> tuple[str, ...]:
    """The simulation controls, program controls and world functions (methods of the model)."""
    from ejsrl.sim.model import ModelBase

    return tuple(p.name for p in _marked(ModelBase, ("control", "program", "world")))


def command_names() -> tuple[str, ...]:
    """The motion commands of robot programs (statements of a program only)."""
    from ejsrl.sim.programs import Program

    return tuple(p.name for p in _marked(Program, ("command",)))


def prelude_names() -> tuple[str, ...]:
    """Every prelude name: ``np``, the math names, the controls and the program commands."""
    return ("np", *MATH_NAMES, *control_names(), *command_names())


def model_attributes() -> frozenset[str]:
    """Every attribute name ``ModelBase`` and its bases define (methods, class attributes, dunders)."""
    from ejsrl.sim.model import ModelBase

    return frozenset(dir(ModelBase))
