"""Array shapes known when a spec is built, to catch mismatches before the app runs."""

from __future__ import annotations

import ast
from typing import Any

__all__ = ["literal_shape", "infer_shape"]

Shape = tuple[int, ...]

_SCALAR_FUNCS = {"sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "log", "log10", "sqrt", "hypot", "floor", "ceil", "radians", "degrees", "abs", "float", "int", "len", "min", "max", "round"}


def literal_shape(value: Any) -> tuple[Shape | None, str]:
    """Shape of a nested list of numbers, or (None, error text)."""
    if isinstance(value, bool) or isinstance(value, str) or value is None or isinstance(value, dict):
        return None, f"lists hold numbers only, found {value!r}"
    if isinstance(value, (int, float)):
        return (), ""
    if not isinstance(value, list):
        return None, f"unsupported value {value!r}"
    if not value:
        return (0,), ""
    shapes = []
    for item in value:
        s, err = literal_shape(item)
        if err:
            return None, err
        shapes.append(s)
    if any(s != shapes[0] for s in shapes):
        return None, "a nested list must be rectangular (every row the same length)"
    return (len(value),) + shapes[0], ""


def _broadcast(a: Shape, b: Shape) -> Shape | None:
    if a == ():
        return b
    if b == ():
        return a
    if len(a) != len(b):
        return None
    out = []
    for x, y in zip(a, b):
        if x == y or y == 1:
            out.append(x)
        elif x == 1:
            out.append(y)
        else:
            return None
    return tuple(out)


def infer_shape(node: ast.AST, var_shapes: dict[str, Shape | None]) -> Shape | None:
    """The shape of a rewritten expression when it is certain, else None."""
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
        return ()
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "self":
        return var_shapes.get(node.attr)
    if isinstance(node, (ast.List, ast.Tuple)):
        inner = [infer_shape(e, var_shapes) for e in node.elts]
        if any(s is None for s in inner):
            return None
        if all(s == () for s in inner):
            return (len(node.elts),)
        if all(s == inner[0] for s in inner):
            return (len(node.elts),) + inner[0]  # type: ignore[operator]
        return None
    if isinstance(node, ast.UnaryOp):
        return infer_shape(node.operand, var_shapes)
    if isinstance(node, ast.BinOp) and not isinstance(node.op, ast.MatMult):
        a = infer_shape(node.left, var_shapes)
        b = infer_shape(node.right, var_shapes)
        if a is None or b is None:
            return None
        if isinstance(node.left, (ast.List, ast.Tuple)) or isinstance(node.right, (ast.List, ast.Tuple)):
            return None  # list arithmetic is not elementwise
        return _broadcast(a, b)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in _SCALAR_FUNCS:
        return ()
    return None
