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
- A logarithmic axis (:func:`log_ticks`) is ticked as matplotlib's ``LogLocator`` with
  ``subs``: powers of ten (every one, or every 2nd, 3rd, 5th ...), or 1-3, 1-2-5, 1-2-3-5,
  1-1.5-2-3-5-7, 1-1.2-...-8 times them, or nice linear steps on a sliver of a decade: the
  set with about five ticks whose labels do not touch at the axis' length in pixels and
  that has a tick near each end. Its labels are numbers ("0.01", "150", "1e6", "2.5e-5").
- A readout beside a plot (:func:`readout_text`) has the digits that tell the last frames'
  values apart and is written in its axis' notation ("-0.8801e-5" beside "0.5e-5").
"""

from __future__ import annotations

import math

__all__ = ["nice_step", "linear_ticks", "log_ticks", "tick_labels", "format_tick", "label_extent", "readout_text", "MINUS"]

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


#: the multiples of each power of ten a log axis may be ticked at, densest first: each set
#: spaced nearly evenly in log space (a tick's neighbour is 1.2-1.3x, 1.3-1.7x, 1.5-2x, 2-2.5x, 3x away)
LOG_SUBS: tuple[tuple[float, ...], ...] = (
    (1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0),
    (1.0, 1.5, 2.0, 3.0, 5.0, 7.0),
    (1.0, 2.0, 3.0, 5.0),
    (1.0, 2.0, 5.0),
    (1.0, 3.0),
)

#: what a tick label takes along its axis (CSS px, 11 px sans-serif as the panel draws it,
#: with a little air): a line's height on a vertical axis, its width on a horizontal one
LABEL_HEIGHT_PX = 15.0
LABEL_CHAR_PX = 6.5
LABEL_PAD_PX = 8.0


def label_extent(label: str, horizontal: bool) -> float:
    """How much of its axis (CSS px) a tick label needs, its neighbours kept clear."""
    return len(label) * LABEL_CHAR_PX + LABEL_PAD_PX if horizontal else LABEL_HEIGHT_PX
#: the most of a log axis (a share of it) between an end and the tick nearest it
LOG_MAX_END_GAP = 0.3


def _log_candidates(lo: float, hi: float) -> list[tuple[list[float], list[str]]]:
    """Every tick set a log axis over ``[lo, hi]`` may use, with its labels."""
    e0 = math.floor(math.log10(lo)) - 1
    e1 = math.floor(math.log10(hi)) + 1
    out: list[tuple[list[float], list[str]]] = []
    for subs in LOG_SUBS:
        ticks = [float(f"{m}e{e}") for e in range(e0, e1 + 1) for m in subs]  # exact decimals: 0.015, not 0.015000000000000001
        ticks = [v for v in ticks if lo * (1 - 1e-9) <= v <= hi * (1 + 1e-9)]
        out.append((ticks, [_log_label(v) for v in ticks]))
    decades = e1 - e0
    every = 1
    while every <= decades:
        ticks = [float(f"1e{e}") for e in range(e0, e1 + 1) if e % every == 0]
        ticks = [v for v in ticks if lo * (1 - 1e-9) <= v <= hi * (1 + 1e-9)]
        out.append((ticks, [_log_label(v) for v in ticks]))
        every = {1: 2, 2: 3, 3: 5}.get(every, every * 2)
    if math.log10(hi / lo) < 1.0:  # a narrow axis is nearly linear: 2.2, 2.4, 2.6 ...
        for target in (2, 3, TARGET_TICKS, 8):
            ticks, step = linear_ticks(lo, hi, target)
            ticks = [v for v in ticks if v > 0]
            out.append((ticks, tick_labels(ticks, step)))
    return out


def log_ticks(lo: float, hi: float, *, length_px: float = 200.0, horizontal: bool = False, target: int = TARGET_TICKS) -> tuple[list[float], list[str]]:
    """``(ticks, labels)`` of a logarithmic axis over ``[lo, hi]`` (``0 < lo < hi``).

    The rule (as matplotlib's ``LogLocator`` with ``subs``): among the tick sets of
    :func:`_log_candidates` -- powers of ten (every one, every 2nd, 3rd, 5th ...), 1-3,
    1-2-5, 1-2-3-5, 1-1.5-2-3-5-7 and 1-1.2-1.5-2-2.5-3-4-5-6-8 times them, and nice linear steps
    on an axis of less than a decade -- the one whose neighbouring ticks are at least
    their labels' extent apart on an axis ``length_px`` long (:func:`label_extent`: their
    labels never touch; ``horizontal``: an x axis, where labels take their width), that has a tick within
    :data:`LOG_MAX_END_GAP` of each end, and whose number of ticks is nearest ``target``
    (then: the ends closest). Labels are numbers: "0.01", "150", "1e6", "2.5e-5".
    """
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo <= 0 or hi <= lo:
        return [], []
    span = math.log10(hi) - math.log10(lo)
    if span < 1e-9:
        return [], []
    best: tuple[tuple[float, ...], list[float], list[str]] | None = None
    for ticks, labels in _log_candidates(lo, hi):
        if len(ticks) < 2 or len(set(labels)) != len(labels):
            continue
        logs = [math.log10(v) for v in ticks]
        px = length_px / span  # CSS px a decade
        ends = max(logs[0] - math.log10(lo), math.log10(hi) - logs[-1]) / span
        clear = all((b - a) * px >= 0.5 * (label_extent(s, horizontal) + label_extent(t, horizontal)) for a, b, s, t in zip(logs, logs[1:], labels, labels[1:]))
        rank = 0.0 if clear and ends <= LOG_MAX_END_GAP else 1.0 if clear else 2.0
        key = (rank, abs(len(ticks) - target), ends)
        if best is None or key < best[0]:
            best = (key, ticks, labels)
    if best is None:  # not even two ticks fit (a sliver of an axis): its ends
        return [lo, hi], [_log_label(lo, digits=3), _log_label(hi, digits=3)]
    return best[1], best[2]


def _log_label(v: float, digits: int = 2) -> str:
    """A tick of a log axis as a number, with the significant digits it has (at most
    ``digits``): "0.01", "150", "2.5", "1e6", "1.5e-5"."""
    text = f"{v:.{digits}g}"
    if "e" in text:
        mant, _, exp = text.partition("e")
        e = int(exp)
        if -3 <= e < 6:
            text = f"{v:.{max(0, digits - 1 - e)}f}".rstrip("0").rstrip(".") if "." in f"{v:.{max(0, digits - 1 - e)}f}" else f"{v:.0f}"
        else:
            text = f"{mant}e{e}"
    return text.replace("-", MINUS)


#: the most significant digits a readout shows (float64 holds about 15)
READOUT_MAX_DIGITS = 12
#: a readout's last digit is never finer than this share of its axis' tick step
READOUT_STEP_SHARE = 1e-6


def readout_resolution(value: float, recent: list[float] | None = None) -> float:
    """The last digit a readout of ``value`` shows: four significant digits, or finer when
    the recent values (the last few frames', in order) change by less than that from one
    frame to the next -- then one digit below their typical (median) change, so that
    3e8 + 12 sin t reads 300000011, not 3e+08; at most :data:`READOUT_MAX_DIGITS` digits."""
    mag = abs(value)
    res = 10.0 ** (math.floor(math.log10(mag)) - 3) if mag > 0 else math.inf
    if recent is not None and len(recent) >= 2:
        steps = [abs(b - a) for a, b in zip(recent, recent[1:]) if math.isfinite(a) and math.isfinite(b) and b != a]
        if steps:
            steps.sort()
            typical = steps[len(steps) // 2]
            res = min(res, 10.0 ** (math.floor(math.log10(typical)) - 1))
    if not math.isfinite(res):
        return 1.0
    if mag > 0:
        res = max(res, 10.0 ** (math.floor(math.log10(mag)) - READOUT_MAX_DIGITS + 1))
    return res


def readout_text(value: float, recent: list[float] | None = None, ticks: list[float] | None = None, log: bool = False) -> str:
    """A value shown beside a plot (the latest of a series, or its x), in its axis' notation.

    Digits: :func:`readout_resolution`. Notation: a linear axis' (``ticks``, :func:`format_tick`):
    fixed ("0.001022", "48.40") where its labels are fixed, else in units of its largest
    tick's power of ten like its labels ("-0.8801e-5" beside ticks "-0.5e-5", "3.00000011e8");
    a log axis or none: fixed between 10^-3 and 10^6, else "1.234e-5". Never "-0".
    """
    if not math.isfinite(value):
        return str(value)
    res = readout_resolution(value, recent)
    ticks = [v for v in (ticks or []) if math.isfinite(v)]
    largest = max((abs(v) for v in ticks), default=0.0)
    if not log and len(ticks) >= 2:
        step = abs(ticks[1] - ticks[0])
        if step > 0:
            # never finer than a millionth of the axis' step: round-off about 0 reads 0
            res = max(res, step * READOUT_STEP_SHARE)
            if abs(value) < 0.5 * res:
                return "0"
        fixed = step > 0 and _fixed(step, largest)
        exp_l = math.floor(math.log10(largest) + 1e-12) if largest > 0 else 0
    else:
        mag = abs(value)
        fixed = mag == 0 or 1e-3 <= mag < 1e6
        exp_l = math.floor(math.log10(mag) + 1e-12) if mag > 0 else 0
    exp_r = math.floor(math.log10(res) + 1e-9)
    if fixed and -exp_r <= 9:
        text = f"{value:.{max(0, -exp_r)}f}"
    else:
        text = f"{value / 10.0**exp_l:.{max(0, exp_l - exp_r)}f}e{exp_l}"
    if text.startswith("-") and not any(c in "123456789" for c in text.partition("e")[0]):
        text = text[1:]  # a value that rounds to zero reads 0, never -0
    return text.replace("-", MINUS)
