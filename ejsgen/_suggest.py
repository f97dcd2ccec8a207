"""'Did you mean ...?' suggestions."""

from __future__ import annotations

import difflib
from collections.abc import Iterable


def closest(name: str, candidates: Iterable[str], *, cutoff: float = 0.6) -> str | None:
    """The candidate closest to ``name`` (similarity at least ``cutoff``, in [0, 1]), or None.

    A candidate that differs only in case (``Pi`` for ``pi``) is the closest of all.
    """
    pool = sorted(set(candidates))
    same = [c for c in pool if c.lower() == name.lower() and c != name]
    if same:
        return same[0]
    matches = difflib.get_close_matches(name, pool, n=1, cutoff=cutoff)
    return matches[0] if matches else None


def did_you_mean(name: str, candidates: Iterable[str], *, cutoff: float = 0.6) -> str:
    """``"did you mean 'x'?"`` or an empty string."""
    c = closest(name, candidates, cutoff=cutoff)
    return f"did you mean '{c}'?" if c else ""
