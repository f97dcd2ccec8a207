"""A plot as one frame of the 2D panel: ranges, ticks, legend and the series' items.

The server decides everything the client draws (see the 2D panel contract in
``ejsrl.view._panel2d``): :func:`plot_frame` turns what each series shows this frame (a
:class:`Layer`: points, or a histogram's bins) and the two axes' settings (:class:`AxisConf`)
into the frame dict -- bounds in data units, tick values with their label text
(:mod:`ejsrl.view._ticks`), axis titles, the legend, and one item per series.

Automatic ranges (an axis without a fixed ``range``):

- x of a strip chart: the window that the buffer's rule gives (:func:`x_range`), passed in
  as ``x_auto``;
- otherwise the data's extent (finite values only), widened by :data:`PAD` of its span on
  each side (a log axis: of its decades); a histogram's axis spans its bins, and its
  counts start from 0;
- values that vary less than :func:`min_span` (1 % of their magnitude; a quantity constant
  up to round-off) get an axis ``2 * min_span`` wide centred on them, kept while they
  stay inside it (``previous``), so the line looks flat and its ticks read differently.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ejsrl.view._ticks import linear_ticks, log_ticks, tick_labels

__all__ = [
    "Layer",
    "AxisConf",
    "plot_frame",
    "histogram",
    "x_range",
    "min_span",
    "flat_range",
    "auto_range",
    "axis_ticks",
    "encode_xy",
    "decode_xy",
    "PAD",
    "PLOT_AREA_PX",
]

#: the margin an automatic range leaves on each side of the data, as a share of its span
PAD = 0.05

#: the least span shown, relative to the values' magnitude, and its absolute floor
MIN_REL_SPAN = 1e-2
MIN_ABS_SPAN = 1e-12


def encode_xy(a: np.ndarray) -> str:
    """An (N, 2) or (N, 4) array as the contract's ``xy``: base64 of little-endian float32, row-major."""
    from ejsrl.view._panel2d import encode_xy as encode

    return encode(a)


@dataclass
class Layer:
    """What one series draws in this frame.

    ``kind``: ``"line"``, ``"scatter"`` or ``"histogram"``; ``xy``: (N, 2) points in data
    units (line, scatter); ``edges`` (B + 1,) and ``counts`` (B,): a histogram's bins;
    ``width``: line width (px); ``marker``/``size``: marker shape and size (px) of a scatter
    series, or of a line drawn with markers; ``color``: CSS colour.
    """

    kind: str
    label: str
    color: str
    xy: np.ndarray | None = None
    edges: np.ndarray | None = None
    counts: np.ndarray | None = None
    width: float = 2.0
    marker: str | None = None
    size: float = 6.0


@dataclass
class AxisConf:
    """One axis: its ``title`` (with the unit, "theta (rad)"), ``log`` scale, and a fixed
    ``range`` (lo, hi) in data units, or None for automatic."""

    title: str = ""
    log: bool = False
    range: tuple[float, float] | None = None


def x_range(x: np.ndarray, window: float | None) -> tuple[float, float]:
    """A strip chart's x axis for points at ``x`` (in the order they came): the window, or the data.

    With a ``window``: ``[x_last - window, x_last]`` once the data is longer than it,
    ``[x_first, x_first + window]`` before. Without: the data's extent (a unit span for one point).
    """
    if len(x) == 0:
        return (0.0, float(window) if window else 1.0)
    first, last = float(x[0]), float(x[-1])
    if window:
        w = float(window)
        return (last - w, last) if last - first > w else (first, first + w)
    lo, hi = float(np.min(x)), float(np.max(x))
    return (lo, hi) if hi > lo else (lo, lo + 1.0)


def min_span(lo: float, hi: float) -> float:
    """The least span shown for values in ``[lo, hi]``: values that vary less are drawn as flat."""
    if lo == hi == 0.0:  # exactly zero (a servo at rest): +-1, not ticks over +-1e-12
        return 1.0
    return max(MIN_REL_SPAN * max(abs(lo), abs(hi)), MIN_ABS_SPAN)


def flat_range(lo: float, hi: float, current: tuple[float, float] | None = None) -> tuple[float, float] | None:
    """A range for values in ``[lo, hi]`` that span less than :func:`min_span`, else None.

    Centred on the values and ``2 * min_span`` wide; ``current`` (the range shown now) is
    kept while it still holds the values and is 1.5 to 4 times ``min_span`` wide, so a flat
    line does not re-scale at every frame.
    """
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return None
    span = min_span(lo, hi)
    if hi - lo >= span:
        return None
    if current is not None and current[0] <= lo and hi <= current[1] and 1.5 * span <= current[1] - current[0] <= 4 * span:
        return current
    mid = 0.5 * (lo + hi)
    return (mid - span, mid + span)


def auto_range(lo: float, hi: float, *, log: bool = False, pad: bool = True, current: tuple[float, float] | None = None) -> tuple[float, float]:
    """The automatic range for data in ``[lo, hi]`` (finite; on a log axis both > 0)."""
    if log:
        a, b = math.log10(lo), math.log10(hi)
        if b - a < 0.01:
            mid = 0.5 * (a + b)
            a, b = mid - 0.5, mid + 0.5
        elif pad:
            d = PAD * (b - a)
            a, b = a - d, b + d
        return (10.0**a, 10.0**b)
    flat = flat_range(lo, hi, current)
    if flat is not None:
        return flat
    if pad:
        d = PAD * (hi - lo)
        return (lo - d, hi + d)
    return (lo, hi)


def histogram(values: np.ndarray, bins: int, bin_range: tuple[float, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(counts (bins,), edges (bins + 1,))`` of the finite ``values``, as ``numpy.histogram``
    bins them (the last bin holds its right edge); values outside ``bin_range`` are not counted."""
    v = np.asarray(values, dtype=float).ravel()
    v = v[np.isfinite(v)]
    if bin_range is None and len(v) == 0:
        bin_range = (0.0, 1.0)
    counts, edges = np.histogram(v, bins=int(bins), range=bin_range)
    return counts.astype(float), edges


#: the plot area a frame's ticks are chosen for when the caller does not say (CSS px): an
#: x axis in the default 400 px panel, a y axis of the default 240 px plot
PLOT_AREA_PX = (300.0, 180.0)


def axis_ticks(lo: float, hi: float, log: bool, *, long_at: int = 0, length_px: float | None = None) -> list[list[Any]]:
    """``[[value, label], ...]`` of an axis over ``[lo, hi]`` (:mod:`ejsrl.view._ticks`).

    ``long_at``: when a label is longer than this many characters (0: never), the axis is
    ticked more sparsely (about 3 ticks instead of 5), so that x labels do not run together;
    a nonzero ``long_at`` also marks a horizontal (x) axis. ``length_px``: the axis' length
    on screen (CSS px), which a log axis spaces its labels by. Remembered for the last
    few hundred axes: a plot's y axis keeps its range from frame to frame (its readouts and
    picture are sent 15 times a second by every session of a class).
    """
    return [[v, s] for v, s in _axis_ticks(float(lo), float(hi), bool(log), int(long_at), length_px)]


@functools.lru_cache(maxsize=512)
def _axis_ticks(lo: float, hi: float, log: bool, long_at: int, length_px: float | None) -> tuple[tuple[float, str], ...]:
    if log:
        horizontal = bool(long_at)
        px = length_px if length_px else PLOT_AREA_PX[0 if horizontal else 1]
        ticks, labels = log_ticks(lo, hi, length_px=px, horizontal=horizontal)
        return tuple(zip(ticks, labels))
    ticks, step = linear_ticks(lo, hi)
    labels = tick_labels(ticks, step)
    if long_at and labels and max(len(s) for s in labels) > long_at:
        ticks, step = linear_ticks(lo, hi, target=3)
        labels = tick_labels(ticks, step)
    return tuple(zip(ticks, labels))


def _extent(values: list[np.ndarray], log: bool) -> tuple[float, float] | None:
    """The least and greatest finite value (> 0 on a log axis) of ``values``, or None."""
    lo, hi = math.inf, -math.inf
    for v in values:
        v = v[np.isfinite(v)]
        if log:
            v = v[v > 0]
        if len(v):
            lo, hi = min(lo, float(v.min())), max(hi, float(v.max()))
    return (lo, hi) if lo <= hi else None


def _on_log(xy: np.ndarray, x_log: bool, y_log: bool) -> np.ndarray:
    """Points with the coordinates a log axis cannot show (<= 0) set to NaN (a line breaks there)."""
    if not (x_log or y_log):
        return xy
    xy = xy.copy()
    if x_log:
        xy[xy[:, 0] <= 0, 0] = np.nan
    if y_log:
        xy[xy[:, 1] <= 0, 1] = np.nan
    return xy


def _rgba(color: str, alpha: float) -> str:
    """``"rgb(r, g, b)"`` (or ``#rrggbb``) with an alpha; other CSS colours as they are."""
    if color.startswith("rgb(") and color.endswith(")"):
        return f"rgba({color[4:-1]}, {alpha})"
    if color.startswith("#") and len(color) == 7:
        r, g, b = (int(color[i : i + 2], 16) for i in (1, 3, 5))
        return f"rgba({r}, {g}, {b}, {alpha})"
    return color


def _ranges(layers: list[Layer], x: AxisConf, y: AxisConf, x_auto: tuple[float, float] | None, previous: tuple[float, ...] | None) -> tuple[tuple[float, float], tuple[float, float]]:
    """The x and y ranges of a frame (see the module's docstring)."""
    prev_x = (previous[0], previous[1]) if previous else None
    prev_y = (previous[2], previous[3]) if previous else None
    if x.range is not None:
        xr = x.range
    elif x_auto is not None and not x.log:
        xr = x_auto
    else:
        xs = [layer.xy[:, 0] for layer in layers if layer.xy is not None]
        xs += [layer.edges for layer in layers if layer.edges is not None]
        ext = _extent(xs, x.log)
        only_bins = all(layer.kind == "histogram" for layer in layers)
        if ext is None:
            xr = (1.0, 10.0) if x.log else (0.0, 1.0)
        else:
            xr = auto_range(*ext, log=x.log, pad=not only_bins, current=prev_x)
    if y.range is not None:
        yr = y.range
    else:
        ys = [layer.xy[:, 1] for layer in layers if layer.xy is not None]
        ys += [layer.counts for layer in layers if layer.counts is not None]
        ext = _extent(ys, y.log)
        if ext is None:
            yr = (1.0, 10.0) if y.log else (0.0, 1.0)
        else:
            lo, hi = ext
            if any(layer.counts is not None for layer in layers) and not y.log:
                lo = min(lo, 0.0)
                yr = (lo, hi * (1 + PAD)) if hi > lo else (0.0, 1.0)
            else:
                yr = auto_range(lo, hi, log=y.log, current=prev_y)
    return xr, yr


def plot_frame(
    title: str,
    layers: list[Layer],
    x: AxisConf,
    y: AxisConf,
    *,
    x_auto: tuple[float, float] | None = None,
    legend: bool = True,
    grid: bool = True,
    previous: tuple[float, ...] | None = None,
    area_px: tuple[float, float] = PLOT_AREA_PX,
) -> dict[str, Any]:
    """The 2D panel frame of a plot (a JSON-able dict, the contract of ``ejsrl.view._panel2d``).

    ``layers``: what each series draws, in order; ``x``/``y``: the axes' settings;
    ``x_auto``: a strip chart's x range (:func:`x_range`) when ``x`` has no fixed range;
    ``legend``: draw the labelled series' legend; ``previous``: the bounds of the frame
    shown before (a flat range is kept while the values stay inside it); ``area_px``: the
    plot area's (width, height) on screen, CSS px, about (log axes space their labels by it).
    """
    xr, yr = _ranges(layers, x, y, x_auto, previous)
    items: list[dict[str, Any]] = []
    for layer in layers:
        if layer.kind == "histogram" and layer.edges is not None and layer.counts is not None:
            base = yr[0] if y.log else 0.0
            tops = layer.counts.copy()
            if y.log:
                tops[tops <= 0] = base  # an empty bin has no bar on a log axis
            rects = np.column_stack((layer.edges[:-1], np.full(len(tops), base), layer.edges[1:], tops))
            items.append({"t": "rects", "xy": encode_xy(rects), "fill": _rgba(layer.color, 0.55), "stroke": layer.color, "width": 1.0})
            continue
        if layer.xy is None or len(layer.xy) == 0:
            continue
        xy = _on_log(layer.xy, x.log, y.log)
        if layer.kind == "line":
            items.append({"t": "polyline", "xy": encode_xy(xy), "stroke": layer.color, "width": float(layer.width), "dash": None, "closed": False, "fill": None})
        if layer.kind == "scatter" or layer.marker:
            pts = xy[np.isfinite(xy).all(axis=1)]
            items.append({"t": "markers", "xy": encode_xy(pts), "shape": layer.marker or "circle", "size": float(layer.size), "fill": layer.color, "stroke": None})
    entries = []
    if legend:
        for layer in layers:
            if layer.label:
                kind = {"histogram": "bar", "scatter": "marker"}.get(layer.kind, "line")
                entries.append({"label": layer.label, "color": layer.color, "kind": kind})
    return {
        "bounds": [float(xr[0]), float(xr[1]), float(yr[0]), float(yr[1])],
        "aspect": "free",
        "background": None,
        "title": title,
        "axes": {
            "x": {"title": x.title, "log": bool(x.log), "ticks": axis_ticks(xr[0], xr[1], x.log, long_at=7, length_px=area_px[0])},
            "y": {"title": y.title, "log": bool(y.log), "ticks": axis_ticks(yr[0], yr[1], y.log, length_px=area_px[1])},
            "grid": bool(grid),
        },
        "legend": entries,
        "items": items,
    }


def decode_xy(text: str, cols: int) -> np.ndarray:
    """The inverse of :func:`encode_xy` (for tests and tools): (N, cols) float32 -> float64."""
    import base64

    return np.frombuffer(base64.b64decode(text), dtype="<f4").reshape(-1, cols).astype(float)

