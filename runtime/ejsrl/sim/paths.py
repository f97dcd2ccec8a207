"""Bind paths: a model variable (``"L"``) or one element of an array variable (``"q[2]"``).

A view control or gizmo names what it shows and edits by its spec ``bind:`` text; the
runtime turns that text into a reader and a writer here, so a generated app declares
``E.Slider(bind="q_deg[0]", ...)`` and needs no getter or setter methods.

>>> class M: q = [1.0, 2.0, 3.0]
>>> get, put = getter("q[2]"), setter("q[2]")
>>> put(M, 5.0); get(M)
5.0
"""

from __future__ import annotations

import ast
from collections.abc import Callable
from functools import lru_cache
from typing import Any

__all__ = ["BindPath", "parse_path", "getter", "setter"]


class BindPath(tuple):
    """``(name, index)``: the variable's name and the element's index (a tuple of ints, empty
    for the whole variable)."""

    __slots__ = ()

    @property
    def name(self) -> str:
        return self[0]

    @property
    def index(self) -> tuple[int, ...]:
        return self[1]


def _int(node: ast.AST, text: str) -> int:
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        return -_int(node.operand, text)
    if isinstance(node, ast.Constant) and type(node.value) is int:
        return node.value
    raise ValueError(f"bind path {text!r}: an index must be a whole number, like q[2]")


@lru_cache(maxsize=None)
def parse_path(text: str) -> BindPath:
    """``"q[1, 2]"`` -> ``BindPath(("q", (1, 2)))``; ``"q[1][2]"`` is the same element.

    Raises ``ValueError`` for anything but a name with optional whole-number indices.
    """
    try:
        node = ast.parse(text.strip(), mode="eval").body
    except SyntaxError:
        raise ValueError(f"bind path {text!r} is not a name or name[index]") from None
    index: list[int] = []
    while isinstance(node, ast.Subscript):
        parts = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
        index[:0] = [_int(p, text) for p in parts]
        node = node.value
    if not isinstance(node, ast.Name):
        raise ValueError(f"bind path {text!r} is not a name or name[index]")
    return BindPath((node.id, tuple(index)))


def getter(text: str) -> Callable[[Any], Any]:
    """A function ``model -> value`` reading the bind path ``text``."""
    name, index = parse_path(text)
    if not index:
        return lambda model: getattr(model, name)
    key = index[0] if len(index) == 1 else index

    def get(model: Any) -> Any:
        value = getattr(model, name)
        try:
            return value[key]
        except TypeError:  # a list of lists indexed by a tuple
            for i in index:
                value = value[i]
            return value

    return get


def setter(text: str) -> Callable[[Any, Any], None]:
    """A function ``(model, value) -> None`` writing the bind path ``text`` (an element in place)."""
    name, index = parse_path(text)
    if not index:
        return lambda model, value: setattr(model, name, value)
    key = index[0] if len(index) == 1 else index

    def put(model: Any, value: Any) -> None:
        target = getattr(model, name)
        try:
            target[key] = value
        except TypeError:
            for i in index[:-1]:
                target = target[i]
            target[index[-1]] = value

    return put
