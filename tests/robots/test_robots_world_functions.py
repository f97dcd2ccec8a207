"""World functions from model code: object poses, moving, grasping and releasing objects.

References: the robot's fkine_all (a grasped object's pose is the link pose times the
relative pose it had when grasped) and closed forms (a belt at constant speed).
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from ejsrl.robotics import models
from ejsrl.robotics.trajectory import jtraj
from ejsrl.robotics.transforms import rpy2tr, transl
from ejsrl.view.elements import Dynamic, Node3D

from testkit.robots import Model, load_built, robot, scene
from testkit import run_app

SPECS = Path(__file__).resolve().parent / "specs"


def box(name: str, position=(0.5, 0.1, 0.3), **kw) -> Node3D:
    return Node3D(kind="box", name=name, props={"size": (0.05, 0.05, 0.05)}, position=position, **kw)


@pytest.fixture
def puma_scene():
    r = models.puma560()
    m = Model(robot=r, q=np.array([0.1, 0.6, -2.4, 0.2, 0.5, -0.3]), mount=transl(0.2, -0.1, 0.05) @ rpy2tr(0, 0, 0.4), z=0.8)
    sync, wf = scene(
        robot("arm", base=Dynamic(lambda m: m.mount, "mount")),
        box("part", rotation=(0.3, 0.0, 0.2)),
        Node3D(kind="group", name="shelf", props={}, position=(0.0, 0.7, 0.0), children=[box("bin", position=(0.1, 0.0, 0.2))]),
        Node3D(kind="sphere", name="lamp", props={"radius": 0.05}, position=Dynamic(lambda m: [0.0, 0.0, m.z], "[0, 0, z]")),
        model=m,
    )
    return r, m, sync, wf


def test_a_grasped_object_keeps_its_pose_on_the_link_through_a_trajectory_and_stays_where_released(puma_scene) -> None:
    r, m, sync, wf = puma_scene
    T_part0 = wf.object_pose("part")
    np.testing.assert_allclose(T_part0, transl(0.5, 0.1, 0.3) @ rpy2tr(0.3, 0.0, 0.2), atol=1e-12)
    wf.attach("part", "arm")  # default: the last link
    assert wf.attached_to("part") == "arm.link6"
    T_link_part = np.linalg.inv(m.mount @ r.fkine_all(m.q)[6]) @ T_part0

    traj = jtraj(m.q, np.array([-0.8, 0.2, -1.9, 1.0, -0.4, 0.9]), 2.0, num=41)
    for k, qk in enumerate(traj.q):
        m.q = qk
        if k % 2:  # between display frames (headless runs, several steps a frame): no update
            sync.update(m)
        if k <= 25:
            np.testing.assert_allclose(wf.object_pose("part"), m.mount @ r.fkine_all(qk)[6] @ T_link_part, atol=1e-12)
        else:
            np.testing.assert_allclose(wf.object_pose("part"), T_released, atol=1e-12)
        if k == 25:
            wf.release("part")
            T_released = m.mount @ r.fkine_all(qk)[6] @ T_link_part
    assert wf.attached_to("part") is None
    np.testing.assert_allclose(wf.object_pose("part"), T_released, atol=1e-12)  # the arm went on; the part did not
    sync.update(m, first=True)  # not even the spec's constant pose moves it back ...
    np.testing.assert_allclose(wf.object_pose("part"), T_released, atol=1e-12)
    sync.reset()  # ... until a reset
    np.testing.assert_allclose(wf.object_pose("part"), T_part0, atol=1e-12)


def test_attach_to_a_given_link_and_to_an_object_in_a_group(puma_scene) -> None:
    r, m, sync, wf = puma_scene
    T_bin0 = wf.object_pose("bin")
    np.testing.assert_allclose(T_bin0, transl(0.1, 0.7, 0.2), atol=1e-12)
    wf.attach("bin", "arm", 2)
    T_rel = np.linalg.inv(m.mount @ r.fkine_all(m.q)[2]) @ T_bin0
    m.q = m.q + 0.3
    np.testing.assert_allclose(wf.object_pose("bin"), m.mount @ r.fkine_all(m.q)[2] @ T_rel, atol=1e-12)
    wf.attach("bin", "arm", -1)  # handed over to the last link, in place
    T_now = wf.object_pose("bin")
    m.q = m.q - 0.5
    np.testing.assert_allclose(wf.object_pose("bin"), m.mount @ r.fkine_all(m.q)[6] @ np.linalg.inv(m.mount @ r.fkine_all(m.q + 0.5)[6]) @ T_now, atol=1e-12)
    sync.reset()
    assert sync.world["bin"].parent is sync.world["shelf"]
    np.testing.assert_allclose(wf.object_pose("bin"), T_bin0, atol=1e-12)


def test_move_object_takes_a_pose_or_a_position(puma_scene) -> None:
    _r, m, sync, wf = puma_scene
    R0 = wf.object_pose("part")[:3, :3]
    wf.move_object("part", [1.0, 2.0, 3.0])
    T = wf.object_pose("part")
    np.testing.assert_allclose(T[:3, 3], [1.0, 2.0, 3.0])
    np.testing.assert_allclose(T[:3, :3], R0, atol=1e-15)  # a position keeps the orientation
    target = transl(-0.3, 0.2, 0.1) @ rpy2tr(0.5, -0.4, 1.2)
    wf.move_object("bin", target)  # a world pose, also for an object inside a moved group
    np.testing.assert_allclose(wf.object_pose("bin"), target, atol=1e-12)
    sync.update(m, first=True)
    np.testing.assert_allclose(wf.object_pose("bin"), target, atol=1e-12)


def test_moving_what_code_may_not_move_is_a_clear_error(puma_scene) -> None:
    _r, _m, _sync, wf = puma_scene
    with pytest.raises(ValueError, match=r"its pose is the expression '\[0, 0, z\]' in the spec"):
        wf.move_object("lamp", [0, 0, 1])
    with pytest.raises(ValueError, match="its pose is the expression"):
        wf.attach("lamp", "arm")
    with pytest.raises(ValueError, match="link of robot 'arm'"):
        wf.move_object("arm.link3", [0, 0, 1])
    with pytest.raises(ValueError, match="it is a robot"):
        wf.attach("arm", "arm")
    with pytest.raises(ValueError, match="'part' is a box, not a robot"):
        wf.attach("bin", "part")
    with pytest.raises(KeyError, match="did you mean 'part'"):
        wf.move_object("prat", [0, 0, 0])
    with pytest.raises(IndexError, match="links 0 \\(the base\\) to 6"):
        wf.attach("part", "arm", 7)
    with pytest.raises(ValueError, match="4x4 matrix or \\[x, y, z\\]"):
        wf.move_object("part", [1, 2])


def test_a_conveyor_belt_and_a_grasp_in_a_built_app(tmp_path) -> None:
    """Model code moves parts every step with move_object, attaches one, lifts it, releases it."""
    from ejsgen.cli import build

    app_dir = build(SPECS / "conveyor.ejs.yaml", tmp_path / "conveyor")
    res = run_app(app_dir, "--headless", "--duration", "2.5", "--csv", "-", "--vars", "t,q,part1_x,part1_z,part2_x,start_dist", timeout=120)
    assert res.returncode == 0, res.stderr
    d = np.genfromtxt(io.StringIO(res.stdout), delimiter=",", names=True, deletechars="")
    t = d["t"]
    v, dt, grasp_at = 0.2, 0.01, 1.0
    np.testing.assert_allclose(d["part2_x"], -0.1 + v * t, atol=1e-12)  # the belt, whole run
    # the step that starts at t = grasp_at moves the part, attaches it, then starts the lift;
    # the step that starts at t = 2 grasp_at lifts, then releases
    before = t < grasp_at + dt / 2
    np.testing.assert_allclose(d["part1_x"][before], 0.2 + v * t[before], atol=1e-12)
    r = models.puma560()
    q = np.column_stack([d[f"q[{j}]"] for j in range(6)])
    k = int(np.flatnonzero(~before)[0])
    p_grasp = np.array([0.2 + v * t[k], -0.15, 0.3, 1.0])
    rel = np.linalg.inv(r.fkine_all(q[k - 1])[6]) @ p_grasp  # its place on the last link
    held = (t > grasp_at + dt / 2) & (t < 2 * grasp_at + 1.5 * dt)
    expected = np.array([r.fkine_all(qi)[6] @ rel for qi in q[held]])
    np.testing.assert_allclose(d["part1_x"][held], expected[:, 0], atol=1e-12)
    np.testing.assert_allclose(d["part1_z"][held], expected[:, 2], atol=1e-12)
    assert np.ptp(d["part1_z"][held]) > 0.05  # it was lifted
    after = t > 2 * grasp_at + dt / 2
    assert np.ptp(d["part1_x"][after]) == 0 and np.ptp(d["part1_z"][after]) == 0  # stays where released
    # released where it was last held: the app composes the link pose with the relative pose it
    # stored at the grasp, the test inverts fkine instead; the two products of 4x4 transforms of
    # unit size round differently (a few ulps, ~1e-16 m; NumPy/SciPy builds differ there), so the
    # same 1e-12 m as the held positions above, ten orders below the 5 cm lift
    assert d["part1_z"][after][0] == pytest.approx(expected[-1, 2], rel=0, abs=1e-12)
    # the sphere attached in init follows the tool at a constant distance
    q0 = np.array([0.0, 0.7854, -3.1416, 0.0, 0.7854, 0.0])
    dist0 = np.linalg.norm(np.array([0.45, -0.15, 0.4]) - r.fkine(q0)[:3, 3])
    np.testing.assert_allclose(d["start_dist"], dist0, atol=1e-12)


def test_attach_in_init_and_reset_in_a_running_app(tmp_path) -> None:
    from ejsgen.cli import build

    app = load_built(build(SPECS / "conveyor.ejs.yaml", tmp_path / "conveyor"))
    assert app.error is None
    assert app.world["start_tool"].parent is app.world["arm.link6"]
    for _ in range(150):
        app.step_once()
    assert app.model.grasped and app.world["part1"].parent is app.world["arm.link6"]
    assert app.model.part2_x == pytest.approx(-0.1 + 0.2 * 1.5)
    with pytest.raises(ValueError, match="expression"):
        app.model.move_object("bound", [0, 0, 0])
    app.reset()
    assert app.error is None
    assert app.world["part1"].parent is None  # back where the spec has it ...
    np.testing.assert_allclose(app.world.T_world("part1")[:3, 3], [0.2, -0.15, 0.3])
    np.testing.assert_allclose(app.world.T_world("part2")[:3, 3], [-0.1, -0.15, 0.3])
    assert app.world["start_tool"].parent is app.world["arm.link6"]  # ... and init attached this one again
    assert app.model.start_dist == pytest.approx(np.linalg.norm(np.array([0.45, -0.15, 0.4]) - models.puma560().fkine(app.model.q)[:3, 3]))


def test_link_poses_are_known_already_in_the_first_init(tmp_path) -> None:
    from ejsgen.cli import build
    from ejsrl.robotics import models

    spec = tmp_path / "early.ejs.yaml"
    spec.write_text(
        "ejs: 1\ntitle: Early\nimports: [from ejsrl.robotics import models]\n"
        "model:\n  variables:\n    robot: {expr: 'models.rrr()'}\n    q: [0.0, 0.3, -0.6]\n    z: 0.0\n"
        "  init: |\n    z = object_pose('arm.link3')[2, 3]\n"
        "view:\n  - scene:\n      - robot: {name: arm, model: robot, q: q}\n"
    )
    app = load_built(build(spec, tmp_path / "early"))
    assert app.error is None
    assert app.model.z == pytest.approx(models.rrr().fkine_all(np.array([0.0, 0.3, -0.6]))[3][2, 3], abs=1e-12)