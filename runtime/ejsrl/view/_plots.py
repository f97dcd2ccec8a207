"""Plots (uPlot) and images in the control panel.

A :class:`PlotBuffer` keeps the points of one ``Plot`` (one per display frame), trims them
to the plot's ``window`` (x-span) and ``max_points``; :class:`PlotBinding` pushes them to
a viser uPlot chart at most ``max_rate`` times a second. :class:`ImageBinding` sends an
image only when its pixels or its overlay points changed.

Two things about what the chart is sent:

- The x range is sent, not left to the chart: :func:`x_range` — [x_last - window, x_last]
  once the data is longer than ``window``, [x_first, x_first + window] before, the data's
  extent without a window. viser's chart, left to auto-scale x, keeps the x range
  *relative* to the data's extent across updates (so a user's zoom survives new data) and
  learns that relation from the range it shows; in the first updates that range is still
  empty (null), and it learns e.g. [0, 1/span], which it keeps: the x axis ran far past
  the data, squeezed into the left tenth of the plot. A fixed ``range`` turns that off.
- uPlot auto-scales y to the data's extent however small, so a quantity that is constant
  up to round-off (an energy that RK4 keeps to 1e-9) shows as a steep line with equal tick
  labels. When the y values span less than :func:`min_y_span` (1 % of their magnitude) the
  y scale is pinned to ± that span around them (and kept while the values stay flat and
  inside it), so the line looks flat. A ``y_range`` in the spec always wins.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ejsrl.view._wire import set_markdown, set_prop
from ejsrl.view.elements import Image, Plot, escape_markdown
from ejsrl.world.colors import to_rgb

__all__ = ["PlotBuffer", "PlotBinding", "ImageBinding", "prepare_image", "PALETTE"]

#: colours of series that name none (matplotlib's tab10)
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf")


def _css(color: Any, i: int) -> str:
    if color is None:
        return PALETTE[i % len(PALETTE)]
    try:
        r, g, b = (int(round(255 * c)) for c in to_rgb(color))
    except Exception:
        return PALETTE[i % len(PALETTE)]
    return f"rgb({r}, {g}, {b})"


class PlotBuffer:
    """The points of one plot: x (n,) and one y (n,) per series, trimmed to window and max_points."""

    def __init__(self, n_series: int, *, window: float | None = None, max_points: int = 2000) -> None:
        self.n_series = n_series
        self.window = window
        self.max_points = max(2, int(max_points))
        cap = self.max_points * 2
        self._x = np.empty(cap)
        self._y = np.empty((n_series, cap))
        self._start = 0
        self._end = 0
        self.rev = 0

    def __len__(self) -> int:
        return self._end - self._start

    def clear(self) -> None:
        """Forget every point."""
        self._start = self._end = 0
        self.rev += 1

    def append(self, x: float, ys: list[float]) -> bool:
        """Add one point; returns False (and adds nothing) if any value is not finite."""
        if not math.isfinite(x) or not all(math.isfinite(y) for y in ys):
            return False
        if len(self) and x == self._x[self._end - 1]:
            # the same instant again (paused, or a value changed from the panel): replace it
            last = self._end - 1
            if self._y[:, last].tolist() == list(ys):
                return True
            self._y[:, last] = ys
            self.rev += 1
            return True
        if len(self) and x < self._x[self._end - 1]:
            # the independent variable went back (a reset, or the user set it): start over
            self.clear()
        if self._end == len(self._x):
            n = len(self)
            self._x[:n] = self._x[self._start : self._end]
            self._y[:, :n] = self._y[:, self._start : self._end]
            self._start, self._end = 0, n
        self._x[self._end] = x
        self._y[:, self._end] = ys
        self._end += 1
        if len(self) > self.max_points:
            self._start = self._end - self.max_points
        if self.window is not None:
            # x only grows: the points that left the window are the first few, usually one
            lo = x - self.window
            xs = self._x
            while xs[self._start] < lo:
                self._start += 1
        self.rev += 1
        return True

    def data(self) -> tuple[np.ndarray, ...]:
        """``(x, y_0, y_1, ...)`` as fresh float64 arrays."""
        s, e = self._start, self._end
        return (self._x[s:e].copy(), *(self._y[i, s:e].copy() for i in range(self.n_series)))


def _value_text(v: float) -> str:
    """A value to four significant digits, without an exponent between 0.001 and 10^6."""
    mag = abs(v)
    if 1e-3 <= mag < 1e6:
        text = f"{v:.{max(0, 3 - int(np.floor(np.log10(mag))))}f}"
    else:
        text = f"{v:.4g}"
    return text.replace("-", "\u2212")


#: pixels per character of uPlot's tick labels, and for the tick, the gap and the axis title
_TICK_CHAR_PX = 7.0
_Y_AXIS_EXTRA_PX = 22
_Y_AXIS_MIN_PX = 50


def _tick_chars(lo: float, hi: float) -> int:
    """Characters of the widest of about five uPlot tick labels over ``[lo, hi]``."""
    span = abs(hi - lo) or abs(hi) or 1.0
    decimals = max(0, int(-np.floor(np.log10(span / 5.0))))
    return max(len(f"{v:,.{decimals}f}") for v in (lo, hi))


def x_tick_space(lo: float, hi: float) -> int:
    """The least pixels between x ticks so that their labels do not run into each other."""
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return 50
    return int(max(50, np.ceil((_TICK_CHAR_PX * _tick_chars(lo, hi) + 12) / 10.0) * 10))


def y_axis_size(lo: float, hi: float) -> int:
    """Pixels for the y axis so that uPlot's tick labels over ``[lo, hi]`` are not cut.

    uPlot labels about five ticks with the decimals their spacing needs and thousands
    separators ("-123,455.75"); the width grows with that text, in steps of 10 px.
    """
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return _Y_AXIS_MIN_PX
    px = _TICK_CHAR_PX * _tick_chars(lo, hi) + _Y_AXIS_EXTRA_PX
    return int(max(_Y_AXIS_MIN_PX, np.ceil(px / 10.0) * 10))


def x_range(x: np.ndarray, window: float | None) -> tuple[float, float]:
    """The x axis for points at ``x`` (sorted): the window, or the data (a unit span for one point)."""
    if len(x) == 0:
        return (0.0, float(window) if window else 1.0)
    first, last = float(x[0]), float(x[-1])
    if window:
        w = float(window)
        return (last - w, last) if last - first > w else (first, first + w)
    return (first, last) if last > first else (first, first + 1.0)


#: the least y span shown, relative to the values' magnitude, and its absolute floor. 1 %:
#: uPlot labels ticks with at most three decimals, so around 0.2 a smaller axis labels
#: every tick alike ("0.196")
Y_MIN_REL_SPAN = 1e-2
Y_MIN_ABS_SPAN = 1e-12


def min_y_span(lo: float, hi: float) -> float:
    """The least y span shown for values in ``[lo, hi]``: values that vary less are drawn as flat."""
    if lo == hi == 0.0:  # exactly zero (a servo at rest): +-1, not ticks "0 0 0 -0 -0" over +-1e-12
        return 1.0
    return max(Y_MIN_REL_SPAN * max(abs(lo), abs(hi)), Y_MIN_ABS_SPAN)


def flat_y_range(lo: float, hi: float, current: tuple[float, float] | None = None) -> tuple[float, float] | None:
    """A fixed y range for values in ``[lo, hi]`` that span less than :func:`min_y_span`, else None.

    The range is centred on the values and ``2 * min_y_span`` wide; ``current`` (the range
    shown now) is kept while it still fits the values, so a flat line does not re-scale
    the chart at every update.
    """
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return None
    span = min_y_span(lo, hi)
    if hi - lo >= span:
        return None
    if current is not None and current[0] <= lo and hi <= current[1] and current[1] - current[0] <= 4 * span:
        return current
    mid = 0.5 * (lo + hi)
    return (mid - span, mid + span)


#: after a tab connects to a chart that already holds points (a reload, a --shared lab), when
#: the chart's scales are sent again (seconds on the view's clock): see :meth:`PlotBinding.reshow`
RESHOW_AFTER = (0.5, 1.5, 3.0)


class PlotBinding:
    """One ``Plot`` element shown as a viser uPlot chart, with a line of current values below.

    The x axis is labelled with ``plot.x_label`` (else ``x_label``, the x expression), the
    y axis with ``plot.y_label``. uPlot's own legend shows values only under the mouse
    (``--`` otherwise), so the chart's legend is replaced by a Markdown line that shows
    each series' colour, label and latest value, and x's latest value.
    ``title`` / ``labels``: the title and series labels as shown now (they may hold
    ``{expr}``; :meth:`set_title` and :meth:`set_label` change them). ``height``: the
    chart's height in pixels (default: its width / 1.6).
    """

    def __init__(
        self,
        gui: Any,
        plot: Plot,
        *,
        x_label: str = "",
        title: str | None = None,
        labels: list[str] | None = None,
        max_rate: float = 15.0,
        clock: Callable[[], float] = time.monotonic,
        height: int | None = None,
    ) -> None:
        self.plot = plot
        self.buffer = PlotBuffer(len(plot.series), window=plot.window, max_points=plot.max_points)
        self.max_rate = max_rate
        self.clock = clock
        self._sent_rev = -1
        self._last_push = -math.inf
        #: when the scales are to be sent again (clock times, ascending): see :meth:`reshow`
        self._reshow_at: list[float] = []
        self.title = str(plot.title) if title is None else title
        self.labels = [str(s.label) for s in plot.series] if labels is None else list(labels)
        self.x_name = x_label or "x"
        self.colors = [_css(s.color, i) for i, s in enumerate(plot.series)]
        series = [{"label": self.x_name}]
        for i, s in enumerate(plot.series):
            series.append({"label": self.labels[i] or f"y{i + 1}", "stroke": self.colors[i], "width": 2})
        self._flat_y: tuple[float, float] | None = None
        self._x_range = x_range(np.zeros(0), plot.window)
        x_axis = getattr(plot, "x_label", "") or self.x_name
        y_axis = getattr(plot, "y_label", "") or None
        self._y_title = y_axis
        self._y_size = y_axis_size(*plot.y_range) if plot.y_range is not None else _Y_AXIS_MIN_PX + 10
        self._x_axis = {"label": x_axis, "size": 40, "labelSize": 18, "space": 50}
        self.handle = gui.add_uplot(
            data=self.buffer.data(),
            series=tuple(series),
            title=self.title or None,
            scales=self._scales(),
            # room for tick labels such as "-0.0025" on the left and a last x tick on the right
            axes=self._axes(),
            legend={"show": False},
            padding=(8, 28, 0, 4),
            aspect=1.6,
            height=height,
        )
        self.values = gui.add_markdown(self._values_text())

    def _scales(self) -> dict[str, Any]:
        """uPlot's scales: x fixed to :func:`x_range`; y fixed to ``y_range``, or to the flat range, or auto."""
        scales: dict[str, Any] = {"x": {"time": False, "auto": False, "range": [float(v) for v in self._x_range]}}
        if self.plot.y_range is not None:
            lo, hi = (float(v) for v in self.plot.y_range)
            scales["y"] = {"auto": False, "range": [lo, hi]}
        elif self._flat_y is not None:
            scales["y"] = {"auto": False, "range": [float(self._flat_y[0]), float(self._flat_y[1])]}
        else:
            scales["y"] = {"auto": True}
        return scales

    def _fit_scales(self, data: tuple[np.ndarray, ...]) -> None:
        """Send the scales when the x window moved or y became flat or not (see the module's docstring)."""
        xr = x_range(data[0], self.plot.window)
        flat = self._flat_y
        if self.plot.y_range is None and len(data[0]) and len(data) > 1:
            ys = np.concatenate(data[1:])
            flat = flat_y_range(float(ys.min()), float(ys.max()), self._flat_y)
        if xr != self._x_range or flat != self._flat_y:
            self._x_range, self._flat_y = xr, flat
            self.handle.scales = self._scales()

    def _axes(self) -> tuple[dict[str, Any], dict[str, Any]]:
        y = {"label": self._y_title, "size": self._y_size + (18 if self._y_title else 0), "labelSize": 18 if self._y_title else 0}
        return (self._x_axis, y)

    def _fit_axes(self, data: tuple[np.ndarray, ...]) -> None:
        """Resize the axes when the tick labels the data needs change width.

        The y axis grows to fit its widest label; x ticks are spaced so their labels do
        not run into each other. Sent only when a size changes (it redraws the chart).
        """
        if len(data[0]) == 0:
            return
        changed = False
        space = x_tick_space(*self._x_range)
        if space != self._x_axis["space"]:
            self._x_axis = dict(self._x_axis, space=space)
            changed = True
        ys = np.concatenate(data[1:]) if len(data) > 1 else np.zeros(0)
        if self.plot.y_range is None and len(ys):
            lo, hi = self._flat_y if self._flat_y is not None else (float(ys.min()), float(ys.max()))
            size = y_axis_size(lo, hi)
            if size != self._y_size:
                self._y_size = size
                changed = True
        if changed:
            self.handle.axes = self._axes()

    def _values_text(self) -> str:
        """The legend: colour, label and latest value of each series, then x's value."""
        n = len(self.buffer)
        last = [col[-1] for col in self.buffer.data()] if n else None
        parts = []
        for i, label in enumerate(self.labels):
            name = escape_markdown(label or f"y{i + 1}")
            value = f" = {_value_text(last[i + 1])}" if last is not None else ""
            parts.append(f'<span style="color:{self.colors[i]}">&#9632;</span>&nbsp;{name}{value}')
        x = f" &nbsp;at {escape_markdown(self.x_name)} = {_value_text(last[0])}" if last is not None else ""
        return " &nbsp; ".join(parts) + x

    def set_title(self, text: str) -> None:
        """Show a new title (a title with ``{expr}`` whose value changed)."""
        self.title = text
        self.handle.title = text or None

    def set_label(self, index: int, text: str) -> None:
        """Show a new label for series ``index`` (0-based)."""
        self.labels[index] = text
        series = [dict(s) for s in self.handle.series]
        series[index + 1]["label"] = text or f"y{index + 1}"
        self.handle.series = tuple(series)
        self.values.content = self._values_text()

    def append(self, x: Any, ys: list[Any]) -> None:
        """Record this frame's point (None or non-numeric values skip the frame)."""
        try:
            xf = float(x)
            yf = [float(y) for y in ys]
        except (TypeError, ValueError):
            return
        self.buffer.append(xf, yf)

    def reshow(self) -> None:
        """Send the scales again :data:`RESHOW_AFTER` seconds from now (by :meth:`push`).

        A tab that makes the chart with its points already in it (a reloaded tab, a new tab
        on a ``--shared`` lab) may get it from viser's uPlot client without ticks or grid:
        uPlot lays its axes out before the panel has its width and does not again until
        its size or scales change (as when the window scrolls; a window not yet full did
        not scroll for up to its length). New scales make the client build the chart
        again, at its width, with the points it holds.
        """
        now = self.clock()
        self._reshow_at = [now + d for d in RESHOW_AFTER]

    def push(self, *, force: bool = False) -> bool:
        """Send the data if it changed and the rate allows; returns True if sent."""
        now = self.clock()
        if self._reshow_at and now >= self._reshow_at[0]:
            while self._reshow_at and now >= self._reshow_at[0]:
                self._reshow_at.pop(0)
            self.handle.scales = self._scales()  # a new dict: always sent
        if self.buffer.rev == self._sent_rev:
            return False
        if not force and now - self._last_push < 1.0 / self.max_rate:
            return False
        data = self.buffer.data()
        self._fit_scales(data)
        self._fit_axes(data)
        set_prop(self.handle, "data", data)
        text = self._values_text()
        if text != self.values.content:
            set_markdown(self.values, text)
        self._sent_rev = self.buffer.rev
        self._last_push = now
        return True

    def clear(self) -> None:
        """Forget the data (on reset) and show the empty plot."""
        self.buffer.clear()
        self.push(force=True)


def prepare_image(img: Any, points: Any = None) -> np.ndarray | None:
    """An (H, W, 3) uint8 image ready for viser, with ``points`` (N, 2) (x, y) drawn over it.

    Returns None if ``img`` is not an image.
    """
    if img is None:
        return None
    a = np.asarray(img)
    if a.ndim == 2:
        a = np.repeat(a[:, :, None], 3, axis=2)
    elif a.ndim == 3 and a.shape[2] == 1:
        a = np.repeat(a, 3, axis=2)
    elif a.ndim == 3 and a.shape[2] == 4:
        a = a[:, :, :3]
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] == 0 or a.shape[1] == 0:
        return None
    if a.dtype != np.uint8:
        if np.issubdtype(a.dtype, np.floating) and a.size and float(np.nanmax(a)) <= 1.0:
            a = np.clip(np.nan_to_num(a) * 255.0, 0, 255).astype(np.uint8)
        else:
            a = np.clip(np.nan_to_num(a.astype(np.float64)), 0, 255).astype(np.uint8)
    a = np.ascontiguousarray(a)
    if points is not None:
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if len(pts):
            import cv2

            a = a.copy()
            h, w = a.shape[:2]
            r = max(2, int(round(min(h, w) / 80)))
            for x, y in pts:
                if np.isfinite(x) and np.isfinite(y) and -w < x < 2 * w and -h < y < 2 * h:
                    c = (int(round(x)), int(round(y)))
                    cv2.circle(a, c, r + 1, (0, 0, 0), 2, lineType=cv2.LINE_AA)
                    cv2.circle(a, c, r, (255, 40, 40), 2, lineType=cv2.LINE_AA)
    return a


#: the most pictures a second an image element reads and sends
IMAGE_RATE = 20.0


class ImageBinding:
    """One ``Image`` element: sends the picture only when the source or the points changed."""

    def __init__(
        self, gui: Any, image: Image, *, label: str | None = None, max_rate: float = IMAGE_RATE, clock: Callable[[], float] = time.monotonic
    ) -> None:
        self.image = image
        self.max_rate = max_rate
        self.clock = clock
        self._last_src: np.ndarray | None = None
        self._last_pts: np.ndarray | None = None
        self._last_push = -math.inf
        #: when a source was last looked at (sent or not): read again at most max_rate a second
        self._last_read = -math.inf
        self.pushes = 0
        placeholder = np.full((2, 2, 3), 40, dtype=np.uint8)
        label = str(image.label or "") if label is None else label
        self.handle = gui.add_image(placeholder, label=label or None, format="jpeg", jpeg_quality=85)

    def due(self) -> bool:
        """Whether the rate allows a new picture now: if not, the source need not be read
        (a virtual camera's picture is the costliest thing a frame computes)."""
        return self.clock() - max(self._last_push, self._last_read) >= 1.0 / self.max_rate

    def update(self, src: Any, pts: Any) -> bool:
        """Send the image if it changed (at most ``max_rate`` a second); True if sent."""
        if src is None:
            return False
        now = self.clock()
        if now - self._last_push < 1.0 / self.max_rate:
            return False
        self._last_read = now
        a = np.asarray(src)
        p = None if pts is None else np.asarray(pts, dtype=float)
        same_src = self._last_src is not None and self._last_src.shape == a.shape and np.array_equal(self._last_src, a)
        same_pts = (p is None and self._last_pts is None) or (
            p is not None and self._last_pts is not None and p.shape == self._last_pts.shape and np.array_equal(p, self._last_pts)
        )
        if same_src and same_pts:
            return False
        out = prepare_image(a, p)
        if out is None:
            return False
        self.handle.image = out
        self._last_src = a.copy()
        self._last_pts = None if p is None else p.copy()
        self._last_push = now
        self.pushes += 1
        return True

    def clear(self) -> None:
        """Forget what was sent, so the next frame sends the image again."""
        self._last_src = None
        self._last_pts = None
        self._last_push = 0.0
        self._last_read = -math.inf
