"""The plan of a generated app: every decision made, ready for the templates to lay out.

Method bodies are lists of ``Line`` s, each knowing the spec location it came from, so
the generated ``app.py`` can map a run-time error back to the spec.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ejsgen.errors import Location

__all__ = ["Line", "Method", "AppPlan", "Src", "py", "body_lines"]


@dataclass
class Line:
    """One line of generated code and the spec location it came from (or None)."""

    text: str
    where: Location | None = None


@dataclass
class Method:
    """A method of the generated ``Model`` class."""

    name: str
    params: str
    doc: str
    lines: list[Line]
    comment: str = ""


@dataclass
class AppPlan:
    """Everything the templates need to write an app."""

    spec_name: str
    title: str
    description: str
    author: str
    user_imports: list[str]
    variables: dict[str, str]
    independent: str | None
    methods: list[Method]
    view_lines: list[str]
    sim: dict[str, Any]
    assets: list[tuple[Path, str]] = field(default_factory=list)
    after_class: list[str] = field(default_factory=list)
    runtime_imports: list[str] = field(default_factory=list)


class Src(str):
    """A piece of Python source (emitted as is by :func:`py`)."""


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
    the original tree, which has the same shape, to carry locations over.
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
