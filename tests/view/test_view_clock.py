"""The view's timers run on the app's clock: a gizmo drag's hold and the plots' rate
follow the clock a test advances, not the wall clock."""

from __future__ import annotations

import numpy as np
import pytest


def _drag(served, name: str, x: float, phase: str) -> None:
    gizmo = served.view.scene._nodes[name].frame
    gizmo._impl.position = np.array([x, 0.0, 0.0])
    gizmo._impl.wxyz = np.array([1.0, 0.0, 0.0, 0.0])

    class Event:
        pass

    Event.phase = phase
    for cb in gizmo._impl_aux.update_cb:
        cb(Event())


def test_the_view_uses_the_apps_clock(served):
    assert served.view.panel.clock is served.clock
    assert served.view.scene.clock is served.clock
    assert all(p.clock is served.clock for p in served.view.panel.plots)


def test_a_dragged_gizmo_is_left_to_the_user_for_a_second_after_its_last_move(served):
    gizmo = served.view.scene._nodes["handle"].frame
    _drag(served, "handle", 0.5, "update")
    assert served.app.model.k == pytest.approx(2.5)
    served.clock.advance(0.99)
    served.app.frame()
    assert gizmo.position == pytest.approx((0.5, 0.0, 0.0))  # still the user's
    served.clock.advance(0.02)
    served.app.frame()
    assert gizmo.position == pytest.approx((0.0, 0.0, 0.0))  # the server's pose again


def test_a_gizmo_whose_drag_ended_is_released_after_0_3_s(served):
    gizmo = served.view.scene._nodes["handle"].frame
    _drag(served, "handle", 0.5, "end")
    served.clock.advance(0.29)
    served.app.frame()
    assert gizmo.position == pytest.approx((0.5, 0.0, 0.0))
    served.clock.advance(0.02)
    served.app.frame()
    assert gizmo.position == pytest.approx((0.0, 0.0, 0.0))


def test_plots_push_at_most_15_times_a_clock_second_while_playing(served):
    served.app.play()
    plot = served.view.panel.plots[0]
    served.app.frame()
    before = len(served.messages("GuiUpdateMessage"))

    def pushes() -> int:
        return len([m for m in served.messages("GuiUpdateMessage")[before:] if m.uuid == plot.handle.frame._impl.uuid])

    for _ in range(10):
        served.app.frame()  # no time passes on the clock
    assert pushes() == 0
    served.clock.advance(1.0 / 15 + 1e-6)
    served.app.frame()
    assert pushes() == 1
