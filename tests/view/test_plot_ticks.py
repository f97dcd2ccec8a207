"""Tick labels of plots, against the rule in specs/reference.md ("Plots: axes and ticks").

Every label must read back as its tick's value (to the digits shown), no two labels of an
axis may read the same, none reads "-0", and numbers that need it are in scientific
notation instead of rounding to "0".
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ejsrl.view._ticks import MINUS, linear_ticks, log_ticks, nice_step, tick_labels


def _read(label: str) -> float:
    return float(label.replace(MINUS, "-"))


def _labels(lo: float, hi: float) -> tuple[list[float], list[str]]:
    ticks, step = linear_ticks(lo, hi)
    return ticks, tick_labels(ticks, step)


@pytest.mark.parametrize(
    ("lo", "hi", "expected"),
    [
        (0.0, 10.0, ["0", "2", "4", "6", "8", "10"]),
        (-2.5, 2.5, ["\u22122", "\u22121", "0", "1", "2"]),
        (0.0, 1.0, ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]),
        (0.194, 0.198, ["0.194", "0.195", "0.196", "0.197", "0.198"]),
        # data near 1e-5: every label in units of 1e-5, never "0 0 -0"
        (-1e-5, 1e-5, ["\u22121.0e\u22125", "\u22120.5e\u22125", "0", "0.5e\u22125", "1.0e\u22125"]),
        (1.2e-5, 1.3e-5, ["1.20e\u22125", "1.22e\u22125", "1.24e\u22125", "1.26e\u22125", "1.28e\u22125", "1.30e\u22125"]),
        (1e6, 5e6, ["1e6", "2e6", "3e6", "4e6", "5e6"]),
        (123456.1, 123466.1, ["123458", "123460", "123462", "123464", "123466"]),
    ],
)
def test_labels_follow_the_rule(lo, hi, expected):
    assert _labels(lo, hi)[1] == expected


def test_steps_are_one_two_or_five_times_a_power_of_ten_and_give_about_five_ticks():
    rng = np.random.default_rng(1)
    for span in 10.0 ** rng.uniform(-14, 14, 300):
        step = nice_step(span)
        mantissa = step / 10.0 ** math.floor(math.log10(step) + 1e-9)
        assert min(abs(mantissa - m) for m in (1, 2, 5)) < 1e-9, (span, step)
        assert 2.5 <= span / step <= 8, (span, step)


def test_random_axes_have_distinct_labels_that_read_back_as_their_ticks():
    rng = np.random.default_rng(7)
    for _ in range(2000):
        centre = rng.choice([0.0, 1.0, -1.0]) * 10.0 ** rng.uniform(-15, 15)
        span = 10.0 ** rng.uniform(-14, 12) * max(1.0, abs(centre)) ** rng.choice([0, 1])
        lo, hi = centre - span * rng.uniform(0, 1), centre + span * rng.uniform(0.01, 1)
        ticks, labels = _labels(lo, hi)
        if hi - lo < 1e-12 * max(abs(lo), abs(hi)):
            continue  # beyond float64's resolution
        assert len(ticks) >= 2, (lo, hi)
        assert len(set(labels)) == len(labels), (lo, hi, labels)
        step = ticks[1] - ticks[0]
        for v, s in zip(ticks, labels):
            assert abs(_read(s) - v) <= 0.05 * step, (lo, hi, v, s)
            assert not (s.startswith(MINUS) and _read(s) == 0.0), (lo, hi, s)  # no "-0"
            assert s == "0" or _read(s) != 0.0 or v == 0.0, (lo, hi, v, s)  # nothing rounds to 0
        assert len(set(len(s.replace(MINUS, "")) for s in labels if s != "0")) <= 2  # written alike


def test_ticks_are_exact_multiples_without_round_off():
    ticks, step = linear_ticks(0.0, 1.0)
    assert ticks == [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]  # 0.6, not 3 * 0.2 = 0.6000000000000001
    ticks, step = linear_ticks(0.3, 0.9)
    assert ticks == [0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]
    ticks, _ = linear_ticks(-0.3, 0.3)
    assert 0.0 in ticks and all(math.copysign(1.0, v) > 0 for v in ticks if v == 0.0)  # +0, not -0


def test_a_log_axis_is_ticked_at_powers_of_ten_labelled_as_numbers():
    ticks, labels = log_ticks(1e-3, 1e5)
    assert all(math.log10(v) == round(math.log10(v)) for v in ticks)
    assert labels[0] == "0.001" and labels[-1] in ("10000", "100000", "1e5")
    ticks, labels = log_ticks(3.0, 70.0)  # less than two decades: 2 and 5 times them too
    assert ticks == [5.0, 10.0, 20.0, 50.0] and labels == ["5", "10", "20", "50"]
    ticks, labels = log_ticks(2.4, 14.0)  # within one decade: every whole multiple
    assert labels == ["3", "4", "5", "6", "7", "8", "9", "10"]
    ticks, labels = log_ticks(1e-9, 1e-7)
    assert labels[0] == "1e\u22129" and len(set(labels)) == len(labels)
    assert log_ticks(0.0, 1.0) == ([], [])  # no log axis through zero
