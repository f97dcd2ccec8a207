"""Round-off about zero never shows as "-0" (issue #24's new-user trial: the six-axis lab's
q4 box read "-0.0" and its T06 label "-0.000" after an inverse-kinematics move)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ejsrl.view.elements import escaped, format_value


@pytest.mark.parametrize(
    ("value", "spec", "expected"),
    [
        (-1e-17, "+.3f", "+0.000"),
        (-1e-17, ".3f", "0.000"),
        (-0.0, "", "0.0"),
        (-0.0, ".1f", "0.0"),
        (-4e-7, "8.3f", "   0.000"),
        (-1e-9, ".2%", "0.00%"),
        (np.float64(-1e-12), ".2f", "0.00"),
        # real negatives keep their sign
        (-0.0005, ".3f", "-0.001"),
        (-1e-9, ".2e", "-1.00e-09"),
        (-1e-9, "g", "-1e-09"),
        (-3, "d", "-3"),
    ],
)
def test_a_formatted_number_never_reads_minus_zero(value, spec, expected):
    assert format_value(value, spec) == expected


def test_the_six_axis_tool_pose_reads_plus_zero_where_round_off_left_minus_zero():
    # T06 after an inverse-kinematics move: rotation entries at +-1e-17 instead of 0
    T = np.array([[-1.0, 1e-17, -2e-17, 0.35], [-3e-17, 1.0, -1e-16, 0.35], [-1e-17, -0.0, -1.0, 0.3], [0.0, 0.0, 0.0, 1.0]])
    text = format_value(T, "+.3f")
    assert "-0.000" not in text
    assert text.splitlines()[0] == "[-1.000 +0.000 +0.000 +0.350]"
    assert "-0.000" not in escaped(T, "+.3f").replace("&#45;", "-")


def test_a_slider_box_shows_zero_not_minus_zero(served):
    app, panel = served.app, served.view.panel
    q1 = panel.handles_by_label["q1"]  # min -1, max 1, step 0.01: the box shows two decimals
    for value in (-1e-9, -0.0, -0.004):
        with app.lock:
            app.model.q[1] = 0.5
            panel.refresh()
            app.model.q[1] = value
            panel.refresh()
        shown = q1.value
        assert shown == 0.0 and math.copysign(1.0, shown) == 1.0, (value, shown)
    with app.lock:
        app.model.q[1] = -0.006  # rounds to -0.01 in the box: a real negative value, kept
        panel.refresh()
    assert q1.value == pytest.approx(-0.006)
