"""ServoMonitor's retreat warning measured from the goal's depth when the goal is farther
than the start: a servo that must back away to reach a smaller desired image (the
servoing lab's Desired size below the start's) is no retreat, while one receding past
the goal still is."""

from __future__ import annotations

import numpy as np

from ejsrl.vision import ServoMonitor

SQUARE = np.array([[110.0, 70.0], [210.0, 70.0], [210.0, 170.0], [110.0, 170.0]])


def _run(depths, **kw) -> list[str]:
    m = ServoMonitor(320, 240, 4, retreat_factor=1.3)
    out: list[str] = []
    for z in depths:
        out += m.check(SQUARE, np.full(4, z), **kw)
    return out


def test_backing_away_to_a_farther_goal_is_no_retreat():
    approach = 0.4 + 0.5 * (1 - np.exp(-np.linspace(0, 5, 60)))  # 0.4 m -> 0.9 m, the goal's depth
    assert len(_run(approach)) == 1  # measured from the start alone, it looks like a retreat
    assert _run(approach, Z_goal=0.9) == []


def test_receding_past_a_farther_goal_is_a_retreat_said_against_the_goal():
    away = np.linspace(0.4, 1.5, 60)
    warnings = _run(away, Z_goal=0.9)
    assert len(warnings) == 1 and "retreating" in warnings[0]
    assert "times their 0.90 m at the goal" in warnings[0], warnings[0]
    near = _run(away, Z_goal=0.3)  # a goal nearer than the start: measured from the start, as before
    assert len(near) == 1 and "times their 0.40 m at the start" in near[0], near[0]
