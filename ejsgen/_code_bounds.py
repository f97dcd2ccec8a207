"""How deep a snippet's syntax tree may nest before the compiler refuses it.

``a + b + c + ...`` with thousands of terms, or thousands of nested calls, parses into a
tree thousands of levels deep; every later walk over it (name resolution, ``ast.unparse``)
recurses once per level and would die with a 3,000-line ``RecursionError``. A spec's code
nests a few dozen levels at most, so more than ``MAX_CODE_DEPTH`` is refused where it starts.
"""

from __future__ import annotations

import ast

__all__ = ["MAX_CODE_DEPTH", "too_deep"]

MAX_CODE_DEPTH = 200
"""Deepest syntax tree (nodes from the root to a leaf) a snippet may have."""


def too_deep(tree: ast.AST, limit: int = MAX_CODE_DEPTH) -> ast.AST | None:
    """The outermost node (a statement or expression) that has more than ``limit`` levels below it, or None.

    Walks the tree without recursion, so any depth is measured safely.
    """
    stack: list[tuple[ast.AST, int, ast.AST | None]] = [(tree, 0, None)]
    while stack:
        node, depth, located = stack.pop()
        if getattr(node, "lineno", None) is not None and located is None:
            located = node
        if depth > limit:
            return located or node
        for child in ast.iter_child_nodes(node):
            stack.append((child, depth + 1, located if depth else None))
    return None
