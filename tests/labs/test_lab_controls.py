"""The labs' panels do what their descriptions promise, driven through the app as the
browser drives it (``apply_control`` for sliders, dropdowns and checkboxes, ``run_action``
for buttons), with the model checked against the same independent references as the
headless runs."""

from __future__ import annotations

import numpy as np
import pytest
from testkit.labs import LABS

from ejsrl.view.elements import Button, Control, Folder, Tabs


def controls(view):
    """Every control and button of a view, inside folders and tabs too."""
    for element in view:
        if isinstance(element, (Control, Button)):
            yield element
        elif isinstance(element, Folder):
            yield from controls(element.children)
        elif isinstance(element, Tabs):
            for _, children in element.tabs:
                yield from controls(children)


def control(app, bind: str) -> Control:
    return next(c for c in controls(app.view) if isinstance(c, Control) and c.bind == bind)


def button(app, label: str) -> Button:
    return next(b for b in controls(app.view) if isinstance(b, Button) and b.label == label)


@pytest.fixture
def load(built):
    from ejsrl.app import load_app

    def _load(lab: str):
        app = load_app(built(LABS[lab]))
        assert app.error is None
        return app

    return _load


def test_path_planning_profile_dropdown_replans_and_moves(load):
    app = load("path")
    m = app.model
    assert set(control(app, "profile").options) == {"4-3-4", "cubic", "quintic", "trapezoidal", "synchronous", "asynchronous"}
    for _ in range(20):
        app.step_once()
    assert m.t > 0.3
    app.apply_control(control(app, "profile"), "quintic")
    # back at the start, a quintic plan timed so the slowest joint just touches its limit, playing
    D = np.abs(np.radians(m.q_goal_deg) - np.radians(m.q_start_deg))
    assert m.t == 0.0 and np.allclose(m.q, np.radians(m.q_start_deg))
    assert m.T_plan == pytest.approx(1.875 * np.max(D / np.radians(m.v_max_deg)), rel=1e-12)
    assert app.is_playing()
    # a goal slider sends the arm back to its start, paused, with a new plan; the ghost shows the goal
    app.apply_control(control(app, "q_goal_deg[0]"), 0.0)
    assert not app.is_playing() and m.t == 0.0
    assert np.degrees(m.q_goal[0]) == pytest.approx(0.0)
    ghost = app.world["goal.link6"].T_world()
    np.testing.assert_allclose(ghost, m.robot.fkine(m.q_goal), atol=1e-9)


def test_payload_slider_changes_the_torques_at_once(load):
    app = load("dynamics")
    m = app.model
    tau1 = m.tau.copy()  # 1 kg, at rest at the start
    app.apply_control(control(app, "m_payload"), 4.0)
    assert m.m_payload == 4.0
    # at rest the extra torque is the extra weight through the payload's Jacobian: 3 kg more
    q = m.q
    h = 1e-7
    J = np.zeros((3, 6))
    for j in range(6):
        dq = np.zeros(6)
        dq[j] = h
        point = lambda qq: (m.robot.fkine(qq) @ np.append(m.r_payload, 1.0))[:3]  # noqa: E731
        J[:, j] = (point(q + dq) - point(q - dq)) / (2 * h)
    np.testing.assert_allclose(m.tau - tau1, J.T @ [0, 0, 3.0 * 9.81], rtol=1e-6, atol=1e-6)


def test_servo_desired_size_and_restart(load):
    app = load("servo")
    m = app.model
    app.apply_control(control(app, "size_px"), 140.0)
    side = np.ptp(m.s_star[:, 0])
    assert side == pytest.approx(140.0)
    for _ in range(10):
        app.step_once()
    assert m.t > 0.3
    app.run_action(button(app, "Restart"))
    assert m.t == 0.0 and np.allclose(m.q, np.radians(m.q_start_deg))
    assert m.found == 4 and m.err_px > 30


def test_pid_restart_keeps_the_gains(load):
    app = load("pid")
    m = app.model
    app.apply_control(control(app, "Kd"), 0.0)
    for _ in range(100):
        app.step_once()
    assert m.t > 0.15 and np.abs(m.q).max() > 0.05
    app.run_action(button(app, "Restart"))
    assert m.t == 0.0 and np.all(m.q == 0) and np.all(m.i == 0) and m.Kd == 0.0
    assert app.is_playing()


def test_multi_robot_sliders_move_the_mounted_arm(load):
    app = load("multi")
    m = app.model
    app.apply_control(control(app, "demo"), False)
    app.apply_control(control(app, "q1_deg[1]"), 60.0)  # shoulder of the PA-10
    base0 = m.T_base.copy()
    for _ in range(150):
        app.step_once()
    assert m.q1[1] == pytest.approx(np.radians(60.0), abs=1e-3)
    assert np.linalg.norm(m.T_base[:3, 3] - base0[:3, 3]) > 0.1  # the 3R arm rode along
    np.testing.assert_allclose(app.world["arm3.link0"].T_world(), m.T_base, atol=1e-9)


def test_kinematics_slider_and_solve(load):
    app = load("kinematics")
    m = app.model
    app.apply_control(control(app, "q_deg[0]"), 30.0)
    assert m.q[0] == pytest.approx(np.radians(30.0)) and m.plan is None
    np.testing.assert_allclose(m.T06, m.robot.fkine(m.q))
    app.apply_control(control(app, "Y"), 0.5)
    app.run_action(button(app, "Solve and move"))
    assert m.solved and app.is_playing()
    for _ in range(110):
        app.step_once()
    np.testing.assert_allclose(m.T06[:3, 3], [0.35, 0.5, 0.30], atol=1e-6)
