"""The six-axis arm example (the EjsRL paper's first lab), built and driven as a student would.

The reference is an independent product of the paper's Denavit-Hartenberg matrices
(figure 4, written out here with NumPy), not the runtime's Robot class.
"""

from __future__ import annotations

import io
import runpy
from math import pi

import numpy as np
import pytest

from ejsrl.view.elements import Button, Folder, Number, Slider
from ejsrl.world.mesh import load_mesh

from testkit.robots import load_built
from testkit import EXAMPLES, run_app

L1, A2, L4, L6 = 0.45, 0.40, 0.40, 0.10
#: the paper's table, per joint: (theta offset, d, a, alpha)
PAPER_DH = [(pi / 2, L1, 0.0, -pi / 2), (-pi / 2, 0.0, A2, 0.0), (pi, 0.0, 0.0, pi / 2),
            (0.0, L4, 0.0, -pi / 2), (0.0, 0.0, 0.0, pi / 2), (0.0, L6, 0.0, 0.0)]


def dh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1.0]])


def frames(q) -> list[np.ndarray]:
    """World frames 0..6 of the paper's arm at joints q (the base at the origin)."""
    out = [np.eye(4)]
    for qj, (off, d, a, alpha) in zip(q, PAPER_DH):
        out.append(out[-1] @ dh(qj + off, d, a, alpha))
    return out


def rpy(R: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw (Z-Y-X) of a rotation away from pitch = ±pi/2."""
    return np.array([np.arctan2(R[2, 1], R[2, 2]), np.arcsin(-R[2, 0]), np.arctan2(R[1, 0], R[0, 0])])


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return Rz @ Ry @ Rx


def controls(view) -> dict[str, object]:
    """The panel's controls and buttons by bind target or label."""
    out = {}
    for el in view:
        if isinstance(el, Folder):
            out.update(controls(el.children))
        elif isinstance(el, (Slider, Number)):
            out[el.bind] = el
        elif isinstance(el, Button):
            out[el.label] = el
    return out


@pytest.fixture
def app(built):
    return load_built(built("six_axis_arm"))


def test_the_example_runs_headless_and_its_tool_readout_is_the_dh_product(built) -> None:
    q = [0.3, -0.4, 0.9, 1.1, -0.7, 0.5]
    res = run_app(built("six_axis_arm"), "--headless", "--duration", "1", "--csv", "-", "--vars", "t,q,T_tool,tool_rpy",
                  "--set", f"q={q}", timeout=120)
    assert res.returncode == 0, res.stderr
    d = np.genfromtxt(io.StringIO(res.stdout), delimiter=",", names=True, deletechars="")
    assert len(d) == 21 and d["t"][-1] == pytest.approx(1.0)
    T = np.array([[d[f"T_tool[{i}][{j}]"][0] for j in range(4)] for i in range(4)])
    np.testing.assert_allclose(T, frames(q)[6], atol=1e-12)
    np.testing.assert_allclose([d[f"tool_rpy[{k}]"][0] for k in range(3)], rpy(frames(q)[6]), atol=1e-12)


def test_sliders_move_every_drawn_link_to_the_dh_frames(app) -> None:
    rng = np.random.default_rng(4)
    c = controls(app.view)
    for _ in range(5):
        q = rng.uniform(-1.5, 1.5, 6)
        for j in range(6):
            app.apply_control(c[f"q[{j}]"], float(q[j]))
        assert app.error is None
        F = frames(q)
        for i in range(7):
            np.testing.assert_allclose(app.world.T_world(f"arm.link{i}"), F[i], atol=1e-12)
        np.testing.assert_allclose(app.world.T_world("tool_frame"), F[6], atol=1e-12)


def test_link_meshes_come_from_the_vrml_files_in_each_links_frame(app) -> None:
    q = np.array([0.2, 0.5, 0.7, -0.4, 0.9, 0.3])
    app.model.q = q
    app.frame()
    F = frames(q)
    for i in range(7):
        parts = load_mesh(EXAMPLES / "six_axis_arm" / f"link{i}.wrl")
        node = app.world[f"arm.link{i}"]
        assert len(node.parts()) == len(parts) >= 1
        T = node.T_world()
        for drawn, ref in zip(node.parts(), parts):
            np.testing.assert_allclose(drawn.vertices @ T[:3, :3].T + T[:3, 3], ref.vertices @ F[i][:3, :3].T + F[i][:3, 3], atol=1e-12)
    # each moving link reaches from its own joint back towards the previous one
    for i, reach in ((1, 0.2), (2, 0.3), (4, 0.2)):
        v = np.concatenate([p.vertices for p in app.world[f"arm.link{i}"].parts()])  # link frame
        prev = np.linalg.inv(F[i]) @ F[i - 1][:, 3]
        assert np.min(np.linalg.norm(v - prev[:3], axis=1)) < np.linalg.norm(prev[:3]) - reach


def test_make_meshes_writes_the_committed_files(tmp_path) -> None:
    runpy.run_path(str(EXAMPLES / "six_axis_arm" / "make_meshes.py"))["main"](tmp_path)
    for i in range(7):
        assert (tmp_path / f"link{i}.wrl").read_text() == (EXAMPLES / "six_axis_arm" / f"link{i}.wrl").read_text()


def test_solve_moves_the_arm_to_a_typed_target(app) -> None:
    c = controls(app.view)
    q_true = np.array([-0.5, 0.3, 0.8, 0.6, -0.9, 1.2])
    T = frames(q_true)[6]
    values = {"X": T[0, 3], "Y": T[1, 3], "Z": T[2, 3], **dict(zip(("roll", "pitch", "yaw"), rpy(T)))}
    q_before = app.model.q.copy()
    for name, v in values.items():
        app.apply_control(c[name], float(v))
    np.testing.assert_allclose(app.model.q, q_before)  # typing alone does not move the arm
    app.run_action(c["Solve"])
    assert app.error is None and app.model.status == "Solved."
    T_reached = frames(app.model.q)[6]
    np.testing.assert_allclose(T_reached[:3, 3], T[:3, 3], atol=1e-8)
    np.testing.assert_allclose(T_reached[:3, :3], T[:3, :3], atol=1e-8)
    np.testing.assert_allclose(app.world.T_world("arm.link6"), T_reached, atol=1e-12)


def test_an_unreachable_target_leaves_the_arm_and_says_so(app) -> None:
    c = controls(app.view)
    q_before = app.model.q.copy()
    app.apply_control(c["Z"], 1.4)
    app.apply_control(c["Y"], 1.0)
    app.run_action(c["Solve"])
    np.testing.assert_allclose(app.model.q, q_before)
    assert app.model.status.startswith("Out of reach")
    assert any("Out of reach" in a for a in app.pop_alerts())


def test_dragging_the_gizmo_solves_inverse_kinematics(app) -> None:
    rng = np.random.default_rng(6)
    for _ in range(3):
        q_true = rng.uniform(-0.8, 0.8, 6) + np.array([0, 0.3, 0.6, 0, 0.6, 0])
        T = frames(q_true)[6]
        app.apply_gizmo("target", T)
        assert app.error is None
        np.testing.assert_allclose(app.model.T_target, T, atol=1e-12)  # the bound pose variable
        np.testing.assert_allclose([app.model.X, app.model.Y, app.model.Z], T[:3, 3], atol=1e-12)
        np.testing.assert_allclose(rpy_matrix(app.model.roll, app.model.pitch, app.model.yaw), T[:3, :3], atol=1e-12)
        T_reached = frames(app.model.q)[6]
        np.testing.assert_allclose(T_reached, T, atol=1e-8)
        np.testing.assert_allclose(app.world.T_world("target"), T, atol=1e-12)  # the handle stays where dropped


def test_the_wrist_camera_sees_the_block_below_it(app) -> None:
    img = app.model.capture("wrist")
    assert img.shape == (180, 240, 3) and img.dtype == np.uint8
    block = np.array([0.25, 0.45, 0.05])
    # camera 0.25 m above the block, looking straight down (camera z = -world z)
    T_cam = np.eye(4)
    T_cam[:3, :3] = np.diag([1.0, -1.0, -1.0])
    T_cam[:3, 3] = block + [0, 0, 0.30]
    T_tool = T_cam @ np.linalg.inv(app.model.T_tool_camera)
    sol = app.model.robot.ikine(T_tool, app.model.q)
    assert sol.success
    np.testing.assert_allclose(frames(sol.q)[6] @ app.model.T_tool_camera, T_cam, atol=1e-8)
    c = controls(app.view)
    for j in range(6):  # moved with the sliders
        app.apply_control(c[f"q[{j}]"], float(sol.q[j]))
    img = app.model.capture("wrist")
    centre = img[80:100, 110:130].reshape(-1, 3).mean(axis=0)
    assert centre[0] > 120 and centre[1] < 60 and centre[2] < 80, centre  # crimson
    np.testing.assert_allclose(app.world.T_world("wrist"), T_cam, atol=1e-8)


def test_lowering_the_gripper_into_a_block_is_a_collision(app) -> None:
    assert app.model.collisions() == []
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])  # tool pointing down
    T[:3, 3] = [0.25, 0.45, 0.08]  # the tool tip 3 cm into the red block's top
    sol = app.model.robot.ikine(T, app.model.q)
    assert sol.success
    app.model.q = sol.q
    assert ("arm.link6", "red_block") in app.model.collisions()
