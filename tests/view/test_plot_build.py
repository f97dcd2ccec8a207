"""Plot specs at build time: the new keys build into the app's records, and a series that
cannot be drawn is an error at its FILE:LINE:COL (nothing fails silently)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ejsgen.errors import SpecErrors

HEAD = """\
ejs: 1
title: Plots
model:
  variables:
    t: 0.0
    dt: 0.05
    theta: {value: 1.0, unit: rad}
    omega: {value: 0.0, unit: rad/s}
    xs: [0.0, 0.25, 0.5, 0.75, 1.0]
    data: [[0, 1], [1, 2], [2, 3]]
    grid: {expr: "np.linspace(0, 1, 5)"}
  evolution:
    - ode:
        equations: {theta: omega, omega: -sin(theta)}
view:
"""


def _build(tmp_path: Path, view: str) -> Path:
    from ejsgen.cli import build

    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(HEAD + view, encoding="utf-8")
    return build(spec, tmp_path / "app")


def _errors(tmp_path: Path, view: str) -> list[str]:
    with pytest.raises(SpecErrors) as info:
        _build(tmp_path, view)
    return [str(e).replace(f"{tmp_path}/", "") for e in info.value.errors]


def _at(view: str, needle: str, occurrence: int = 0) -> str:
    """``lab.ejs.yaml:LINE:COL`` of ``needle`` in the view (its ``occurrence``-th line holding it)."""
    lines = (HEAD + view).splitlines()
    first = len(HEAD.splitlines()) + 1
    hits = [(i, line.index(needle)) for i, line in enumerate(lines, start=1) if needle in line and i >= first]
    line, col = hits[occurrence]
    return f"lab.ejs.yaml:{line}:{col + 1}"


def test_the_new_keys_build_an_app_whose_plots_draw_them(tmp_path: Path):
    from ejsrl.app import load_app

    view = """\
  - plot:
      title: Phase plane
      x_range: [-2, 2]
      y_log: false
      legend: true
      height: 320
      series:
        - {x: theta, y: omega, label: orbit, max_points: 500}
        - {x: xs, y: "xs**2", label: curve, type: scatter, marker: cross, size: 4}
        - {x: "data[:, 0]", y: "data[:, 1]", label: data}
        - {x: theta, type: histogram, bins: 10, bin_range: [-1, 1], label: spread}
  - plot: {title: Old style, x: t, series: [{y: theta}], window: 5}
"""
    app = load_app(_build(tmp_path, view))
    plot, old = app.view
    assert plot.x_range == (-2.0, 2.0) and plot.legend is True and plot.height == 320
    kinds = [(s.kind, s.marker, s.max_points, s.bins, s.bin_range) for s in plot.series]
    assert kinds == [("line", None, 500, 20, None), ("scatter", "cross", None, 20, None), ("line", None, None, 20, None), ("histogram", None, None, 10, (-1.0, 1.0))]
    assert plot.x_label == ""  # the series have x's of their own, and they differ: no one title fits
    assert old.x_label == "t (s)" and old.series[0].x is None and old.window == 5
    np.testing.assert_allclose(plot.series[2].x(app.model), [0, 1, 2])


def test_one_x_y_series_titles_both_axes_with_their_units(tmp_path: Path):
    from ejsrl.app import load_app

    app = load_app(_build(tmp_path, "  - plot: {title: Phase, series: [{x: theta, y: omega}]}\n"))
    (plot,) = app.view
    assert (plot.x_label, plot.y_label) == ("theta (rad)", "omega (rad/s)")


@pytest.mark.parametrize(
    ("series", "needle", "message"),
    [
        ('{x: xs, y: theta}', "theta}", "series 1 of the plot's y 'theta' is a number but its x 'xs' is an array of 5 values"),
        ('{x: theta, y: xs}', "xs}", "series 1 of the plot's y 'xs' is an array of 5 values but its x 'theta' is a number"),
        ('{x: xs, y: "data[:, 1]"}', '"data', "must have as many values, but its x 'xs' is an array of 5 values and its y 'data[:, 1]' is an array of 3 values"),
        ('{x: "np.linspace(0, 1, 7)", y: "grid*2"}', "np.linspace", None),  # grid's shape is not known: checked when it runs
        ('{x: "data[:, 0]", y: data}', "data}", "needs numbers or 1-D arrays, but its y 'data' is an array of shape (3, 2)"),
        ('{y: xs}', "xs}", "series 1 of the plot's y 'xs' is an array of 5 values but the plot's x 't' is a number; give the series an x of its own with as many values, e.g. x: \"np.arange(len(xs))\""),
    ],
)
def test_a_series_of_the_wrong_shape_is_an_error_at_its_expression(tmp_path: Path, series: str, needle: str, message: str | None):
    view = f"  - plot:\n      title: P\n      series:\n        - {series}\n"
    if message is None:
        _build(tmp_path, view)  # builds: the app checks it every frame
        return
    errors = _errors(tmp_path, view)
    assert len(errors) == 1, errors
    assert errors[0].startswith(_at(view, needle) + ": error: ") and message in errors[0], (errors[0], _at(view, needle))


def test_a_2d_y_hints_at_a_column(tmp_path: Path):
    view = "  - plot:\n      series:\n        - {x: \"data[:, 0]\", y: data}\n"
    (err,) = _errors(tmp_path, view)
    assert "pick one column, e.g. data[:, 1]" in err


@pytest.mark.parametrize(
    ("series", "needle", "message"),
    [
        ("{type: histogram, bins: 5}", "type", "series 1 of the plot is a histogram: it counts the values of its own x"),
        ("{x: theta, y: omega, type: histogram}", "omega", "takes no y"),
        ("{y: theta, bins: 5}", "5}", "'bins' is for a histogram, but series 1 of the plot is a line; add 'type: histogram'"),
        ("{x: theta, label: nothing}", "theta", "series 1 of the plot needs y"),
        ("{x: theta, type: histogram, bin_range: [1, 0]}", "[1, 0]", "bin_range is [lo, hi] with lo < hi"),
    ],
)
def test_series_keys_that_do_not_fit_their_type_are_errors(tmp_path: Path, series: str, needle: str, message: str):
    view = f"  - plot:\n      series:\n        - {series}\n"
    errors = _errors(tmp_path, view)
    assert len(errors) == 1 and message in errors[0], errors
    line = _at(view, needle).rsplit(":", 1)[0]
    assert errors[0].startswith(line + ":"), (errors[0], line)


def test_ranges_and_log_axes_are_checked(tmp_path: Path):
    view = "  - plot:\n      x_range: [2, 1]\n      y_log: true\n      y_range: [0, 10]\n      series: [{y: theta}]\n"
    errors = _errors(tmp_path, view)
    assert any(e.startswith(_at(view, "[2, 1]") + ": error: x_range is [xmin, xmax] with xmin < xmax") for e in errors), errors
    assert any(e.startswith(_at(view, "[0, 10]") + ": error: a logarithmic y axis shows only positive values") and "e.g. [0.01, 10]" in e for e in errors), errors


def test_a_misspelt_series_key_says_what_was_meant(tmp_path: Path):
    view = "  - plot:\n      series:\n        - {x: theta, y: omega, tipe: scatter}\n"
    errors = _errors(tmp_path, view)
    assert len(errors) == 1 and "unknown key 'tipe'; did you mean 'type'?" in errors[0], errors
    assert errors[0].startswith(_at(view, "tipe")), errors
