"""`initialize()` restarts keeping what the user set from the view; `reset()` forgets it.

Driven through the app as the browser drives it (``apply_control`` for sliders,
``run_action`` for buttons), and checked against closed forms."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ejsrl.app import App, load_app
from ejsrl.view.elements import Button, Control
from testkit import EXAMPLES

G = 9.81

SPEC = """\
ejs: 1
title: Restarts
model:
  variables:
    t: 0.0
    dt: 0.01
    h0: 1.0
    bounce: 0.9
    y: 1.0
    vy: 0.0
    kicks: 0
    q: [0.0, 0.0]
  init: |
    y = h0
    vy = 0.0
  evolution:
    - ode:
        equations:
          y: vy
          vy: -9.81
  custom: |
    def kick():
        kicks = kicks + 1
view:
  - slider: {bind: h0, min: 0.1, max: 3, label: Height, on_change: "initialize()"}
  - slider: {bind: bounce, min: 0, max: 1}
  - slider: {bind: "q[1]", min: -1, max: 1}
  - button: {label: Kick, action: "kick()"}
  - button: {label: Again, action: "initialize()"}
  - button: {label: Reset, action: "reset()"}
"""


def control(app: App, bind: str) -> Control:
    return next(c for c in app.view if isinstance(c, Control) and c.bind == bind)


def button(app: App, label: str) -> Button:
    return next(b for b in app.view if isinstance(b, Button) and b.label == label)


@pytest.fixture(scope="module")
def restarts_dir(tmp_path_factory) -> Path:
    from ejsgen.cli import build

    spec = tmp_path_factory.mktemp("restarts") / "restarts.ejs.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    return build(spec, spec.parent / "app")


def test_initialize_keeps_the_values_set_from_the_view_and_restores_the_rest(restarts_dir) -> None:
    app = load_app(restarts_dir)
    m = app.model
    app.apply_control(control(app, "bounce"), 0.5)
    app.apply_control(control(app, "q[1]"), 0.25)
    app.play()
    for _ in range(30):
        app.step_once()
    app.run_action(button(app, "Kick"))  # a change made by code, not set from the view
    assert m.t > 0.29 and m.kicks == 1
    # moving the height slider restarts from the new height, with the user's other settings
    app.apply_control(control(app, "h0"), 2.0)
    assert app.is_playing()  # a restart, not a pause
    assert (m.t, m.h0, m.y, m.vy, m.kicks) == (0.0, 2.0, 2.0, 0.0, 0)
    assert m.bounce == 0.5 and m.q.tolist() == [0.0, 0.25]
    # and the new height is in effect: it lands at sqrt(2 h / g)
    while m.y > 0.0:
        app.step_once()
    assert m.t == pytest.approx(math.ceil(math.sqrt(2 * 2.0 / G) / m.dt) * m.dt)
    # an initialize() button restarts the same way
    app.run_action(button(app, "Again"))
    assert (m.t, m.y, m.h0, m.bounce) == (0.0, 2.0, 2.0, 0.5)


def test_reset_forgets_the_values_set_from_the_view(restarts_dir) -> None:
    app = load_app(restarts_dir)
    m = app.model
    app.apply_control(control(app, "bounce"), 0.5)
    app.apply_control(control(app, "h0"), 2.0)
    app.play()
    app.run_action(button(app, "Reset"))
    assert not app.is_playing()
    assert (m.h0, m.y, m.bounce) == (1.0, 1.0, 0.9) and m.q.tolist() == [0.0, 0.0]
    # and a later initialize() has nothing of the user's to keep
    app.run_action(button(app, "Again"))
    assert (m.h0, m.y, m.bounce) == (1.0, 1.0, 0.9)


def test_bouncing_ball_drop_height_slider_restarts_from_the_new_height(built) -> None:
    app = load_app(built("bouncing_ball"))
    m = app.model
    app.apply_control(control(app, "restitution"), 0.5)
    app.play()
    for _ in range(80):
        app.step_once()
    assert m.bounces == 1
    app.apply_control(control(app, "h0"), 2.5)
    assert (m.t, m.y, m.bounces) == (0.0, 2.5, 0) and m.restitution == 0.5
    while m.bounces < 2:
        app.step_once()
    # closed form: first impact at sqrt(2 h / g), the second a flight 2 e v1 / g later
    v1 = math.sqrt(2 * G * 2.5)
    assert m.last_impact == pytest.approx(v1 / G + 2 * 0.5 * v1 / G, abs=1e-6)


def test_mass_spring_chain_restart_starts_in_the_chosen_mode(built) -> None:
    app = load_app(built("mass_spring_chain"))
    m = app.model
    app.apply_control(control(app, "mode"), 3)
    for _ in range(40):
        app.step_once()
    app.run_action(button(app, "Restart"))
    assert m.t == 0.0 and m.mode == 3
    n = np.arange(1, m.N + 1)
    np.testing.assert_allclose(m.x, m.amp * np.sin(3 * np.pi * n / (m.N + 1)), rtol=0, atol=1e-15)


def test_pick_and_place_boxes_slider_changes_the_number_of_boxes() -> None:
    from ejsgen.cli import build
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        app = load_app(build(EXAMPLES / "paper" / "pick_and_place.ejs.yaml", Path(tmp) / "pp"))
        m = app.model
        app.play()
        for _ in range(50):
            app.step_once()
        app.apply_control(control(app, "n_objects"), 5)
        assert m.n_objects == 5 and m.t == 0.0 and app.is_playing()
        app.frame()  # what the panel and the scene show
        assert [app.world[f"box{i + 1}"].visible for i in range(6)] == [True] * 5 + [False]
        # the belt brings all five to the pick point, queued one spacing apart
        for _ in range(int(14 / m.dt)):
            app.step_once()
        ys = [app.world[f"box{i + 1}"].T_world()[1, 3] for i in range(5)]
        np.testing.assert_allclose(ys, [m.pick[1] - m.spacing * i for i in range(5)], atol=1e-9)
