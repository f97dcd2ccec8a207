"""The panel's text and layout, at the server (issue #10, items 1 and 13).

Labels keep their spaces and show values as text; the About panel is open, docked at the
left; the panel is docked right at the width the spec asks for (or wide enough for its
title); plots have axis titles and a line of current values; the first 3D view frames
the scene. The browser tests (tests/browser/test_ui_polish*.py) check the same on screen.
"""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.view._gui import PANEL_WIDTH, panel_width_for
from ejsrl.view._framing import VIEW_ASPECT, VIEW_FOV, framing_view, scene_bounds
from ejsrl.view.elements import Dynamic, Label
from ejsrl.world.scene import Box, Grid, Line, Sphere, World


class Recorded:
    """A view built on a server whose every message is recorded from the start."""

    def __init__(self, **sim) -> None:
        from ejsrl.view.viser_view import ViserView, make_server
        from testkit.view_lab import make_app

        self.app = make_app(**sim)
        self.server, _url = make_server("127.0.0.1", 0)
        self.sent: list = []
        queue = self.server._websock_server.queue_message

        def record(message):
            self.sent.append(message)
            return queue(message)

        self.server._websock_server.queue_message = record
        self.view = ViserView(self.app, self.server)


@pytest.fixture
def recorded(request):
    r = Recorded(**(getattr(request, "param", {}) or {}))
    yield r
    r.server.stop()


def placements(rec, kind: str, *, about: bool = False) -> list:
    about_id = rec.view.panel.about._impl.uuid
    return [m for m in rec.sent if type(m).__name__ == kind and (m.uuid == about_id) == about]


def test_about_is_open_in_its_own_panel_docked_left(recorded) -> None:
    panel = recorded.view.panel
    assert "A **test** lab." in panel.about_text.content and "*Author: Tester*" in panel.about_text.content
    docks = [m.position for m in placements(recorded, "GuiSetPanelPositionMessage", about=True)]
    assert docks == [{"kind": "edge", "edge": "left"}]
    assert not [m for m in placements(recorded, "GuiSetPanelCollapsedMessage", about=True) if m.collapsed]


def test_the_panel_is_docked_right_and_wide_enough(recorded) -> None:
    assert [m.width for m in placements(recorded, "GuiSetPanelWidthMessage")] == [PANEL_WIDTH]
    assert [m.position for m in placements(recorded, "GuiSetPanelPositionMessage")] == [{"kind": "edge", "edge": "right"}]


@pytest.mark.parametrize("recorded", [{"panel_width": 555}], indirect=True)
def test_the_spec_s_panel_width_is_applied(recorded) -> None:
    assert [m.width for m in placements(recorded, "GuiSetPanelWidthMessage")] == [555]


def test_a_long_title_widens_the_panel() -> None:
    assert panel_width_for("Pendulum") == PANEL_WIDTH
    long = "Multi-robot system with an eye-in-hand camera and a very long name"
    assert panel_width_for(long) > PANEL_WIDTH + 100


def test_label_spaces_and_indents_survive_the_markdown_renderer(served) -> None:
    panel = served.view.panel
    app = served.app
    label = Label(Dynamic(lambda m: f"    x = {m.x:.1f}   t = {m.t:.1f}", "spaced"))
    handle = panel.gui.add_markdown("")
    panel.labels.append((label, handle))
    with app.lock:
        panel.refresh()
    assert handle.content == "&nbsp;&nbsp;&nbsp;&nbsp;x = 0.0 &nbsp;&nbsp;t = 0.0"


def test_plots_have_axis_titles_and_a_line_of_current_values(served) -> None:
    plot = served.view.panel.plots[0]
    assert plot.handle.last_frame["axes"]["x"]["title"] == "t"  # the x expression (this hand-written lab declares no units)
    app = served.app
    with app.lock:
        app.model.L = 1.5
        app.model.t = 0.25
        app.model.x = -0.125
        served.view.on_frame()
    text = plot.values.content
    assert "&nbsp;x = \u22120.1250" in text and "&nbsp;L = 1.500" in text and "at t = 0.2500" in text
    assert "color:rgb(255, 0, 0)" in text  # the series' own colour


def _world() -> World:
    w = World()
    w.add(Grid("floor", size=2.0, cell=0.1))
    T = np.eye(4)
    T[:3, 3] = (0.5, 0.0, 1.0)
    w.add(Sphere("bob", radius=0.1, T_parent_local=T))
    w.add(Line("rod", points=np.array([[0.0, 0.0, 1.5], [0.5, 0.0, 1.0]])))
    w.add(Box("hidden", size=(10.0, 10.0, 10.0), visible=False))
    return w


def test_scene_bounds_count_what_is_shown() -> None:
    content, floor = scene_bounds(_world())
    assert np.allclose(content[0], [0.0, -0.1, 0.9], atol=0.02) and np.allclose(content[1], [0.6, 0.1, 1.5], atol=0.02)
    assert np.allclose(floor[0], [-1.0, -1.0, 0.0]) and np.allclose(floor[1], [1.0, 1.0, 0.0])


@pytest.mark.parametrize("seed", range(5))
def test_the_framing_camera_sees_every_point_and_no_more_than_needed(seed: int) -> None:
    """Checked with an independent pinhole projection (look-at basis, z up)."""
    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(30, 3)) * rng.uniform(0.1, 5.0, size=3) + rng.normal(size=3) * 3
    eye, target = framing_view(pts)
    f = (target - eye) / np.linalg.norm(target - eye)
    r = np.cross(f, [0, 0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    rel = pts - eye
    depth = rel @ f
    assert np.all(depth > 0)
    tan_v = np.tan(VIEW_FOV / 2)
    ndc = np.column_stack(((rel @ r) / depth / (tan_v * VIEW_ASPECT), (rel @ u) / depth / tan_v))
    assert np.all(np.abs(ndc) <= 1.0)
    assert np.abs(ndc).max() > 0.9  # tight: some point is near the edge
