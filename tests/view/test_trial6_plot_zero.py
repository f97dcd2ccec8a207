"""A quantity that is exactly zero for a whole window (the servoing lab's |v| once the arm
holds still) is drawn on a readable axis: a new user's trial saw y ticks "0 0 0 -0 -0",
from a range of +-1e-12 around the zero labelled with three decimals at most.
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
    frame = b.handle.last_frame  # what the browser draws
    lo, hi = frame["bounds"][2:]
    assert lo < 0.0 < hi and (lo + hi) / 2 == 0.0  # the line in the middle
    labels = [label for _value, label in frame["axes"]["y"]["ticks"]]
    assert len(labels) >= 3 and len(set(labels)) == len(labels), labels
    assert not any(label.lstrip("\u2212-").strip("0.") == "" and label.startswith(("\u2212", "-")) for label in labels), labels  # no "-0"
    values = [float(label.replace("\u2212", "-")) for label in labels]
    assert values == sorted(values) and values[0] < 0 < values[-1]
