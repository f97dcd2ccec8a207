"""Errors meant for users: each carries its own text; the CLI prints it without a traceback."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["EjsError", "SpecError", "SpecErrors", "Location", "CodeSyntaxError", "UnknownNameError"]


@dataclass(frozen=True)
class Location:
    """A place in a spec file: 1-based ``line`` and ``col``."""

    file: str
    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


class EjsError(Exception):
    """Root of every error ejsgen reports to users (printed as is, exit status 1)."""


class SpecError(EjsError):
    """One problem in a spec, at a location: ``FILE:LINE:COL: error: message``."""

    def __init__(self, where: Location, message: str, hint: str = "") -> None:
        self.where = where
        self.message = message
        self.hint = hint
        super().__init__(self.format())

    def format(self) -> str:
        text = f"{self.where}: error: {self.message}"
        if self.hint:
            text += f"; {self.hint}"
        return text


class CodeSyntaxError(SpecError):
    """A Python syntax error in a code block or expression of the spec."""


class UnknownNameError(SpecError):
    """A name in spec code that no rule of the language resolves."""


class SpecErrors(EjsError):
    """Several problems in one spec, in file order, Python syntax errors first.

    Code that cannot be parsed cannot be checked, and the functions it defines are unknown
    everywhere else; so when there is a syntax error, unknown-name errors (likely its echoes)
    are left out, and the syntax errors come before every other problem.
    """

    def __init__(self, errors: list[SpecError]) -> None:
        if any(isinstance(e, CodeSyntaxError) for e in errors):
            errors = [e for e in errors if not isinstance(e, UnknownNameError)]
        self.errors = sorted(errors, key=lambda e: (not isinstance(e, CodeSyntaxError), e.where.file, e.where.line, e.where.col))
        super().__init__("\n".join(e.format() for e in self.errors))
