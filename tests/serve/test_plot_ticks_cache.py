"""A plot's axis ticks are remembered (issue #30: a class's plots are redrawn 15 times a second
by every session): the remembered ticks are those the tick rules give afresh, for linear and
log axes, x and y, and a caller that changes its list changes no later frame's."""

from __future__ import annotations

import numpy as np

from ejsrl.view._plot_frame import PLOT_AREA_PX, axis_ticks
from ejsrl.view._ticks import linear_ticks, log_ticks, tick_labels


def _fresh(lo: float, hi: float, log: bool, long_at: int, length_px: float | None) -> list[list]:
    """The ticks as the rules in ejsrl.view._ticks give them, with nothing remembered."""
    if log:
        px = length_px if length_px else PLOT_AREA_PX[0 if long_at else 1]
        ticks, labels = log_ticks(lo, hi, length_px=px, horizontal=bool(long_at))
        return [[v, s] for v, s in zip(ticks, labels)]
    ticks, step = linear_ticks(lo, hi)
    labels = tick_labels(ticks, step)
    if long_at and labels and max(len(s) for s in labels) > long_at:
        ticks, step = linear_ticks(lo, hi, target=3)
        labels = tick_labels(ticks, step)
    return [[v, s] for v, s in zip(ticks, labels)]


def test_remembered_ticks_are_the_rules_own_and_each_call_gets_its_own_list():
    rng = np.random.default_rng(3)
    cases = [(-1.2, 1.3, False, 0, 180.0), (0.0, 10.0, False, 7, 300.0), (2.99999989e8, 3.00000011e8, False, 7, 300.0),
             (1e-3, 1e4, True, 0, 180.0), (2.0, 19.0, True, 7, 300.0), (-0.0, 1e-5, False, 0, None)]
    cases += [(float(a), float(a + w), False, int(k), 300.0) for a, w, k in
              zip(rng.normal(0, 50, 40), rng.uniform(1e-3, 100, 40), rng.integers(0, 2, 40) * 7)]
    for lo, hi, log, long_at, px in cases * 2:  # the second round is remembered
        got = axis_ticks(np.float64(lo), hi, log, long_at=long_at, length_px=px)
        assert got == _fresh(lo, hi, log, long_at, px), (lo, hi, log)
        got.append(["mutated", "by a caller"])
        got[0][1] = "changed"
        assert axis_ticks(lo, hi, log, long_at=long_at, length_px=px) == _fresh(lo, hi, log, long_at, px)
