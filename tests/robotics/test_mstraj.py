"""``mstraj`` against Robotics Toolbox for Python's (recorded in fixtures/mstraj_rtb.json by
fixtures/make_mstraj_rtb.py), and against what its documentation promises."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ejsrl.robotics import mstraj
from testkit.robotics import FIXTURES

REF = json.loads((FIXTURES / "mstraj_rtb.json").read_text())


@pytest.mark.parametrize("case", sorted(REF["cases"]))
def test_mstraj_equals_the_toolboxs(case: str) -> None:
    ref = REF["cases"][case]
    tr = mstraj(**ref["kwargs"])
    for key in ("t", "q", "qd", "qdd"):
        np.testing.assert_allclose(getattr(tr, key), np.array(ref[key]).reshape(getattr(tr, key).shape),
                                   atol=1e-12, rtol=0, err_msg=key)
        assert getattr(tr, key).shape[0] == len(ref[key])
    np.testing.assert_allclose(tr.arrive, ref["arrive"], atol=1e-12)
    got = [[np.nan if i.slowest is None else float(i.slowest), i.segtime, i.clock] for i in tr.info]
    want = np.array([[np.nan if s is None else s, a, b] for s, a, b in ref["info"]], dtype=float)
    np.testing.assert_allclose(np.array(got, dtype=float), want, atol=1e-12)
    # sample() evaluates the same blends and lines at the sample times
    q, _, _ = tr.sample(tr.t)
    np.testing.assert_allclose(q, tr.q, atol=1e-12)


def test_mstraj_by_hand_one_axis() -> None:
    """0 -> 1 -> 0.5 at 1 unit/s, dt 0.1, tacc 0.2 (a blend of 0.1 s at the start and end,
    0.2 s at the corner): worked out from the algorithm's description."""
    tr = mstraj([[0.0], [1.0], [0.5]], 0.1, 0.2, qdmax=1.0)
    # segment 1: 0.1 s blend + ceil(1/1 / 0.1) * 0.1 = 1.1 s; speed 1/1.1
    assert tr.info[0].segtime == pytest.approx(1.1) and tr.info[0].slowest == 0
    np.testing.assert_allclose(tr.q[0], [0.1 / 1.1 * 1.0])  # the first sample, dt after the start
    np.testing.assert_allclose(tr.qd[5], [1 / 1.1])  # cruising at constant speed
    # segment 2: 0.2 + 0.5 = 0.7 s
    assert tr.info[1].segtime == pytest.approx(0.7)
    np.testing.assert_allclose(tr.arrive, [1.1, 1.8])
    np.testing.assert_allclose(tr.q[-1], [0.5], atol=1e-12)  # ends on the last via point, at rest
    np.testing.assert_allclose(tr.qd[-1], [0.0], atol=1e-12)


def test_mstraj_respects_speed_limits_and_passes_near_the_via_points() -> None:
    via = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 2.0], [3.0, 0.0]])
    vmax = np.array([1.0, 0.5])
    tr = mstraj(via, 0.01, 0.3, qdmax=vmax)
    linear = np.all(tr.qdd == 0.0, axis=1)  # the straight parts (blends may exceed, as in the Toolbox)
    assert linear.sum() > len(tr.t) / 2
    assert np.all(np.abs(tr.qd[linear]) <= vmax * (1 + 1e-9))
    # every segment's slowest axis runs near its limit (its time also holds the blend)
    for info in tr.info[:-1]:
        assert np.max(np.abs(tr.qd[linear])[:, info.slowest]) > 0.8 * vmax[info.slowest]
    for p in via[1:-1]:  # corners are cut by the blends, but only near the via point
        d = np.min(np.linalg.norm(tr.q - p, axis=1))
        assert 0.0 < d < 0.3
    np.testing.assert_allclose(tr.q[-1], via[-1], atol=1e-12)


def test_mstraj_errors_say_what_to_give() -> None:
    with pytest.raises(ValueError, match="give qdmax or tsegment, not both"):
        mstraj([[0], [1]], 0.1, 0.2, qdmax=1.0, tsegment=[1.0])
    with pytest.raises(ValueError, match="give qdmax"):
        mstraj([[0], [1]], 0.1, 0.2)
    with pytest.raises(ValueError, match="tsegment has 1 values for 2 segments"):
        mstraj([[0], [1], [2]], 0.1, 0.2, tsegment=[1.0])
