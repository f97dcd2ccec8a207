"""The length of the two fixed *pieces* that draw a segment whose length changes.

The browser's 3D view moves a node by a pose in the frame that receives it, but shows new
geometry a frame later (``ejsrl.view._lines``). A segment of changing length (a line that
stretches, an arrow's shaft) is therefore drawn as two pieces of one fixed length ``h``, one
from each end, posed so that they point at each other: they cover the segment exactly while
its length stays within ``[h, 2h]``. This module picks ``h`` when a length leaves that band.
"""

from __future__ import annotations

import math

__all__ = ["PIECE_RATIO", "refit_piece"]

#: a segment's pieces are ``length / PIECE_RATIO`` long when made: it may then shrink to 2/3 or
#: stretch to 4/3 of that length (a spring about its rest length) before they are made again
PIECE_RATIO = 1.5


def refit_piece(piece: float, length: float, seen: tuple[float, float]) -> tuple[float | None, tuple[float, float]]:
    """``(new piece length or None if ``piece`` still covers ``length``, lengths seen)``.

    ``piece``: the pieces' length now (metres); ``length``: the segment's; ``seen``: the shortest
    and longest lengths it has had ((inf, 0) for none). A length out of the band gets pieces for
    every length seen if one piece length covers them all (the middle of those that do, by ratio:
    room both ways: a spring oscillating within twice its shortest length is then covered by poses
    alone after its first swing), else with room the way it went.
    """
    lo, hi = min(seen[0], length), max(seen[1], length)
    if piece * (1.0 - 1e-9) <= length <= 2.0 * piece * (1.0 + 1e-9):
        return None, (lo, hi)
    if hi <= 2.0 * lo:
        return math.sqrt(hi / 2.0 * lo), (lo, hi)
    return (0.75 * length if length > piece else 0.55 * length), (lo, hi)
