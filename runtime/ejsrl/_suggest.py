"""``did you mean ...?`` for a name the user typed on the command line (``--set``, ``--vars``,
a sweep's parameters, a summary column): one rule for every option.

A candidate that differs only in case wins (``l`` -> ``L``); otherwise the closest by
``difflib``'s ratio (at least 0.6), ties going to a candidate with the same first letter
(``Lx`` -> ``L``, not ``x``).
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

__all__ = ["closest", "did_you_mean"]


def closest(name: str, candidates: Iterable[str]) -> str | None:
    """The candidate ``name`` most likely meant, or None."""
    cands = list(dict.fromkeys(candidates))
    same_case = [c for c in cands if c.lower() == name.lower()]
    if same_case:
        return same_case[0]
    best: tuple[float, bool] = (0.0, False)
    found = None
    for c in cands:
        score = (round(difflib.SequenceMatcher(None, name.lower(), c.lower()).ratio(), 9), c[:1].lower() == name[:1].lower())
        if score[0] >= 0.6 and score > best:
            best, found = score, c
    return found


def did_you_mean(name: str, candidates: Iterable[str]) -> str:
    """``"; did you mean 'X'?"`` for the closest candidate, or ``""``."""
    match = closest(name, candidates)
    return f"; did you mean '{match}'?" if match else ""
