"""Plots and images in the control panel.

A :class:`PlotBinding` shows one ``Plot`` on a 2D panel (:class:`ejsrl.view._panel2d.Panel2D`,
the engine that also draws drawing panels). Each display frame :meth:`PlotBinding.update`
reads the plot's expressions and files the values by their shapes:

- series without an ``x`` of their own whose values are numbers, with the plot's ``x`` a
  number: one point each in the strip chart's :class:`~ejsrl.view._plot_buffers.PlotBuffer`
  (trimmed to ``window`` and ``max_points``);
- a series with an ``x`` of its own, both numbers: its own x-y history
  (:class:`~ejsrl.view._plot_buffers.TraceBuffer`, ``max_points`` long): a phase orbit;
- x and y 1-D arrays of one length: a curve drawn as it is now (redrawn every frame);
- a histogram: the values of its ``x`` (a number's history, or an array) counted in bins.

Any other combination (an array against a number, arrays of different lengths, a 2-D
array, text) pauses the app with a message at the series' spec location: a plot never
shows nothing without saying why. At most ``max_rate`` times a second (every frame while
paused) the binding builds the panel's frame (:func:`ejsrl.view._plot_frame.plot_frame`:
ranges, ticks and their labels, legend) and sends it if it changed. Below the plot a line
shows each history series' colour, label and latest value.

:class:`ImageBinding` (in :mod:`ejsrl.view._image`, re-exported here) sends an image only when its
pixels or its overlay points changed, once the page has laid its panel out.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ejsrl.view._image import IMAGE_RATE, IMAGE_SETTLE, ImageBinding, prepare_image  # noqa: F401 - re-exported: images have their own module
from ejsrl.view._plot_buffers import PlotBuffer, TraceBuffer
from ejsrl.view._plot_frame import PLOT_AREA_PX, AxisConf, Layer, flat_range, min_span, plot_frame, x_range
from ejsrl.view._ticks import readout_text
from ejsrl.view._wire import set_markdown
from ejsrl.view.elements import Plot, escape_markdown
from ejsrl.world.colors import to_rgb

__all__ = [
    "PlotBuffer",
    "TraceBuffer",
    "PlotBinding",
    "PlotShapeError",
    "ImageBinding",
    "prepare_image",
    "PALETTE",
    "x_range",
    "min_span",
    "flat_range",
    "DEFAULT_HEIGHT",
]

#: colours of series that name none (matplotlib's tab10)
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf")

#: a plot's height (CSS pixels) when neither the spec nor the panel says
DEFAULT_HEIGHT = 240


class PlotShapeError(ValueError):
    """A series' values cannot be drawn (an array against a number, lengths that differ, ...)."""


def _css(color: Any, i: int) -> str:
    if color is None:
        return PALETTE[i % len(PALETTE)]
    try:
        r, g, b = (int(round(255 * c)) for c in to_rgb(color))
    except Exception:
        return PALETTE[i % len(PALETTE)]
    return f"rgb({r}, {g}, {b})"


#: how many of the latest values a readout looks at for its digits
READOUT_RECENT = 20


def _value_text(v: float, recent: Any = None, axis: dict[str, Any] | None = None) -> str:
    """A value in the line below a plot: with the digits that tell the ``recent`` values
    apart, written as its ``axis`` (of the frame sent) writes its labels
    (:func:`ejsrl.view._ticks.readout_text`)."""
    ticks = [float(t[0]) for t in axis.get("ticks", [])] if axis else None
    tail = None if recent is None else [float(r) for r in np.asarray(recent, dtype=float)[-READOUT_RECENT:]]
    return readout_text(float(v), tail, ticks, bool(axis and axis.get("log")))


def _numbers(value: Any, what: str) -> np.ndarray:
    """``value`` as a float array (0-D for a number), or :class:`PlotShapeError` saying why not."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        shown = repr(value)
        raise PlotShapeError(f"{what} must be a number or a 1-D array of numbers, not {shown[:60]}") from None
    if a.ndim > 1:
        raise PlotShapeError(f"{what} must be a number or a 1-D array, but it has shape {a.shape}")
    return a


def _described(a: np.ndarray) -> str:
    return "a number" if a.ndim == 0 else f"an array of {len(a)} values"


class PlotBinding:
    """One ``Plot`` element shown on a 2D panel, with a line of current values below.

    ``gui``: where to add it (viser's ``server.gui`` or a tab's ``client.gui``);
    ``x_label``: the x axis' title when the plot has none (``plot.x_label``); ``title`` /
    ``labels``: the title and series labels as shown now (they may hold ``{expr}``:
    :meth:`set_title` and :meth:`set_label` change them); ``max_rate``: frames a second
    at most while playing; ``height``: CSS pixels (default: ``plot.height``, else
    :data:`DEFAULT_HEIGHT`); ``key``: the panel's name, unique in ``gui``.
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
        key: str = "plot",
    ) -> None:
        from ejsrl.view._panel2d import Panel2D

        self.plot = plot
        self.max_rate = max_rate
        self.clock = clock
        series = plot.series
        #: the strip chart of the series without an x of their own (those whose values are numbers)
        self.buffer = PlotBuffer(len(series), window=plot.window, max_points=plot.max_points)
        #: series index -> its own history (an x-y series, or a histogram of a number)
        self.traces: dict[int, TraceBuffer] = {}
        #: series index -> (N, 2) points of an array series, or (N,) values of a histogram, as now
        self.arrays: dict[int, np.ndarray] = {}
        #: which series draw from the strip chart (set by the values of the last frame)
        self._strip: list[int] = [i for i, s in enumerate(series) if s.x is None and s.kind != "histogram"]
        self._arrays_rev = 0
        self._sent_rev = -1
        self._last_push = -math.inf
        self.title = str(plot.title) if title is None else title
        self.labels = [str(s.label) for s in series] if labels is None else list(labels)
        self.x_name = x_label or "x"
        self.colors = [_css(s.color, i) for i, s in enumerate(series)]
        # the plot's x names the axis only when a series draws against it (not a phase plot's
        # series that each have an x of their own: their title, if any, is plot.x_label)
        uses_x = any(s.x is None and s.kind != "histogram" for s in series)
        self.x_axis = AxisConf(plot.x_label or (self.x_name if uses_x else ""), bool(plot.x_log), plot.x_range)
        self.y_axis = AxisConf(plot.y_label or "", bool(plot.y_log), plot.y_range)
        #: the last frame built (a dict of the 2D panel's contract), None before the first
        self.frame: dict[str, Any] | None = None
        self.height = int(height or plot.height or DEFAULT_HEIGHT)
        self.handle = Panel2D(gui, key, height=self.height, max_rate=math.inf, clock=clock)  # rate-limited here
        self.values = gui.add_markdown("")
        self.push(force=True)

    # -- values of the model --------------------------------------------------------------------
    @property
    def rev(self) -> int:
        """Changes whenever what the plot shows may have changed."""
        return self.buffer.rev + sum(t.rev for t in self.traces.values()) + self._arrays_rev

    def _trace(self, i: int) -> TraceBuffer:
        t = self.traces.get(i)
        if t is None:
            s = self.plot.series[i]
            t = self.traces[i] = TraceBuffer(s.max_points or self.plot.max_points)
        return t

    def _set_array(self, i: int, a: np.ndarray) -> None:
        old = self.arrays.get(i)
        if old is None or old.shape != a.shape or not np.array_equal(old, a, equal_nan=True):
            self.arrays[i] = a.copy()
            self._arrays_rev += 1

    def take(self, x: Any, values: list[tuple[Any, Any]], clock: float | None = None) -> None:
        """File one frame's values: ``x`` the plot's x, ``values[i]`` series i's ``(x, y)``
        (its own x or None, its y or None); ``clock``: the model's time (None: it has none).

        Raises :class:`PlotShapeError` (naming the series) for values that cannot be drawn;
        the values of the other series are filed first.
        """
        plot = self.plot
        problem: PlotShapeError | None = None
        px = _numbers(x, "the plot's x") if any(s.x is None and s.kind != "histogram" for s in plot.series) else None
        strip: list[int] = []
        ys: list[float] = []
        for i, (s, (sx, sy)) in enumerate(zip(plot.series, values)):
            name = f"series {i + 1} ({self.labels[i] or s.kind})"
            try:
                if s.kind == "histogram":
                    v = _numbers(sx, "its x")
                    if v.ndim == 0:
                        self._trace(i).append(float(v), 0.0, clock)
                        self.arrays.pop(i, None)
                    else:
                        self._set_array(i, v)
                    continue
                xv = px if s.x is None else _numbers(sx, "its x")
                yv = _numbers(sy, "its y")
                assert xv is not None
                if xv.ndim == 0 and yv.ndim == 0:
                    if s.x is None:
                        strip.append(i)
                        ys.append(float(yv))
                    else:
                        self._trace(i).append(float(xv), float(yv), clock)
                    continue
                if xv.ndim == 1 and yv.ndim == 1 and len(xv) == len(yv):
                    self._set_array(i, np.column_stack((xv, yv)))
                    continue
                x_what = "the plot's x" if s.x is None else "its x"
                if xv.ndim == 1 and yv.ndim == 1:
                    raise PlotShapeError(f"{x_what} and y must have as many values, but {x_what} has {len(xv)} and y has {len(yv)}")
                hint = " (give the series an x of its own with as many values)" if s.x is None and yv.ndim == 1 else ""
                raise PlotShapeError(f"y is {_described(yv)} but {x_what} is {_described(xv)}{hint}; give both as numbers (a history) or both as arrays of one length (a curve)")
            except PlotShapeError as exc:
                if problem is None:
                    problem = PlotShapeError(f"{name}: {exc}")
                    problem.where = s.where or plot.where  # type: ignore[attr-defined]
        self._strip = strip
        if strip and px is not None:
            row = [float("nan")] * len(plot.series)
            for i, y in zip(strip, ys):
                row[i] = y
            self.buffer.append(float(px), [row[i] if i in strip else 0.0 for i in range(len(plot.series))], clock)
        if problem is not None:
            raise problem

    def update(self, app: Any, *, playing: bool, now: float | None = None) -> None:
        """Read this frame's values from ``app``'s model (the caller holds ``app.lock``) and
        push; a shape that cannot be drawn pauses the app with its message. ``now``: the
        panel's clock for this frame, the same for each of its plots (so they are sent in
        the same frames and their readouts agree)."""
        self.record(app)
        self.push(force=not playing, now=now)

    def record(self, app: Any) -> None:
        """Read and file this frame's values without sending anything (a tab that is behind)."""
        plot = self.plot
        needs_x = any(s.x is None and s.kind != "histogram" for s in plot.series)
        x = app.safe_value(plot.x, plot.where) if needs_x else None
        values = []
        for s in plot.series:
            where = s.where or plot.where
            sx = app.safe_value(s.x, where) if s.x is not None else None
            sy = app.safe_value(s.y, where) if s.y is not None else None
            values.append((sx, sy))
        if getattr(app, "error", None) is not None:
            return
        if (needs_x and x is None) or any((s.x is not None and sx is None) or (s.y is not None and sy is None) for s, (sx, sy) in zip(plot.series, values)):
            return
        model = getattr(app, "model", None)
        clock = None
        if model is not None and getattr(model, "INDEPENDENT", None) is not None:
            try:
                clock = float(model._ejs_time())
            except (TypeError, ValueError, AttributeError):
                clock = None
        try:
            self.take(x, values, clock)
        except PlotShapeError as exc:
            from ejsrl.sim.model import UserCodeError

            title = f" '{self.title}'" if self.title else ""
            sep = " " if str(exc).startswith("series") else ": "
            app.fail(UserCodeError(f"the plot{title} cannot draw{sep}{exc}", getattr(exc, "where", plot.where)))

    def append(self, x: Any, ys: list[Any], clock: float | None = None) -> None:
        """Record one point of the strip chart (x and one number per series; tests, scripted input).

        Non-numeric values skip the frame."""
        try:
            xf = float(x)
            yf = [float(y) for y in ys]
        except (TypeError, ValueError):
            return
        self.buffer.append(xf, yf, clock)

    # -- the frame ------------------------------------------------------------------------------
    def layers(self) -> tuple[list[Layer], tuple[float, float] | None]:
        """What each series draws now, and the strip chart's x range (None: not a strip chart)."""
        plot = self.plot
        data = self.buffer.data() if len(self.buffer) else None
        out: list[Layer] = []
        for i, s in enumerate(plot.series):
            layer = Layer(s.kind, self.labels[i], self.colors[i], width=s.width, marker=s.marker, size=s.size)
            if s.kind == "histogram":
                from ejsrl.view._plot_frame import histogram

                vals = self.arrays.get(i)
                if vals is None:
                    vals = self.traces[i].data()[:, 0] if i in self.traces else np.zeros(0)
                layer.counts, layer.edges = histogram(vals, s.bins, s.bin_range)
            elif i in self.arrays:
                layer.xy = self.arrays[i]
            elif i in self.traces:
                layer.xy = self.traces[i].data()
            elif i in self._strip and data is not None:
                layer.xy = np.column_stack((data[0], data[i + 1]))
            out.append(layer)
        strip_only = bool(self._strip) and len(self._strip) == len(plot.series)
        x_auto = x_range(data[0] if data is not None else np.zeros(0), plot.window) if strip_only and not self.buffer.turns else None
        return out, x_auto

    def build(self) -> dict[str, Any]:
        """The frame of the plot as it is now (:func:`ejsrl.view._plot_frame.plot_frame`)."""
        layers, x_auto = self.layers()
        legend = self.plot.legend if self.plot.legend is not None else len(self.plot.series) >= 2
        previous = tuple(self.frame["bounds"]) if self.frame is not None else None
        area = (PLOT_AREA_PX[0], max(40.0, self.height - 60.0))  # the panel's title and x axis take about 60 px of the height
        return plot_frame(self.title, layers, self.x_axis, self.y_axis, x_auto=x_auto, legend=legend, grid=self.plot.grid, previous=previous, area_px=area)

    def push(self, *, force: bool = False, now: float | None = None) -> bool:
        """Build and send the frame if anything changed and the rate allows; True if sent.

        The rate allows one frame in each 1/``max_rate`` s slot of the clock (slots counted
        from 0, not from this plot's last push): plots updated with one ``now`` are sent in
        the same frames, never one a frame behind another."""
        now = self.clock() if now is None else now
        rev = self.rev
        if rev == self._sent_rev:
            return False
        if not force and math.isfinite(self.max_rate) and math.isfinite(self._last_push):
            if math.floor(now * self.max_rate) == math.floor(self._last_push * self.max_rate):
                return False
        self.frame = self.build()
        self.handle.show(self.frame)
        text = self._values_text()
        if text != self.values.content:
            set_markdown(self.values, text)
        self._sent_rev = rev
        self._last_push = now
        return True

    def _values_text(self) -> str:
        """The line below the plot: colour, label and latest value of each history series
        (the x and y of an x-y series), then the strip chart's x."""
        parts = []
        data = self.buffer.data() if len(self.buffer) else None
        axes = self.frame["axes"] if self.frame is not None else {}
        ax_x, ax_y = axes.get("x"), axes.get("y")
        for i, s in enumerate(self.plot.series):
            name = escape_markdown(self.labels[i] or f"y{i + 1}")
            swatch = f'<span style="color:{self.colors[i]}">&#9632;</span>&nbsp;{name}'
            if i in self._strip:
                value = f" = {_value_text(data[i + 1][-1], data[i + 1], ax_y)}" if data is not None else ""
            elif s.kind != "histogram" and i in self.traces and len(self.traces[i]) and i not in self.arrays:
                xy = self.traces[i].data()
                value = f" = {_value_text(xy[-1, 1], xy[:, 1], ax_y)} at {_value_text(xy[-1, 0], xy[:, 0], ax_x)}"
            else:
                continue
            parts.append(swatch + value)
        if not parts:
            return ""
        x = f" &nbsp;at {escape_markdown(self.x_name)} = {_value_text(data[0][-1], data[0], ax_x)}" if data is not None and self._strip else ""
        return " &nbsp; ".join(parts) + x

    # -- titles, reset, tabs ----------------------------------------------------------------------
    def set_title(self, text: str) -> None:
        """Show a new title (a title with ``{expr}`` whose value changed)."""
        self.title = text
        self._sent_rev = -1
        self.push(force=True)

    def set_label(self, index: int, text: str) -> None:
        """Show a new label for series ``index`` (0-based)."""
        self.labels[index] = text
        self._sent_rev = -1
        self.push(force=True)

    def clear(self) -> None:
        """Forget the data (on reset) and show the empty plot."""
        self.buffer.clear()
        for t in self.traces.values():
            t.clear()
        self.arrays.clear()
        self._arrays_rev += 1
        self.frame = None
        self.push(force=True)

    def adopt(self, old: PlotBinding) -> None:
        """Take over the points of ``old`` (the same plot in a reloaded tab) and show them."""
        self.buffer = old.buffer
        self.traces = old.traces
        self.arrays = old.arrays
        self._strip = old._strip
        self.reshow()

    def reshow(self) -> None:
        """Send the frame again with the next :meth:`push` (its data was handed over)."""
        self._sent_rev = -1
