"""Which x a plot needs, and the titles its axes get (issue #24's new-user trial).

A plot whose series each give their own x needs no ``t`` (a data-fitting lab has none);
when a series does draw against the plot's default ``x: t`` and the model has no ``t``,
the error is at the plot with a hint. A phase plot's axes are titled with the variable its
series share (``th1`` and ``[th1]`` are one variable), unit and all, as the browser is sent
them -- never with the plot's default x when no series draws against it.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from ejsgen.errors import SpecErrors
from ejsrl.view._plots import PlotBinding

NO_T = """\
ejs: 1
title: Fitting
model:
  variables:
    t_data: {expr: "np.linspace(0, 10, 11)", unit: s}
    I_data: {expr: "np.exp(-t_data/3)", unit: A}
    t_grid: {expr: "np.linspace(0, 10, 50)", unit: s}
    I_model: {expr: "np.exp(-t_grid/3)", unit: A}
    k: 1.0
view:
"""

PHASE = """\
ejs: 1
title: Phase
model:
  variables:
    t: 0.0
    dt: 0.05
    th1: {value: 1.0, unit: rad}
    w1: {value: 0.0, unit: rad/s}
    E: {value: 1.0, unit: J}
  evolution:
    - ode:
        equations: {th1: w1, w1: -sin(th1)}
view:
"""


def _build(tmp_path: Path, head: str, view: str) -> Path:
    from ejsgen.cli import build

    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(head + view, encoding="utf-8")
    return build(spec, tmp_path / "app")


def _plots(tmp_path: Path, head: str, view: str) -> list:
    from ejsrl.app import load_app

    return [el for el in load_app(_build(tmp_path, head, view)).view if type(el).__name__ == "Plot"]


def _sent_titles(served, plot) -> tuple[str, str]:
    """The axis titles the browser is sent for ``plot`` (as the panel builds its binding)."""
    x_label = getattr(plot.x, "source", "") or "t"
    b = PlotBinding(served.server.gui, plot, x_label=x_label, clock=served.clock)
    axes = b.handle.last_frame["axes"]
    return axes["x"]["title"], axes["y"]["title"]


def test_a_lab_without_t_whose_series_have_their_own_x_builds(tmp_path: Path):
    view = """\
  - plot:
      title: Data and model
      series:
        - {x: t_data, y: I_data, type: scatter, label: measured}
        - {x: t_grid, y: I_model, label: model}
"""
    (plot,) = _plots(tmp_path, NO_T, view)
    assert plot.x is None  # nothing draws against the plot's x: it is not even compiled
    assert plot.x_label == "" and plot.y_label == "A"  # two different x's: no x title; y: the shared unit


def test_a_series_without_x_in_a_lab_without_t_is_an_error_at_the_plot_with_a_hint(tmp_path: Path):
    view = """\
  - plot:
      title: Data
      series:
        - {x: t_data, y: I_data}
        - {y: k}
"""
    with pytest.raises(SpecErrors) as info:
        _build(tmp_path, NO_T, view)
    (err,) = [str(e).replace(f"{tmp_path}/", "") for e in info.value.errors]
    line = len(NO_T.splitlines()) + 1
    assert err.startswith(f"lab.ejs.yaml:{line}:5: error: "), err  # the plot's own line, not 1:1
    assert "no variable t" in err and "series 2 has no x of its own" in err
    assert "give the plot an x, or each series its own x" in err


def test_a_histogram_alone_needs_no_t(tmp_path: Path):
    (plot,) = _plots(tmp_path, NO_T, "  - plot: {series: [{x: I_data, type: histogram}]}\n")
    assert plot.x is None and plot.x_label == "I_data (A)" and plot.y_label == "count"


def test_a_phase_plot_and_its_current_point_title_their_axes_with_the_shared_variables(tmp_path: Path, served):
    view = """\
  - plot:
      title: Phase plane
      series:
        - {x: th1, y: w1, label: orbit}
        - {x: "[th1]", y: "[w1]", type: scatter, label: now}
  - plot:
      title: Different x
      series:
        - {x: th1, y: w1}
        - {x: w1, y: th1}
  - plot: {title: Energy, series: [{y: E}]}
"""
    phase, different, energy = _plots(tmp_path, PHASE, view)
    assert _sent_titles(served, phase) == ("th1 (rad)", "w1 (rad/s)")
    assert _sent_titles(served, different) == ("", "")  # the x's differ and so do the units: no titles, and not "t"
    assert _sent_titles(served, energy) == ("t (s)", "J")
