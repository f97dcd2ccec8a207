"""Robots drawn in the world: every link where fkine_all puts it, every frame.

The reference is the robot model's own forward kinematics (``fkine_all``, tested against
Robotics Toolbox in tests/robotics) composed with the mounting pose, never the scene's
earlier output; the geometry is checked against the joint origins it must connect.
"""

from __future__ import annotations

from unittest.mock import MagicMock

import numpy as np
import pytest

from ejsrl.robotics import models
from ejsrl.robotics.transforms import rpy2tr, transl, trotz
from ejsrl.view._scene_mirror import SceneMirror
from ejsrl.view.elements import Dynamic, Node3D
from ejsrl.world.binding import SceneSync
from ejsrl.world.robot_node import LinkNode, RobotNode

from testkit.robots import Model, random_q, robot, scene

ARMS = {"puma560": models.puma560, "ur5": models.ur5, "pa10": models.pa10, "stanford": models.stanford, "scara": models.scara}


def world_vertices(node) -> np.ndarray:
    """All vertices of a node's parts, in the world frame."""
    T = node.T_world()
    out = []
    for p in node.parts():
        v = p.vertices if p.T_node_part is None else p.vertices @ p.T_node_part[:3, :3].T + p.T_node_part[:3, 3]
        out.append(v @ T[:3, :3].T + T[:3, 3])
    return np.concatenate(out) if out else np.zeros((0, 3))


@pytest.mark.parametrize("arm", sorted(ARMS))
def test_every_drawn_link_sits_at_fkine_all_for_random_q_with_a_non_identity_base(arm: str) -> None:
    rng = np.random.default_rng(5)
    r = ARMS[arm]()
    r.base = transl(0.3, -0.2, 0.1) @ rpy2tr(0.1, -0.2, 0.3)  # the model's own base
    m = Model(robot=r, q=random_q(r, rng), mount=transl(-1.0, 0.5, 0.2) @ trotz(0.7))  # and the element's base
    sync, _ = scene(robot("arm", base=Dynamic(lambda m: m.mount, "mount")), model=m)
    world = sync.world
    assert [world[f"arm.link{i}"].index for i in range(r.n + 1)] == list(range(r.n + 1))
    assert f"arm.link{r.n + 1}" not in world
    for _ in range(25):
        m.q = random_q(r, rng)
        sync.update(m)
        F = r.fkine_all(m.q)
        for i in range(r.n + 1):
            np.testing.assert_allclose(world.T_world(f"arm.link{i}"), m.mount @ F[i], atol=1e-12)
        # the tool: the last link's frame and the model's tool offset give fkine
        np.testing.assert_allclose(world.T_world(f"arm.link{r.n}") @ r.tool, m.mount @ r.fkine(m.q), atol=1e-12)
    np.testing.assert_allclose(world.T_world("arm"), m.mount, atol=0)


@pytest.mark.parametrize("arm", ["puma560", "ur5", "stanford"])
def test_automatic_link_bodies_reach_both_joints_they_connect(arm: str) -> None:
    """Each link with a length is drawn from the previous joint origin to its own."""
    rng = np.random.default_rng(2)
    r = ARMS[arm]()
    m = Model(robot=r, q=random_q(r, rng))
    sync, _ = scene(robot("arm"), model=m)
    F = r.fkine_all(m.q)
    lengths = r.link_lengths()
    tol = 0.03 * r.reach  # the rods' radius is a few per cent of the reach
    for i in range(1, r.n + 1):
        if r.links[i - 1].isprismatic or np.allclose(lengths[i - 1], 0):
            continue
        v = world_vertices(sync.world[f"arm.link{i}"])
        for origin in (F[i - 1][:3, 3], F[i][:3, 3]):
            assert np.min(np.linalg.norm(v - origin, axis=1)) < tol, (i, origin)
        # and nothing of it lies much beyond the segment that joins them
        a, b = F[i - 1][:3, 3], F[i][:3, 3]
        assert np.max(np.linalg.norm(v - a, axis=1)) < np.linalg.norm(b - a) + np.abs(lengths[i - 1]).sum() + tol


def test_a_robot_mounted_on_another_robots_link_follows_it() -> None:
    rng = np.random.default_rng(8)
    carrier, tool_arm = models.puma560(), models.rrr()
    m = Model(carrier=carrier, qa=random_q(carrier, rng), small=tool_arm, qb=random_q(tool_arm, rng))
    sync, _ = scene(
        robot("big", model="carrier", q="qa"),
        robot("small", model="small", q="qb", base=Dynamic(lambda m: m.carrier.fkine(m.qa), "carrier.fkine(qa)")),
        model=m,
    )
    for _ in range(20):
        m.qa, m.qb = random_q(carrier, rng), random_q(tool_arm, rng)
        sync.update(m)
        F = tool_arm.fkine_all(m.qb)
        for i in range(tool_arm.n + 1):
            np.testing.assert_allclose(sync.world.T_world(f"small.link{i}"), carrier.fkine(m.qa) @ F[i], atol=1e-12)
        np.testing.assert_allclose(sync.world.T_world("small.link0"), sync.world.T_world("big.link6"), atol=1e-12)


def test_position_and_rotation_of_the_element_place_the_robot() -> None:
    r = models.rrr()
    m = Model(robot=r, q=np.array([0.3, 0.4, -0.5]))
    sync, _ = scene(robot("arm", position=(1.0, 2.0, 0.5), rotation=(0.0, 0.0, np.pi / 2)), model=m)
    pose = transl(1.0, 2.0, 0.5) @ trotz(np.pi / 2)
    for i, T in enumerate(r.fkine_all(m.q)):
        np.testing.assert_allclose(sync.world.T_world(f"arm.link{i}"), pose @ T, atol=1e-12)


def test_frames_are_shown_per_link_when_asked() -> None:
    r = models.ur5()
    m = Model(robot=r, q=np.array([0.1, -0.5, 0.9, 0.2, 0.3, 0.4]), r2=models.rrr(), q2=np.zeros(3))
    sync, _ = scene(robot("arm", show_frames=True), robot("plain", model="r2", q="q2"), model=m)
    F = r.fkine_all(m.q)
    for i in range(r.n + 1):
        node = sync.world[f"arm.frame{i}"]
        assert node.kind == "frame"
        np.testing.assert_allclose(node.T_world(), F[i], atol=1e-12)
    assert not any(n.kind == "frame" for n in sync.world.walk() if n.name.startswith("plain"))


def test_a_new_model_object_rebuilds_the_links_and_keeps_attached_objects_on_their_link() -> None:
    m = Model(robot=models.puma560(), q=np.array([0.2, 0.5, -0.4, 0.1, 0.3, 0.0]))
    box = Node3D(kind="box", name="part", props={"size": (0.05, 0.05, 0.05)}, position=(0.5, 0.1, 0.3))
    sync, wf = scene(robot("arm"), box, model=m)
    wf.attach("part", "arm", 3)
    T_link_part = np.linalg.inv(sync.world.T_world("arm.link3")) @ sync.world.T_world("part")
    m.robot, m.q = models.rrr(), np.array([0.4, 0.3, 0.2])
    sync.update(m)
    names = {n.name for n in sync.world.walk()}
    assert {f"arm.link{i}" for i in range(4)} <= names and "arm.link4" not in names and "arm.link6" not in names
    assert sync.world["part"].parent is sync.world["arm.link3"]
    F = m.robot.fkine_all(m.q)
    np.testing.assert_allclose(sync.world.T_world("part"), F[3] @ T_link_part, atol=1e-12)


def test_the_same_arm_made_again_keeps_its_link_nodes_and_another_arm_redraws_them() -> None:
    """On reset a model's robot is made again: same joints count, same nodes (no flicker)."""
    m = Model(robot=models.puma560(), q=np.array([0.2, 0.5, -0.4, 0.1, 0.3, 0.0]))
    sync, wf = scene(robot("arm"), Node3D(kind="box", name="part", props={"size": (0.05,) * 3}, position=(0.5, 0.1, 0.3)), model=m)
    wf.attach("part", "arm")
    nodes = [sync.world[f"arm.link{i}"] for i in range(7)]
    revs = [n.geom_rev for n in nodes]
    m.robot = models.puma560()
    sync.update(m)
    assert [sync.world[f"arm.link{i}"] for i in range(7)] == nodes and [n.geom_rev for n in nodes] == revs
    m.robot, m.q = models.ur5(), np.array([0.1, -0.5, 0.9, 0.2, 0.3, 0.4])  # another 6-joint arm
    sync.update(m)
    assert [sync.world[f"arm.link{i}"] for i in range(7)] == nodes and nodes[2].geom_rev > revs[2]
    F = m.robot.fkine_all(m.q)
    for i in range(7):
        np.testing.assert_allclose(sync.world.T_world(f"arm.link{i}"), F[i], atol=1e-12)
    v = world_vertices(nodes[2])  # the UR5's upper arm (a2 = -0.425) joins its frames 1 and 2
    for origin in (F[1][:3, 3], F[2][:3, 3]):
        assert np.min(np.linalg.norm(v - origin, axis=1)) < 0.03 * m.robot.reach
    assert sync.world["part"].parent is nodes[6]


def test_editing_a_dh_parameter_in_place_redraws_the_link() -> None:
    r = models.rrr()
    m = Model(robot=r, q=np.zeros(3))
    sync, _ = scene(robot("arm"), model=m)
    link2 = sync.world["arm.link2"]
    rev = link2.geom_rev
    assert np.ptp(world_vertices(link2)[:, 0]) < 0.5  # the upper arm, a2 = 0.4 along x
    r.links[1].a = 0.6
    sync.update(m)
    assert link2.geom_rev > rev
    F = r.fkine_all(m.q)
    np.testing.assert_allclose(F[2][:3, 3], [0.6, 0.0, 0.4], atol=1e-12)
    v = world_vertices(link2)
    for origin in (F[1][:3, 3], F[2][:3, 3]):  # drawn from the shoulder out to the new elbow
        assert np.min(np.linalg.norm(v - origin, axis=1)) < 0.03 * r.reach
    assert np.ptp(v[:, 0]) > 0.6


def test_one_mesh_per_link_is_drawn_in_that_links_frame(tmp_path) -> None:
    """Mesh files are read relative to the app folder and drawn in the link frames."""
    r = models.rrr()
    (tmp_path / "meshes").mkdir()
    for i in range(r.n + 1):  # a small box per link, off its frame's origin along x by 0.1 i
        (tmp_path / "meshes" / f"l{i}.wrl").write_text(
            f"#VRML V2.0 utf8\nTransform {{ translation {0.1 * i} 0 0 children [ Shape {{ geometry Box {{ size 0.02 0.02 0.02 }} }} ] }}\n"
        )
    files = [f"meshes/l{i}.wrl" for i in range(r.n + 1)]
    m = Model(robot=r, q=np.array([0.5, -0.3, 0.8]))
    sync, _ = scene(robot("arm", meshes=files), robot("short", meshes=files[1:]), model=m, base_dir=tmp_path)
    F = r.fkine_all(m.q)
    for i in range(r.n + 1):
        centre = world_vertices(sync.world[f"arm.link{i}"]).mean(axis=0)
        np.testing.assert_allclose(centre, (F[i] @ [0.1 * i, 0, 0, 1])[:3], atol=1e-12)
    # with n files, link i gets file i (1-based) and the base keeps its automatic plate
    for i in range(1, r.n + 1):
        centre = world_vertices(sync.world[f"short.link{i}"]).mean(axis=0)
        np.testing.assert_allclose(centre, (F[i] @ [0.1 * i, 0, 0, 1])[:3], atol=1e-12)
    assert len(sync.world["short.link0"].parts()) > 0


def test_a_wrong_number_of_meshes_or_joints_is_reported_with_the_element() -> None:
    errors = []

    def evaluate(prop, where):
        try:
            return prop(m) if isinstance(prop, Dynamic) else prop
        except Exception as exc:  # noqa: BLE001 - the app records any error this way
            errors.append((str(exc), where))
            return None

    r = models.puma560()
    m = Model(robot=r, q=np.zeros(5))
    sync = SceneSync([robot("arm", where="lab.ejs.yaml:12:7")])
    sync.update(m, evaluate, first=True)
    assert errors == [("robot 'arm' has 6 joints, but q has 5 values", "lab.ejs.yaml:12:7")]
    m.q = np.zeros(6)
    sync.update(m, evaluate)
    assert len(errors) == 1
    np.testing.assert_allclose(sync.world.T_world("arm.link6"), r.fkine_all(np.zeros(6))[6])

    node = RobotNode("x", mesh_parts=[[]] * 2)
    sync.world.add(node)
    with pytest.raises(ValueError, match="has 6 links, but 2 mesh files were given"):
        node.set(model=r, q=np.zeros(6))


def test_the_browser_mirror_sends_only_link_poses_when_the_joints_move() -> None:
    r = models.puma560()
    m = Model(robot=r, q=np.zeros(6))
    sync, _ = scene(robot("arm"), model=m)
    handles: dict[str, MagicMock] = {}

    def add_frame(path, **kw):
        h = handles[path] = MagicMock(name=path)
        h.position, h.wxyz = kw["position"], kw["wxyz"]
        return h

    fake = MagicMock()
    fake.add_frame.side_effect = add_frame
    mirror = SceneMirror(fake)
    mirror.sync(sync.world)
    created = dict(mirror.counters)
    assert created["create"] == 1 + r.n + 1  # the robot and its n + 1 links
    meshes = fake.add_mesh_simple.call_count
    assert meshes >= r.n  # links drawn as meshes below their frames

    m.q = np.array([0.4, 0.2, -0.3, 0.5, -0.6, 0.7])
    sync.update(m)
    mirror.sync(sync.world)
    assert mirror.counters["create"] == created["create"] and mirror.counters["geometry"] == created["geometry"]
    assert fake.add_mesh_simple.call_count == meshes
    assert mirror.counters["pose"] - created["pose"] == 6  # links 1..6 moved; the base did not
    F = r.fkine_all(m.q)
    from ejsrl.robotics.transforms import q2r

    for i in range(r.n + 1):
        h = handles[f"/ejs/arm.link{i}"]
        np.testing.assert_allclose(h.position, F[i][:3, 3], atol=1e-9)
        np.testing.assert_allclose(q2r(np.asarray(h.wxyz)), F[i][:3, :3], atol=1e-9)


def test_links_are_mesh_nodes_with_flat_names() -> None:
    """The mirror places every node at /ejs/<name>: a '/' in a link name would nest it."""
    m = Model(robot=models.pa10(), q=np.zeros(7))
    sync, _ = scene(robot("arm"), model=m)
    links = [n for n in sync.world.walk() if isinstance(n, LinkNode)]
    assert len(links) == 8
    assert all("/" not in n.name and n.kind == "mesh" and n.parts() for n in links)


def test_mesh_elements_load_relative_to_the_app_folder(tmp_path, monkeypatch) -> None:
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "peg.wrl").write_text("#VRML V2.0 utf8\nShape { geometry Box { size 0.1 0.2 0.3 } }\n")
    monkeypatch.chdir(tmp_path.parent)  # not the app folder
    sync = SceneSync([Node3D(kind="mesh", name="peg", props={"file": "parts/peg.wrl", "scale": 2.0}, position=(1.0, 0.0, 0.0))],
                     base_dir=tmp_path)
    v = world_vertices(sync.world["peg"])
    np.testing.assert_allclose(v.min(axis=0), [0.9, -0.2, -0.3])
    np.testing.assert_allclose(v.max(axis=0), [1.1, 0.2, 0.3])


def test_a_hidden_robot_hides_its_links_everywhere() -> None:
    m = Model(robot=models.rrr(), q=np.zeros(3), shown=True)
    sync, wf = scene(robot("arm", visible=Dynamic(lambda m: m.shown, "shown")),
                     Node3D(kind="sphere", name="ball", props={"radius": 0.05}, position=(0.55, 0.0, 0.4)), model=m)
    n_tris = len(sync.world.triangles()[0])
    assert wf.collisions() == [("arm.link3", "ball")]  # on the forearm, 0.4 to 0.7 m out
    m.shown = False
    sync.update(m)
    assert len(sync.world.triangles()[0]) == len(sync.world["ball"].parts()[0].faces) < n_tris  # only the ball is left
    assert wf.collisions() == []
