"""The line of values below a plot (issue #24's new-user trial).

Each value is read back from the text the browser is sent and compared with the model's
value, computed here independently: it has the digits that tell the last frames' values
apart (3e8 + 12 sin t is not "3e+08"), it is written as its axis writes its labels (the
same power of ten: "-0.8801e-5" beside "0.5e-5"), it never reads "-0", and the plots of
one panel show the same frame (the first one was a frame behind the others).
"""

from __future__ import annotations

import math
import re

import pytest

from ejsrl.app import App, AppMeta, SimConfig
from ejsrl.view._plots import PlotBinding
from ejsrl.view._ticks import MINUS
from ejsrl.view.elements import Dynamic, Plot, Series
from ejsrl.view.viser_view import ViserView, make_server
from testkit.view_lab import SPEC, LabModel

DT = 0.2


def _number(text: str) -> float:
    return float(text.replace(MINUS, "-"))


def _readout(b: PlotBinding) -> tuple[str, str]:
    """``(value, x)``: the texts of the first series' value and of the strip chart's x."""
    m = re.search(r"= (\S+) &nbsp;at \S+ = (\S+)$", b.values.content)
    assert m, b.values.content
    return m.group(1), m.group(2)


def _strip(served, f, n_frames: int = 243) -> tuple[PlotBinding, list[tuple[float, str, str]]]:
    """A strip chart of f(t), one frame every DT s up to t = 48.4 s; (true value, readout, x readout) per frame."""
    b = PlotBinding(served.server.gui, Plot("p", Dynamic(lambda m: m.t, "t"), [Series(Dynamic(lambda m: 0.0, "y"), "y")]), x_label="t", clock=served.clock)
    out = []
    for i in range(n_frames):
        t = round(i * DT, 10)
        b.append(t, [f(t)])
        b.push(force=True)
        value, x = _readout(b)
        out.append((f(t), value, x))
    return b, out


def _axis_labels(b: PlotBinding, axis: str) -> list[str]:
    return [label for _v, label in b.handle.last_frame["axes"][axis]["ticks"]]


def test_a_large_value_that_varies_a_little_shows_its_variation(served):
    b, frames = _strip(served, lambda t: 3e8 + 12 * math.sin(t))
    for true, text, _x in frames[-30:]:
        assert abs(_number(text) - true) <= 1.0, (true, text)  # it was "3e+08": 12 units of variation lost
    assert len({text for _true, text, _x in frames[-30:]}) >= 20  # the readout changes as the value does (24 integers of 3e8 + 12 sin t)
    exponent = _axis_labels(b, "y")[-1].split("e")[1]
    assert all(text.endswith("e" + exponent) for _true, text, _x in frames[-30:])  # in the axis' notation


def test_a_small_value_is_written_as_its_axis_writes_its_labels(served):
    b, frames = _strip(served, lambda t: 1e-5 * math.sin(t))
    labels = _axis_labels(b, "y")
    assert "0.5e\u22125" in labels  # the axis: every label in units of 1e-5
    true, text, x = frames[-1]
    assert text.endswith("e\u22125") and "e\u221206" not in text, text  # not "-8.801e-06"
    assert abs(_number(text) - true) <= 1e-9, (true, text)
    assert x == "48.40"  # t's frames are 0.2 s apart: two decimals, as before


def test_a_readout_never_reads_minus_zero(served):
    # a swing through zero whose last value is round-off below it: "0", not "-0.000"
    _b, frames = _strip(served, lambda t: -1e-17 if t >= 3.0 else math.cos(t), n_frames=16)
    assert all(not (text.startswith(MINUS) and _number(text) == 0.0) for _true, text, _x in frames), [text for _t, text, _x in frames]
    assert frames[-1][1] == "0"
    # round-off alone is shown as what it is, on an axis of its size (not as -0)
    _b, frames = _strip(served, lambda t: -1e-17 if int(round(t / DT)) % 2 else 0.0, n_frames=20)
    assert all(not (text.startswith(MINUS) and _number(text) == 0.0) for _true, text, _x in frames)


class _TickingClock:
    """A clock that moves ``tick`` s every time it is read (building a panel, reading the model take time)."""

    def __init__(self) -> None:
        self.now = 1000.0
        self.tick = 0.02

    def __call__(self) -> float:
        self.now += self.tick
        return self.now

    def advance(self, dt: float) -> None:
        self.now += dt


def test_the_plots_of_a_panel_show_the_same_frame():
    clock = _TickingClock()
    plots = [Plot(f"p{k}", Dynamic(lambda m: m.t, "t"), [Series(Dynamic(lambda m, k=k: m.x * k, "x"), f"y{k}")]) for k in range(1, 6)]
    app = App(LabModel, plots, clock=clock, sim=SimConfig(fps=30.0), meta=AppMeta(title="Plots", description="", author="Tests", spec=SPEC))
    server, _url = make_server("127.0.0.1", 0)
    try:
        view = ViserView(app, server)  # each plot built some 20-40 ms after the one before
        app.views.append(view)
        clock.tick = 0.0005  # then a frame reads the clock every half millisecond
        app.play()
        behind = 0
        for _ in range(150):
            clock.advance(1 / 30)
            app.frame()
            xs = {b.values.content.rpartition("= ")[2] for b in view.panel.plots}  # the x each shows (or no value yet)
            behind += len(xs) > 1
        assert behind == 0, f"in {behind} of 150 frames the plots' readouts were at different t"
        assert _number(_readout(view.panel.plots[0])[1]) > 1.0  # it played
    finally:
        server.stop()
