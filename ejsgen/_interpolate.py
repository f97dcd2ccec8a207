"""Splitting an interpolated text (``"E = {E:.3f} J"``) into literal parts and fields.

A field is ``{expression[!conversion][:format]}`` as in an f-string: the expression may
hold brackets, strings and ``!=``; ``{{`` and ``}}`` are literal braces. Unlike
``string.Formatter.parse``, the scanner knows where each field starts and where a
bracket or quote was opened, so an error points at the character to fix ("this '[' is
never closed"), not at the start of the text.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Field", "BraceError", "split_fields"]

_CLOSE = {"(": ")", "[": "]", "{": "}"}


@dataclass(frozen=True)
class Field:
    """One ``{...}`` of the text: ``expr`` starts at ``offset`` (0-based, in the text)."""

    expr: str
    offset: int
    conversion: str | None = None
    spec: str = ""


@dataclass
class BraceError(Exception):
    """A malformed text: ``message`` about the character at ``offset``; ``hint``: the fix."""

    offset: int
    message: str
    hint: str = "write {{ and }} for literal braces"
    detail: str = ""
    """Said after the caller's "in <what>"."""


def split_fields(text: str) -> list[str | Field]:
    """The literal parts (``str``, braces unescaped) and fields of ``text``, in order."""
    parts: list[str | Field] = []
    literal: list[str] = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c in "{}" and text.startswith(c * 2, i):
            literal.append(c)
            i += 2
            continue
        if c == "}":
            raise BraceError(i, "this '}' closes no '{'")
        if c != "{":
            literal.append(c)
            i += 1
            continue
        if literal:
            parts.append("".join(literal))
            literal = []
        field, i = _field(text, i)
        parts.append(field)
    if literal:
        parts.append("".join(literal))
    return parts


def _field(text: str, start: int) -> tuple[Field, int]:
    """The field whose '{' is at ``start``, and the index after its closing '}'."""
    n = len(text)
    stack: list[tuple[str, int]] = []
    quote: tuple[str, int] | None = None
    j = start + 1
    while j < n:
        ch = text[j]
        if quote is not None:
            if ch == "\\":
                j += 2
                continue
            if ch == quote[0]:
                quote = None
        elif ch in "'\"":
            quote = (ch, j)
        elif ch in _CLOSE:
            stack.append((ch, j))
        elif ch in ")]}":
            if ch == "}" and all(opener != "{" for opener, _ in stack):
                if not stack:
                    break  # the end of the field
                opener, at = stack[-1]
                raise BraceError(at, f"this '{opener}' is never closed", f"add the missing '{_CLOSE[opener]}'")
            if not stack:
                raise BraceError(j, f"this '{ch}' closes no bracket", "remove it or add the opening bracket")
            opener, at = stack.pop()
            if _CLOSE[opener] != ch:
                raise BraceError(at, f"this '{opener}' is closed by '{ch}'", f"close it with '{_CLOSE[opener]}'")
        elif not stack and (ch == ":" or (ch == "!" and text[j + 1 : j + 2] != "=")):
            break
        j += 1
    if quote is not None:
        raise BraceError(quote[1], f"this quote {quote[0]} is never closed", f"add the closing {quote[0]}")
    if stack:
        opener, at = stack[-1]
        raise BraceError(at, f"this '{opener}' is never closed", f"add the missing '{_CLOSE[opener]}'")
    if j >= n:
        raise BraceError(start, "this '{' is never closed", "add the missing '}' (or write {{ for a literal brace)")
    expr = text[start + 1 : j]
    conversion: str | None = None
    if text[j] == "!":
        conversion = text[j + 1 : j + 2]
        if conversion not in ("r", "s", "a"):
            raise BraceError(j, f"'!{conversion}' is not a conversion", "use !r, !s or !a, or none")
        j += 2
        if j < n and text[j] not in ":}":
            raise BraceError(j, "expected ':' or '}' after the conversion")
    spec = ""
    if j < n and text[j] == ":":
        end, depth, nested = j + 1, 0, False
        while end < n and (text[end] != "}" or depth):
            if text[end] == "{":
                depth, nested = depth + 1, True
            elif text[end] == "}":
                depth -= 1
            end += 1
        if nested:
            raise BraceError(
                start + 1,
                "a format inside a format is not supported",
                "write the format out, e.g. {x:8.3f}",
                f": '{text[start : min(end + 1, n)]}'",
            )
        if end >= n:
            raise BraceError(start, "this '{' is never closed", "add the missing '}' after the format")
        spec = text[j + 1 : end]
        j = end
    if j >= n:
        raise BraceError(start, "this '{' is never closed", "add the missing '}'")
    return Field(expr, start + 1, conversion, spec), j + 1
