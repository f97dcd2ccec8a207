"""The plan of a generated app: every decision made, as data the emitter lays out.

The compiler fills an :class:`AppPlan`: the variables (with their unit and doc), the methods
of the ``Model`` class (each line knowing the spec location it came from, so ``app.py`` can
map a run-time error back to the spec), the ODE pages (:class:`OdePlan`) and the view as a
tree of runtime calls (:class:`Call`: the runtime function's name, positional and keyword
arguments). ``ejsgen.emit`` turns the plan into Python text; nothing here is a runtime
signature written as text.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ejsgen.errors import Location

__all__ = [
    "Line",
    "Method",
    "Variable",
    "Expr",
    "Ref",
    "Call",
    "EventPlan",
    "OdePlan",
    "ProgramPlan",
    "AppPlan",
    "Src",
    "py",
    "body_lines",
]


@dataclass
class Line:
    """One line of generated code and the spec location it came from (or None)."""

    text: str
    where: Location | None = None


@dataclass
class Method:
    """A method of the generated ``Model`` class: ``def name(params):`` and its body lines.

    ``raw``: ``lines`` are the whole method as the author wrote it (a custom function), ``def``
    line included.
    """

    name: str
    params: str
    doc: str
    lines: list[Line]
    comment: str = ""
    raw: bool = False


@dataclass
class Variable:
    """A model variable: ``init`` holds the lines that give its initial value (``self.x = ...``)."""

    name: str
    vtype: str
    init: list[Line]
    unit: str | None = None
    doc: str | None = None


class Src(str):
    """A piece of Python source (emitted as is by :func:`py`)."""


@dataclass
class Expr:
    """A rewritten spec expression (``self.x + 1``), where it is in the spec, and its spec text.

    ``lam``: None for the expression itself, else the parameters of a lambda returning it:
    ``"self"`` for ``lambda self: <source>`` (a view property computed from the model),
    ``""`` for ``lambda: <source>`` (inside a method, where ``self`` is the model).
    """

    source: str
    where: Location | None = None
    text: str = ""
    lam: str | None = None


@dataclass
class Ref:
    """A reference to a method of the model: ``Model.name`` (in the view) or ``self.name``."""

    name: str
    owner: str = "Model"


@dataclass
class Call:
    """A call of a runtime function or class: ``fn(*args, **kwargs)``.

    ``fn`` is a dotted name as the app imports it (``E.Slider``, ``OdePage.of``, ``SimConfig``);
    ``children``: the keyword whose value is a list of nested calls, laid out one per line.
    A keyword whose value is the runtime's default is not written, unless it is in ``keep``.
    """

    fn: str
    args: list[Any] = field(default_factory=list)
    kwargs: dict[str, Any] = field(default_factory=dict)
    children: str | None = None
    keep: tuple[str, ...] = ()

    def walk(self) -> Any:
        """This call and every call nested in its arguments."""
        yield self
        for v in [*self.args, *self.kwargs.values()]:
            yield from _calls_in(v)


def _calls_in(value: Any) -> Any:
    if isinstance(value, Call):
        yield from value.walk()
    elif isinstance(value, (list, tuple)):
        for v in value:
            yield from _calls_in(v)
    elif isinstance(value, dict):
        for v in value.values():
            yield from _calls_in(v)


@dataclass
class EventPlan:
    """An event of an ODE page: ``when`` crosses zero in ``direction``; ``action`` a method or None."""

    name: str
    when: Expr
    direction: str
    action: str | None
    stop: bool
    where: str


@dataclass
class OdePlan:
    """An ODE page: ``rates`` maps each state variable to its rewritten rate expression (the
    states in order); ``rates_method`` computes them all (a method, or a lambda when short)."""

    title: str
    independent: str
    rates: dict[str, Expr]
    method: str
    step: Expr | float
    rates_method: str | Expr  # a method's name, or a short list of the rates inline
    preliminary: str | None = None
    events: list[EventPlan] = field(default_factory=list)
    tolerance: float = 1e-6
    max_step: float | None = None
    enabled: bool = True
    where: str = ""


@dataclass
class ProgramPlan:
    """A robot program: its generator method and the variables it drives."""

    name: str
    method: str
    robot: str | None
    q: str | None
    gripper: str | None
    autostart: bool
    where: str


@dataclass
class AppPlan:
    """Everything the emitter needs to write an app."""

    spec_name: str
    title: str
    description: str
    author: str
    user_imports: list[str]
    variables: dict[str, str]
    independent: str | None
    methods: list[Method]
    view: list[Call]
    sim: dict[str, Any]
    assets: list[tuple[Path, str]] = field(default_factory=list)
    after_class: list[str] = field(default_factory=list)
    runtime_imports: list[str] = field(default_factory=list)
    var_plans: list[Variable] = field(default_factory=list)
    pages: list[OdePlan | Call] = field(default_factory=list)
    programs: list[ProgramPlan] = field(default_factory=list)
    #: the lab uses OpenCV (its requirements list it); ``ejsgen.cli.load_plan`` decides from the spec
    uses_opencv: bool = True

    @property
    def view_lines(self) -> list[str]:
        """The ``VIEW = [...]`` assignment as app.py has it."""
        from ejsgen.emit import view_lines

        return [line.text for line in view_lines(self.view)]

    def calls(self) -> list[Call]:
        """Every runtime call the app makes outside the model's own code (view, pages, settings)."""
        from ejsgen.emit import module_calls

        return [c for top in module_calls(self) for c in top.walk()]


def py(value: Any) -> str:
    """Python source for a constant (numbers, strings, bools, None, lists, tuples, dicts) or ``Src``."""
    if isinstance(value, Src):
        return str(value)
    if isinstance(value, bool) or value is None:
        return repr(value)
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (int, str)):
        return repr(value)
    if isinstance(value, tuple):
        inner = ", ".join(py(v) for v in value)
        return f"({inner},)" if len(value) == 1 else f"({inner})"
    if isinstance(value, list):
        return "[" + ", ".join(py(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{py(k)}: {py(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot emit {value!r}")


def body_lines(stmts: list[ast.stmt], where_of: Any) -> list[Line]:
    """Unparse statements into lines, mapping each line to the spec location of its node.

    ``where_of(node)`` gives the ``Location`` of an original node (with its snippet's
    ``lineno``/``col_offset``). The unparsed text is parsed again and walked in step with
    the original tree, which has the same shape, to carry locations over. (Used when the
    author's text cannot be kept, see ``_resolve.rewrite_source``.)
    """
    module = ast.Module(body=stmts, type_ignores=[])
    text = ast.unparse(module)
    again = ast.parse(text)
    mapping: dict[int, Location] = {}
    for orig, new in zip(ast.walk(module), ast.walk(again)):
        if type(orig) is not type(new):
            break
        if isinstance(new, (ast.stmt, ast.expr)) and hasattr(orig, "lineno"):
            mapping.setdefault(new.lineno, where_of(orig))
    lines: list[Line] = []
    last: Location | None = None
    for i, text_line in enumerate(text.splitlines(), start=1):
        where = mapping.get(i, last)
        lines.append(Line(text_line, where))
        last = where
    return lines
