"""What an author meant by ``^``: the power written next to the operator (``x^2`` -> ``x**2``).

``^`` is Python's bitwise exclusive or; the resolver (``ejsgen._resolve``) refuses it in spec
code and suggests the power read here from the author's own text.
"""

from __future__ import annotations

import re

__all__ = ["power_text"]

_ATOM = re.compile(r"[\w.]+")


def power_text(line: str, byte_col: int) -> str:
    """The operands next to the ``^`` at ``byte_col`` of ``line``, written as a power:
    ``0.5*v^2 + 1`` -> ``v**2``, ``(k*x) ^ 4`` -> ``(k*x) ** 4``, ``f(x)^-1`` -> ``f(x)**-1``.

    The operands are what the author wrote around the operator (a name, number, call or
    bracketed group), not the tree Python made: ``^`` binds more loosely than ``*`` and
    ``+``, so the tree's operands are not what was meant. Empty if they cannot be read.
    """
    at = len(line.encode("utf-8")[:byte_col].decode("utf-8", errors="replace"))
    i = at
    while i > 0 and line[i - 1] == " ":
        i -= 1
    start = i
    while start > 0:  # a name, number, call or subscript: atoms and bracketed groups
        ch = line[start - 1]
        if ch in ")]":
            depth, j = 0, start - 1
            while j >= 0:
                depth += {")": 1, "]": 1, "(": -1, "[": -1}.get(line[j], 0)
                if depth == 0:
                    break
                j -= 1
            if j < 0:
                return ""
            start = j
        elif _ATOM.match(ch):
            start -= 1
        else:
            break
    left = line[start:i]
    j = at + 1
    while j < len(line) and line[j] == " ":
        j += 1
    end = j + 1 if j < len(line) and line[j] in "+-" else j
    if end < len(line) and line[end] in "([":
        depth, k = 0, end
        while k < len(line):
            depth += {"(": 1, "[": 1, ")": -1, "]": -1}.get(line[k], 0)
            if depth == 0:
                break
            k += 1
        end = k + 1
    else:
        m = _ATOM.match(line, end)
        end = m.end() if m else end
        if end < len(line) and line[end] in "([":  # a call or subscript after a name
            return _power_text_call(line, start, i, at, j, end)
    right = line[j:end]
    if not left or not right.strip("+-"):
        return ""
    op = line[i:j].replace("^", "**")
    return f"{left}{op}{right}"


def _power_text_call(line: str, start: int, i: int, at: int, j: int, end: int) -> str:
    """``power_text`` when the right operand is a call or subscript (``x^f(2)``)."""
    depth, k = 0, end
    while k < len(line):
        depth += {"(": 1, "[": 1, ")": -1, "]": -1}.get(line[k], 0)
        if depth == 0:
            break
        k += 1
    left, right = line[start:i], line[j : k + 1]
    return f"{left}{line[i:j].replace('^', '**')}{right}" if left and right else ""
