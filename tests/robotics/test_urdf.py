"""URDF arms: ``load_urdf`` against Pinocchio loading the same files (recorded in
fixtures/urdf_pinocchio.json by fixtures/make_urdf_pinocchio.py), and what the loader
reads from the file (limits, friction, tool, visuals)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ejsrl.robotics import load_urdf
from ejsrl.robotics.urdf import URDFError
from ejsrl.robotics import models
from testkit.robotics import FIXTURES

UR5 = models.UR5_URDF  # the installed copy
TEST_ARM = FIXTURES / "urdf_test_arm.urdf"
REF = json.loads((FIXTURES / "urdf_pinocchio.json").read_text())


def _arm(name: str):
    arm = REF["arms"][name]
    robot = models.ur5_urdf() if name == "ur5" else load_urdf(TEST_ARM, tip=arm["tip"])
    rows = arm["rows"]
    cols = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    return robot, cols


@pytest.mark.parametrize("name", ["ur5", "test_arm"])
@pytest.mark.parametrize("fast", [True, False])
def test_urdf_arm_matches_pinocchio(name: str, fast: bool) -> None:
    robot, c = _arm(name)
    robot._fast = fast
    assert robot.n == REF["arms"][name]["nv"]
    np.testing.assert_allclose(robot.gravity, REF["arms"][name]["gravity"])
    for i in range(len(c["q"])):
        q, qd, qdd = c["q"][i], c["qd"][i], c["qdd"][i]
        np.testing.assert_allclose(robot.fkine(q), c["T"][i], atol=1e-12, rtol=0)
        np.testing.assert_allclose(robot.jacob0(q), c["J"][i], atol=1e-12, rtol=0)
        np.testing.assert_allclose(robot.rne(q, qd, qdd, friction=False), c["tau"][i], atol=1e-12, rtol=0)
        np.testing.assert_allclose(robot.inertia(q), c["M"][i], atol=1e-12, rtol=0)
        # Pinocchio's ABA has no joint friction: cancel ours (URDF damping and friction)
        tau = c["tau2"][i] - robot.friction(qd)
        np.testing.assert_allclose(robot.accel(q, qd, tau), c["accel"][i], atol=1e-12, rtol=1e-12)  # |qdd| up to 4e3
    # batches give the same answers
    np.testing.assert_allclose(robot.fkine(c["q"]), c["T"], atol=1e-12, rtol=0)
    np.testing.assert_allclose(robot.rne(c["q"], c["qd"], c["qdd"], friction=False), c["tau"], atol=1e-12, rtol=0)
    np.testing.assert_allclose(robot.inertia(c["q"]), c["M"], atol=1e-12, rtol=0)


def test_urdf_ur5_reads_limits_names_tool_and_meshes() -> None:
    robot = models.ur5_urdf()
    assert robot.name == "UR5" and robot.tip == "tool0"
    assert robot.joint_names == ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                 "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
    np.testing.assert_allclose(robot.qlim[:, 2], [-np.pi, np.pi], atol=1e-10)
    np.testing.assert_allclose(robot.qlim[:, 0], [-2 * np.pi, 2 * np.pi], atol=1e-10)
    # the tool0 frame: 0.0823 m beyond wrist 3 (the UR5's published d6) along its own z
    T = robot.fkine(np.zeros(6))
    W = robot.fkine_all(np.zeros(6))[-1]
    np.testing.assert_allclose(np.linalg.norm(T[:3, 3] - W[:3, 3]), 0.0823, atol=1e-12)
    # at q = 0 the arm lies along x of the ROS base_link: x = a2 + a3, y = d4 + d6, z = d1 - d5
    # with the UR5's published DH lengths (a2 0.425, a3 0.39225, d1 0.089159, d4 0.10915, d5 0.09465, d6 0.0823)
    np.testing.assert_allclose(T[:3, 3], [0.425 + 0.39225, 0.10915 + 0.0823, 0.089159 - 0.09465], atol=1e-12)
    assert len(robot.visuals) == 7 and all(len(v) == 1 for v in robot.visuals)
    assert [v.filename.rsplit("/", 1)[-1] for vs in robot.visuals for v in vs] == [
        "base.stl", "shoulder.stl", "upperarm.stl", "forearm.stl", "wrist1.stl", "wrist2.stl", "wrist3.stl"]
    parts = robot.visuals[2][0].trimeshes()
    assert parts and parts[0].vertices.shape[1] == 3
    np.testing.assert_allclose(robot.visuals[2][0].rgba, [0.75, 0.76, 0.78, 1.0])


def test_urdf_reads_friction_continuous_joints_and_fixed_branches() -> None:
    robot = load_urdf(TEST_ARM)  # default tip: the deepest leaf, "tcp"
    assert robot.tip == "tcp"
    assert robot.joint_names == ["j1", "j2", "j3", "j4", "j5"]
    assert [k.isprismatic for k in robot.links] == [False, False, True, False, False]
    assert robot.links[3].qlim is None  # continuous
    np.testing.assert_allclose(robot.links[2].qlim, [0.0, 0.3])
    assert robot.links[1].B == 0.5
    np.testing.assert_allclose(robot.links[1].Tc, [0.1, -0.1])
    still = robot.nofriction(coulomb=True, viscous=True)  # a copy keeps the URDF's names and geometry
    assert still.links[1].B == 0.0 and still.joint_names == robot.joint_names and still.visuals is robot.visuals
    # link 2 carries l2, the plate and the sensor (fixed joints): 2.5 + 0.7 + 0.4 kg
    assert robot.links[1].m == pytest.approx(3.6, abs=1e-12)
    # visuals: a cylinder on link 1, a box and the sensor's sphere on link 2
    assert [v.kind for v in robot.visuals[1]] == ["cylinder"]
    assert sorted(v.kind for v in robot.visuals[2]) == ["box", "sphere"]


def test_urdf_jacobian_and_ik_work_on_an_urdf_arm() -> None:
    robot = load_urdf(TEST_ARM)
    q = np.array([0.3, -0.4, 0.1, 0.7, -0.2])
    J = robot.jacob0(q)
    eps = 1e-6
    for j in range(robot.n):  # linear rows against finite differences of fkine
        dq = np.zeros(5)
        dq[j] = eps
        dp = (robot.fkine(q + dq)[:3, 3] - robot.fkine(q - dq)[:3, 3]) / (2 * eps)
        np.testing.assert_allclose(J[:3, j], dp, atol=1e-8)
    ur5 = load_urdf(UR5, tip="tool0")
    q = np.array([0.2, -1.0, 1.2, -0.5, 0.8, 0.3])
    T = ur5.fkine(q)
    sol = ur5.ikine(T, q0=q + 0.1)
    assert sol.success
    np.testing.assert_allclose(ur5.fkine(sol.q), T, atol=1e-9)


def test_urdf_errors_name_the_problem(tmp_path) -> None:
    with pytest.raises(URDFError, match="no link named 'tol0'.*tool0"):
        load_urdf(UR5, tip="tol0")
    bad = tmp_path / "floating.urdf"
    bad.write_text('<robot name="f"><link name="a"/><link name="b"/>'
                   '<joint name="free" type="floating"><parent link="a"/><child link="b"/></joint></robot>')
    with pytest.raises(URDFError, match="joint 'free' is of type 'floating'"):
        load_urdf(bad)
    missing = tmp_path / "mesh.urdf"
    missing.write_text('<robot name="m"><link name="a"/><link name="b"><visual><geometry>'
                       '<mesh filename="package://nowhere/m.stl"/></geometry></visual></link>'
                       '<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>'
                       '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>')
    with pytest.raises(URDFError, match="mesh file 'package://nowhere/m.stl' not found"):
        load_urdf(missing)
    assert load_urdf(missing, load_visuals=False).n == 1


def test_urdf_arm_with_a_base_tool_and_payload_agrees_on_both_paths() -> None:
    """The generated kernels and the NumPy reference (``_fast = False``) give the same
    answers for a URDF arm mounted on a tilted base with a payload on a tool."""
    from ejsrl.robotics.transforms import rpy2tr, transl

    robot = load_urdf(TEST_ARM)
    T0 = robot.fkine(np.array([0.2, 0.1, 0.05, -0.3, 0.4]))
    robot.base = transl(0.3, -0.1, 0.5) @ rpy2tr(0.4, -0.2, 0.9)
    robot.tool = robot.tool @ transl(0.0, 0.0, 0.05)
    robot.payload(0.8, [0.01, 0.0, 0.02], [0.001, 0.002, 0.0015])
    q = np.array([0.2, 0.1, 0.05, -0.3, 0.4])
    np.testing.assert_allclose(robot.fkine(q), robot.base @ T0 @ transl(0.0, 0.0, 0.05), atol=1e-12)
    qd, qdd = np.array([0.3, -0.2, 0.1, 0.5, -0.4]), np.array([-0.1, 0.4, 0.2, 0.3, 0.1])
    fast = [robot.fkine(q), robot.jacob0(q), robot.rne(q, qd, qdd), robot.inertia(q), robot.accel(q, qd, qdd)]
    robot._fast = False
    slow = [robot.fkine(q), robot.jacob0(q), robot.rne(q, qd, qdd), robot.inertia(q), robot.accel(q, qd, qdd)]
    for a, b in zip(fast, slow):
        np.testing.assert_allclose(a, b, atol=1e-12)


def test_urdf_arm_without_meshes_is_drawn_with_rods_from_joint_to_joint() -> None:
    from ejsrl.world.robot_node import robot_geometry

    robot = load_urdf(UR5, load_visuals=False)
    assert robot.visuals is None
    parts, shapes = robot_geometry(robot)
    assert len(parts) == robot.n + 1 and all(parts)
    F = robot.fkine_all(np.array([0.3, -1.0, 1.2, 0.2, 0.5, -0.4]))
    for i in range(1, robot.n + 1):  # in frame i-1, a rod from its origin to joint i's origin
        (rod,) = [s for s in shapes[i - 1] if s.kind == "capsule"]
        np.testing.assert_allclose(rod.p0, 0.0)
        p1_world = F[i - 1][:3, :3] @ rod.p1 + F[i - 1][:3, 3]
        np.testing.assert_allclose(p1_world, F[i][:3, 3], atol=1e-12)


def _two_joints(tmp_path, second: str) -> str:
    p = tmp_path / "arm.urdf"
    p.write_text('<robot name="g"><link name="a"/><link name="b"/><link name="c"/><link name="f"/>'
                 '<joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>'
                 '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
                 '<joint name="j2" type="revolute"><parent link="b"/><child link="c"/><axis xyz="0 1 0"/>'
                 '<origin xyz="0.3 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
                 f'<joint name="finger" type="prismatic"><parent link="b"/><child link="f"/>{second}'
                 '<axis xyz="1 0 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/></joint></robot>')
    return str(p)


def test_urdf_off_chain_and_mimic_joints(tmp_path) -> None:
    path = _two_joints(tmp_path, "")
    with pytest.warns(UserWarning, match="joint 'finger' is not on the chain to 'c'; it is held at 0"):
        robot = load_urdf(path, tip="c")
    assert robot.n == 2
    with pytest.raises(URDFError, match="joint 'finger' mimics 'j1'; mimic joints on the chain are not supported"):
        load_urdf(_two_joints(tmp_path, '<mimic joint="j1" multiplier="0.01"/>'), tip="f")
