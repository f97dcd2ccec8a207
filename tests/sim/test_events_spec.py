"""Events of a built spec: several events on one `when` fire once each per crossing."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from testkit import run_app

G = 9.81

SPEC = """\
ejs: 1
title: Ball with three events on its height
model:
  variables:
    t: 0.0
    dt: 0.01
    z: 1.0
    vz: 0.0
    downs: 0
    boths: 0
    ups: 0
    first_both: -1.0
  evolution:
    - ode:
        method: {method}
        tolerance: 1e-10
        equations:
          z: vz
          vz: -{g}
        events:
{events}
view:
  - label: {{text: "{{downs}} {{boths}} {{ups}}"}}
"""

DOWN = """\
          - name: floor
            when: z
            direction: down
            action: |
              vz = -0.9*vz
              downs = downs + 1
"""
BOTH = """\
          - name: touch
            when: z
            direction: both
            action: |
              boths = boths + 1
              if first_both < 0:
                  first_both = t
"""
UP = """\
          - name: below
            when: z
            direction: up
            action: |
              ups = ups + 1
"""


def impacts_before(t_end: float) -> list[float]:
    """Closed form of a ball dropped from 1 m with restitution 0.9."""
    v1 = math.sqrt(2 * G)
    times = [v1 / G]
    while times[-1] + 2 * v1 * 0.9 ** len(times) / G < t_end:
        times.append(times[-1] + 2 * v1 * 0.9 ** len(times) / G)
    return times


@pytest.mark.parametrize(("method", "order"), [("rk4", (DOWN, BOTH, UP)), ("dopri5", (BOTH, UP, DOWN))])
def test_a_built_ball_counts_each_impact_once_in_every_event(tmp_path: Path, method: str, order) -> None:
    from ejsgen.cli import build

    spec = tmp_path / "ball.ejs.yaml"
    spec.write_text(SPEC.format(method=method, g=G, events="".join(order)), encoding="utf-8")
    app = build(spec, tmp_path / "app")
    done = run_app(app, "--headless", "--duration", "4", "--csv", "-", "--vars", "t,z,downs,boths,ups,first_both", timeout=120)
    assert done.returncode == 0, done.stderr
    assert "Zeno" not in done.stderr
    last = done.stdout.strip().splitlines()[-1].split(",")
    t, z, downs, boths, ups, first_both = float(last[0]), float(last[1]), *map(int, last[2:5]), float(last[5])
    expected = impacts_before(t)
    assert len(expected) == 6
    assert (downs, boths, ups) == (len(expected), len(expected), 0)
    assert first_both == pytest.approx(expected[0], abs=1e-8)
    assert z > 0
