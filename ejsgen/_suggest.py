"""'Did you mean ...?' suggestions."""

from __future__ import annotations

import difflib
from collections.abc import Iterable


def closest(name: str, candidates: Iterable[str], *, cutoff: float = 0.6) -> str | None:
    """The candidate closest to ``name`` (similarity at least ``cutoff``, in [0, 1]), or None."""
    matches = difflib.get_close_matches(name, sorted(set(candidates)), n=1, cutoff=cutoff)
    return matches[0] if matches else None


def did_you_mean(name: str, candidates: Iterable[str], *, cutoff: float = 0.6) -> str:
    """``"did you mean 'x'?"`` or an empty string."""
    c = closest(name, candidates, cutoff=cutoff)
    return f"did you mean '{c}'?" if c else ""
