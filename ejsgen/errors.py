"""Errors meant for users: each carries its own text; the CLI prints it without a traceback."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["EjsError", "SpecError", "SpecErrors", "Location"]


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


class SpecErrors(EjsError):
    """Several problems in one spec, in file order."""

    def __init__(self, errors: list[SpecError]) -> None:
        self.errors = sorted(errors, key=lambda e: (e.where.file, e.where.line, e.where.col))
        super().__init__("\n".join(e.format() for e in self.errors))
