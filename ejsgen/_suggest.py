"""'Did you mean ...?' suggestions."""

from __future__ import annotations

import difflib
import importlib.util
import sys
from collections.abc import Iterable


def closest(name: str, candidates: Iterable[str], *, cutoff: float = 0.6) -> str | None:
    """The candidate closest to ``name`` (similarity at least ``cutoff``, in [0, 1]), or None.

    A candidate that differs only in case (``Pi`` for ``pi``) is the closest of all.
    """
    pool = sorted(set(candidates))
    same = [c for c in pool if c.lower() == name.lower() and c != name]
    if same:
        return same[0]
    matches = difflib.get_close_matches(name, pool, n=5, cutoff=cutoff)
    if not matches:
        return None
    # among the close ones, the fewest edits (a swap of two neighbours counts as one), then
    # the same first letter, then the same letters (a typo of order: 'lable' is 'label', not 'table')
    return min(matches, key=lambda c: (_edits(name, c), c[:1] != name[:1], sorted(c) != sorted(name), matches.index(c)))


def _edits(a: str, b: str) -> int:
    """Optimal-string-alignment distance: insertions, deletions, substitutions and swaps of neighbours."""
    prev2: list[int] = []
    prev = list(range(len(b) + 1))
    for i in range(1, len(a) + 1):
        cur = [i] + [0] * len(b)
        for j in range(1, len(b) + 1):
            cost = a[i - 1] != b[j - 1]
            cur[j] = min(prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + cost)
            if i > 1 and j > 1 and a[i - 1] == b[j - 2] and a[i - 2] == b[j - 1]:
                cur[j] = min(cur[j], prev2[j - 2] + 1)
        prev2, prev = prev, cur
    return prev[len(b)]


def did_you_mean(name: str, candidates: Iterable[str], *, cutoff: float = 0.6) -> str:
    """``"did you mean 'x'?"`` or an empty string."""
    c = closest(name, candidates, cutoff=cutoff)
    return f"did you mean '{c}'?" if c else ""


#: a key's other spellings (former, or British/American) -> the key to use where a model has it
#: (the mobile kinds' keys are the drawing panel's in the 3D scene too: issue #27)
SYNONYMS: dict[str, tuple[str, ...]] = {
    "centre": ("position",), "center": ("position",), "path": ("points",), "particles": ("points",),
}


def did_you_mean_key(name: str, fields: Iterable[str]) -> str:
    """``"did you mean 'x'?"`` for an unknown key: a synonym the model has, else the closest field; or ''."""
    pool = set(fields)
    for alt in SYNONYMS.get(name, ()):
        if alt in pool:
            return f"did you mean '{alt}'?"
    return did_you_mean(name, pool)


#: modules usually imported under a short name: the import line that binds it
_MODULE_ALIASES = {"plt": "import matplotlib.pyplot as plt", "pd": "import pandas as pd", "sp": "import scipy as sp"}


def module_hint(name: str) -> str:
    """For an unknown ``name`` used as ``name.attr``: if it is a module (the standard library's,
    an installed one, or a usual alias such as ``plt``), the import line to add to the spec's
    ``imports:`` list; else ''."""
    if name == "numpy":
        return "NumPy is already 'np' without an import (np.zeros, np.linalg.norm); or add 'import numpy' to the spec's imports: list"
    if name == "math":
        return ("'math' is a module: add 'import math' to the spec's imports: list "
                "(its functions and constants are already names without 'math.': sin(x), sqrt(x), pi)")
    line = _MODULE_ALIASES.get(name)
    if line is None and (name in sys.stdlib_module_names or _installed(name)):
        line = f"import {name}"
    return f"'{name}' is a module: add '{line}' to the spec's imports: list" if line else ""


def _installed(name: str) -> bool:
    """A top-level module of that name can be imported (found, not imported)."""
    if not name.isidentifier() or name.startswith("_"):
        return False
    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):
        return False


def text_value_hint(name: str, value: str) -> str:
    """Why a variable given a quoted value has shape (): it is that text, not what it computes."""
    shown = value if len(value) <= 60 else value[:57] + "..."
    return (f"'{name}' is text: its value \"{shown}\" is in quotes, so it is not computed; "
            f"for the value of an expression declare {name}: {{expr: \"{shown}\"}}")
