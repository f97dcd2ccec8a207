"""A quantity that is exactly zero for a whole window (the servoing lab's |v| once the arm
holds still) is drawn on a readable axis: a new user's trial saw y ticks "0 0 0 -0 -0",
from a range of +-1e-12 around the zero, which uPlot labels with three decimals at most.
"""

from __future__ import annotations

from ejsrl.view._plots import PlotBinding
from ejsrl.view.elements import Dynamic, Plot, Series


def test_an_exact_zero_gets_a_y_axis_whose_ticks_differ(served):
    plot = Plot("p", Dynamic(lambda m: m.t, "t"), [Series(Dynamic(lambda m: 0.0, "v"), "|v|")], window=10.0)
    b = PlotBinding(served.server.gui, plot, x_label="t", clock=served.clock)
    for i in range(101):
        b.append(i * 0.1, [0.0])
        b.push(force=True)
    y = b.handle.scales["y"]
    assert y.get("auto") is False
    lo, hi = y["range"]
    assert lo < 0.0 < hi and (lo + hi) / 2 == 0.0  # the line in the middle
    # five ticks over the range, labelled with at most three decimals, must read differently
    labels = [f"{lo + k * (hi - lo) / 4:.3f}" for k in range(5)]
    assert len(set(labels)) == 5, labels
