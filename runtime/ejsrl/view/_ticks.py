"""Axis ticks of plots and the text of their labels.

The rule for a label's text (``specs/reference.md``, "Plots"):

- Ticks are multiples of a *nice* step (1, 2 or 5 times a power of ten) chosen so that an
  axis gets about five of them; a value within a billionth of a step of zero is exactly 0
  (so no label reads "-0").
- Every label of an axis is written alike, with the decimals its step needs and no more:
  ticks 0, 0.25, 0.5 at a step of 0.25 read "0.00", "0.25", "0.50"; a step of 2 reads
  "0", "2", "4". Two ticks therefore never read the same.
- That *fixed* notation is used while the largest tick is below 10^6 in magnitude, at
  least 10^-3 (or zero), and the step needs at most six decimals. Otherwise every label
  is in scientific notation, all in units of the largest tick's power of ten, with the
  mantissa decimals the step needs: "-1.0e-5", "-0.5e-5", "0", "0.5e-5", "1.0e-5"
  ("0.5e-5" is 0.5 x 10^-5). SI prefixes ("15µ") are not used: next to a unit
  in the axis title they read as part of it (is "2m" 2 milli or 2 metres?).
- A minus sign is the typographic one (U+2212), as in print.
- A logarithmic axis is ticked at the powers of ten it spans (every 2nd, 3rd ... when it
  spans many decades), with 2 and 5 times them when it spans less than two decades, and
  every whole multiple (2, 3, ... 9 times them) within one decade; its labels are numbers
  ("0.01", "100", "1e6", "2e-5").
"""

from __future__ import annotations

import math

__all__ = ["nice_step", "linear_ticks", "log_ticks", "tick_labels", "format_tick", "MINUS"]

#: the minus sign of tick labels
MINUS = "\u2212"

#: about how many ticks an axis gets
TARGET_TICKS = 5


def nice_step(span: float, target: int = TARGET_TICKS) -> float:
    """The step (1, 2 or 5 x 10^k) that cuts ``span`` (> 0) into the number of parts
    nearest ``target`` (the larger step on a tie)."""
    raw = span / max(1, target)
    exp = math.floor(math.log10(raw))
    candidates = [m * 10.0**e for e in (exp - 1, exp, exp + 1) for m in (1.0, 2.0, 5.0)]
    return min(candidates, key=lambda s: (abs(span / s - target), -s))


def linear_ticks(lo: float, hi: float, target: int = TARGET_TICKS) -> tuple[list[float], float]:
    """``(ticks, step)``: the multiples of :func:`nice_step` within ``[lo, hi]`` (``lo < hi``).

    Each tick is the float nearest ``k * step`` written in decimal (no round-off: 0.6, not
    0.6000000000000001); zero is +0.0.
    """
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        return [], 0.0
    step = nice_step(hi - lo, target)
    exp = math.floor(math.log10(step) + 1e-9)
    mant = round(step / 10.0**exp)
    k0 = math.ceil(lo / step - 1e-9)
    k1 = math.floor(hi / step + 1e-9)
    # k * mant x 10^exp read from its decimal text: 0.6, not 3 * 0.2 = 0.6000000000000001
    ticks = [float(f"{k * mant}e{exp}") + 0.0 for k in range(k0, k1 + 1)]
    return ticks, step


def _decimals(step: float) -> int:
    """The decimals that write every multiple of ``step`` (1, 2 or 5 x 10^k) exactly."""
    return max(0, -math.floor(math.log10(step) + 1e-9))


def _pretty_exponent(text: str) -> str:
    """``"1.50e-05"`` -> ``"1.50e-5"``, ``"3e+06"`` -> ``"3e6"``."""
    mant, _, exp = text.partition("e")
    return f"{mant}e{int(exp)}"


def format_tick(value: float, step: float, largest: float) -> str:
    """One tick label by the module's rule: ``step`` is the axis' step, ``largest`` its largest |tick|."""
    if value == 0.0:
        return f"{0.0:.{_decimals(step)}f}" if _fixed(step, largest) else "0"
    if _fixed(step, largest):
        text = f"{value:.{_decimals(step)}f}"
    else:
        # every label of the axis in units of the largest tick's power of ten
        exp_l = math.floor(math.log10(largest) + 1e-12)
        exp_s = math.floor(math.log10(step) + 1e-9)
        digits = max(0, exp_l - exp_s)
        text = f"{value / 10.0**exp_l:.{digits}f}e{exp_l}"
    return text.replace("-", MINUS)


def _fixed(step: float, largest: float) -> bool:
    """Whether an axis with this step and largest |tick| is labelled in fixed notation."""
    if largest >= 1e6:
        return False
    if largest != 0.0 and largest < 1e-3:
        return False
    return _decimals(step) <= 6


def tick_labels(ticks: list[float], step: float) -> list[str]:
    """The labels of one linear axis' ``ticks`` (at ``step`` apart), written alike."""
    if not ticks:
        return []
    largest = max(abs(v) for v in ticks)
    return [format_tick(v, step, largest) for v in ticks]


def log_ticks(lo: float, hi: float) -> tuple[list[float], list[str]]:
    """``(ticks, labels)`` of a logarithmic axis over ``[lo, hi]`` (``0 < lo < hi``)."""
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo <= 0 or hi <= lo:
        return [], []
    e0 = math.floor(math.log10(lo) + 1e-9)
    e1 = math.floor(math.log10(hi) + 1e-9)
    decades = math.log10(hi) - math.log10(lo)
    if decades < 1:
        mults = (1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0)
        every = 1
    elif decades < 2:
        mults = (1.0, 2.0, 5.0)
        every = 1
    else:
        mults = (1.0,)
        every = max(1, math.ceil((e1 - e0 + 1) / 8))
    ticks: list[float] = []
    for e in range(e0, e1 + 1):
        if (e - e0) % every:
            continue
        for m in mults:
            v = float(f"{m}e{e}")  # exact decimal: 0.01, not 0.010000000000000002
            if lo * (1 - 1e-9) <= v <= hi * (1 + 1e-9):
                ticks.append(v)
    labels = [_log_label(v) for v in ticks]
    return ticks, labels


def _log_label(v: float) -> str:
    """A power of ten (or 2 or 5 times one) as a log axis labels it: "0.01", "100", "1e6"."""
    e = math.floor(math.log10(v) + 1e-9)
    if -3 <= e < 6:
        return f"{v:.{max(0, -e)}f}"
    return _pretty_exponent(f"{v:.0e}").replace("-", MINUS)
