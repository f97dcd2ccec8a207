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
    ticks, labels = log_ticks(1e-3, 1e5)  # many decades: powers of ten, every other one
    assert all(math.log10(v) == round(math.log10(v)) for v in ticks)
    assert labels == ["0.01", "1", "100", "10000"]
    ticks, labels = log_ticks(1.0, 1000.0)
    assert labels == ["1", "10", "100", "1000"]
    ticks, labels = log_ticks(10.0, 100.0)  # one decade: 1-2-3-5
    assert labels == ["10", "20", "30", "50", "100"]
    ticks, labels = log_ticks(1e-9, 1e-7)
    assert labels[0] == "1e\u22129" and labels[-1] == "1e\u22127" and len(set(labels)) == len(labels)
    assert log_ticks(1.5e-5, 3e-5)[1] == ["1.5e\u22125", "2e\u22125", "2.5e\u22125", "3e\u22125"]
    assert log_ticks(2.1, 2.9)[1] == ["2.2", "2.4", "2.6", "2.8"]  # a sliver of a decade: nice linear steps
    assert log_ticks(0.0, 1.0) == ([], [])  # no log axis through zero


def test_the_trials_energy_axis_from_2_to_19_is_labelled_up_to_its_top_and_nowhere_crowded():
    # it was 2, 3, 4, 5, 6, 7, 8, 9, 10: 8, 9 and 10 nearly touching and nothing over the top 30 %
    ticks, labels = log_ticks(2.0, 19.0, length_px=180.0)
    assert labels == ["2", "3", "5", "7", "10", "15"]
    ticks, labels = log_ticks(2.0, 19.0, length_px=90.0)  # a short plot: fewer
    assert labels == ["2", "3", "5", "10"]


def _log_rule_holds(lo: float, hi: float, length_px: float, horizontal: bool) -> float:
    """The log axis rule, checked independently of how the ticks were chosen; returns the
    share of the axis between an end and the tick nearest it (the larger of the two)."""
    ticks, labels = log_ticks(lo, hi, length_px=length_px, horizontal=horizontal)
    span = math.log10(hi / lo)
    assert len(ticks) >= 2, (lo, hi, ticks)
    assert len(set(labels)) == len(labels), (lo, hi, labels)  # distinct
    assert all(lo * (1 - 1e-9) <= v <= hi * (1 + 1e-9) for v in ticks), (lo, hi, ticks)  # in range
    assert ticks == sorted(ticks)
    for v, s in zip(ticks, labels):
        assert _read(s) == pytest.approx(v, rel=1e-9), (v, s)  # the label is the tick's value
        assert "-" not in s
    px = length_px / span
    for a, b, sa, sb in zip(ticks, ticks[1:], labels, labels[1:]):
        gap = math.log10(b / a) * px  # CSS px between two labels' centres
        # labels 11 px high, about 6 px a character wide: never overlapping
        need = 0.5 * (len(sa) + len(sb)) * 6.0 + 4 if horizontal else 13.0
        assert gap >= need, (lo, hi, length_px, labels)
    # a labelled tick near each end: within 45 % of the axis (in log space; a sliver of a decade on a narrow x axis
    # with long labels), and 30 % where the labels leave room
    ends = max(math.log10(ticks[0] / lo), math.log10(hi / ticks[-1])) / span
    assert ends <= 0.45, (lo, hi, labels)
    assert len(ticks) <= 12
    return ends


def test_random_log_axes_follow_the_rule():
    rng = np.random.default_rng(24)
    ends = []
    for _ in range(3000):
        lo = 10.0 ** rng.uniform(-12, 12)
        hi = lo * 10.0 ** rng.choice([rng.uniform(0.02, 1.5), rng.uniform(1.5, 20)])
        length_px, horizontal = (float(rng.uniform(300, 900)), True) if rng.random() < 0.5 else (float(rng.uniform(90, 700)), False)
        ends.append(_log_rule_holds(lo, hi, length_px, horizontal))
    assert np.mean(np.array(ends) <= 0.3) >= 0.99
