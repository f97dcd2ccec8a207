"""The plan is data (issue 11, item 3), and the runtime reads ``bind:`` paths itself (item 4).

The plan of an app holds its variables (with unit and doc), its methods (each line with the
spec location it came from), its ODE pages and its view as runtime calls; the runtime's
bind-path reader and writer are checked against plain indexing.
"""

from __future__ import annotations

import numpy as np
import pytest

from ejsgen.cli import load_plan
from ejsgen.plan import Call, Expr, OdePlan
from ejsrl.sim.paths import getter, parse_path, setter
from testkit import EXAMPLES


def test_the_plan_holds_variables_methods_pages_and_view_as_data() -> None:
    plan = load_plan(EXAMPLES / "bouncing_ball.ejs.yaml")
    h0 = next(v for v in plan.var_plans if v.name == "h0")
    assert (h0.unit, h0.doc) == ("m", "height it is dropped from")
    assert h0.init[0].text == "self.h0 = 1.0" and h0.init[0].where.line == 15
    (page,) = plan.pages
    assert isinstance(page, OdePlan)
    assert list(page.rates) == ["y", "vy"] and page.rates["vy"].source == "-self.g"
    assert page.method == "rk4" and page.independent == "t"
    (event,) = page.events
    assert (event.name, event.direction, event.when.source) == ("floor", "down", "self.y")
    action = next(m for m in plan.methods if m.name == event.action)
    assert [(ln.text, ln.where.line) for ln in action.lines] == [
        ("self.vy = -self.restitution*self.vy", 37),
        ("self.bounces = self.bounces + 1", 38),
        ("self.last_impact = self.t", 39),
    ]
    slider = plan.view[1]
    assert isinstance(slider, Call) and slider.fn == "E.Slider" and slider.kwargs["bind"] == "h0"
    plot = next(c for c in plan.view if c.fn == "E.Plot")
    assert plot.kwargs["x"] == Call("E.Dynamic", ["t"])
    ball = next(c for c in plan.calls() if c.fn == "E.Node3D" and c.kwargs["name"] == "ball")
    position = ball.kwargs["position"]
    assert position.fn == "E.Dynamic" and isinstance(position.args[0], Expr) and position.args[0].lam == "self"


class _M:
    def __init__(self) -> None:
        self.L = 1.0
        self.q = np.array([0.0, 1.0, 2.0])
        self.M = np.arange(9.0).reshape(3, 3)
        self.rows = [[1, 2], [3, 4]]


@pytest.mark.parametrize(
    ("path", "read"),
    [("L", lambda m: m.L), ("q[2]", lambda m: m.q[2]), ("q[-1]", lambda m: m.q[-1]), ("M[1, 2]", lambda m: m.M[1, 2]),
     ("M[1][2]", lambda m: m.M[1][2]), ("rows[1][0]", lambda m: m.rows[1][0]), (" q[ 0 ] ", lambda m: m.q[0])],
)
def test_bind_paths_read_and_write_like_indexing(path: str, read) -> None:
    m = _M()
    assert getter(path)(m) == read(m)
    setter(path)(m, 42.0)
    assert read(m) == 42.0


def test_writing_an_element_changes_that_element_in_place() -> None:
    m = _M()
    q = m.q
    setter("q[1]")(m, 7.0)
    assert m.q is q and list(q) == [0.0, 7.0, 2.0]


@pytest.mark.parametrize("bad", ["q[i]", "q[1.5]", "f(x)", "q[1:2]", "a.b", "1x"])
def test_a_path_that_is_not_a_name_or_element_is_refused(bad: str) -> None:
    with pytest.raises(ValueError, match="bind path"):
        parse_path(bad)


def test_a_control_without_get_and_set_reads_and_writes_its_bind() -> None:
    from ejsrl.view.elements import Dynamic, Node3D, Slider

    m = _M()
    s = Slider(bind="q[0]", label="q0", min=-1.0, max=1.0)
    s.set(m, 0.5)
    assert s.get(m) == 0.5 == m.q[0]
    assert Dynamic("M[2, 0]")(m) == 6.0 and Dynamic("M[2, 0]").source == "M[2, 0]"
    pose = Node3D(kind="gizmo", name="g", bind="M")
    assert pose.transform(m) is m.M
    pose.set(m, np.eye(3))
    assert np.array_equal(m.M, np.eye(3))
