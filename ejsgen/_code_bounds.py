"""How deep a snippet's syntax tree may nest before the compiler refuses it.

``a + b + c + ...`` with thousands of terms, or thousands of nested calls, parses into a
tree thousands of levels deep; every later walk over it (name resolution, ``ast.unparse``)
recurses once per level and would die with a 3,000-line ``RecursionError``. A spec's code
nests a few dozen levels at most, so more than ``MAX_CODE_DEPTH`` is refused where it starts.
Deeper still (``1+1+...`` with 5,000 terms) and Python's own parser gives up with a
``RecursionError`` before there is a tree: :func:`heaviest_statement` then finds the
statement from the tokens (read without recursion), so the error is at its line, not the block's.
"""

from __future__ import annotations

import ast
import io
import tokenize

__all__ = ["MAX_CODE_DEPTH", "too_deep", "heaviest_statement"]

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


#: tokens that neither nest nor chain: separators, brackets and the ends of lines
_FLAT = frozenset({",", ":", ";", "(", ")", "[", "]", "{", "}"})
_SKIP = (tokenize.NL, tokenize.NEWLINE, tokenize.COMMENT, tokenize.INDENT, tokenize.DEDENT, tokenize.ENDMARKER)


def heaviest_statement(text: str) -> tuple[int, int]:
    """(1-based line, 0-based column) where the statement of ``text`` that nests deepest starts.

    A statement's weight is its deepest bracket nesting plus its operators and dots (each
    ``+`` of ``1+1+...`` or ``.`` of ``a.b.c...`` is one more level of the tree the parser
    builds); the first of the heaviest wins. ``(1, 0)`` when ``text`` does not tokenize.
    """
    best, best_at = -1, (1, 0)
    weight, depth, start = 0, 0, None
    try:
        for tok in tokenize.generate_tokens(io.StringIO(text).readline):
            if tok.type == tokenize.NEWLINE or tok.type == tokenize.ENDMARKER:
                if start is not None and weight > best:
                    best, best_at = weight, start
                weight, depth, start = 0, 0, None
                continue
            if tok.type in _SKIP:
                continue
            if start is None:
                start = tok.start
            if tok.type == tokenize.OP and tok.string in "([{":
                depth += 1
                weight = max(weight, depth)
            elif tok.type == tokenize.OP and tok.string in ")]}":
                depth -= 1
            if tok.type == tokenize.OP and tok.string not in _FLAT:
                weight += 1
    except (tokenize.TokenError, SyntaxError, RecursionError, MemoryError):
        pass
    if start is not None and weight > best:  # a last statement the tokens stopped inside
        best, best_at = weight, start
    return best_at
