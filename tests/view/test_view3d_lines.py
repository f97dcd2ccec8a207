"""A line that moves as a whole reaches the browser as a pose, like the spheres beside it.

viser's client draws a pose in the frame that receives it but a line's new points a frame
later (see ``ejsrl.view._scene_mirror``): a rod sent as points trailed its bob. These tests
check, message by message on a real viser server, that a rigidly moved line is sent as the
pose of its geometry, that a line whose shape changes is sent as points, and that in both
cases what the browser draws (the geometry's points under its pose) is where the model put
the line.
"""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.robotics.transforms import q2r, rpy2r
from ejsrl.view._scene_mirror import ROOT, SceneMirror, rigid_fit
from ejsrl.view.viser_view import make_server
from ejsrl.world.scene import Line, Sphere, World


@pytest.fixture
def mirrored():
    server, _url = make_server("127.0.0.1", 0, banner=False)
    sent: list = []
    queue = server._websock_server.queue_message

    def counting(message):
        sent.append(message)
        return queue(message)

    server._websock_server.queue_message = counting
    world = World()
    mirror = SceneMirror(server.scene)
    yield world, mirror, sent
    server.stop()


def drawn(mirror: SceneMirror, name: str) -> np.ndarray:
    """The line's points as the browser places them: its segments' points under the geometry's pose, (N, 3)."""
    m = mirror._nodes[name]
    g = m.geoms[0]
    segs = np.asarray(g.points, dtype=float)
    local = np.vstack([segs[:, 0], segs[-1:, 1]])
    R = q2r(np.asarray(g.wxyz, dtype=float))
    return local @ R.T + np.asarray(g.position, dtype=float)


def kinds(sent: list, name: str) -> set[str]:
    return {type(msg).__name__ for msg in sent if getattr(msg, "name", None) == name}


def test_rigid_fit_finds_a_known_motion_and_refuses_a_stretch():
    rng = np.random.default_rng(4)
    ref = rng.normal(size=(6, 3))
    R, t = rpy2r([0.3, -1.1, 2.0]), np.array([0.5, -2.0, 1.0])
    T = rigid_fit(ref, ref @ R.T + t)
    assert T is not None
    assert np.allclose(T[:3, :3], R, atol=1e-12) and np.allclose(T[:3, 3], t, atol=1e-12)
    stretched = ref.copy()
    stretched[0] *= 1.001
    assert rigid_fit(ref, stretched @ R.T + t) is None
    assert rigid_fit(ref, (ref @ R.T)[:5]) is None  # a point fewer
    assert rigid_fit(ref[:1], ref[:1]) is None  # one point has no shape to fit


def test_a_swinging_rod_is_sent_as_a_pose_in_step_with_its_bob(mirrored):
    world, mirror, sent = mirrored
    rod = world.add(Line("rod", points=np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0]])))
    bob = world.add(Sphere("bob", radius=0.05, T_parent_local=np.eye(4)))
    mirror.sync(world)
    for theta in np.linspace(0.1, 1.2, 12):
        end = np.array([np.sin(theta), 0.0, -np.cos(theta)])
        rod.set(points=np.array([[0.0, 0.0, 0.0], end]))
        T = np.eye(4)
        T[:3, 3] = end
        bob.set(T_parent_local=T)
        sent.clear()
        mirror.sync(world)
        # the rod's geometry is moved by a pose, as the bob is: no points are sent
        assert kinds(sent, f"{ROOT}/rod/g0") <= {"SetPositionMessage", "SetOrientationMessage"}
        assert "SetOrientationMessage" in kinds(sent, f"{ROOT}/rod/g0")
        assert "SetPositionMessage" in kinds(sent, f"{ROOT}/bob")
        assert np.allclose(drawn(mirror, "rod"), [[0.0, 0.0, 0.0], end], atol=1e-6)


def test_a_line_whose_shape_changes_is_sent_as_points(mirrored):
    world, mirror, sent = mirrored
    spring = world.add(Line("spring", points=np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])))
    mirror.sync(world)
    spring.set(points=np.array([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]))  # turned: a pose
    mirror.sync(world)
    sent.clear()
    spring.set(points=np.array([[0.0, 0.0, 0.0], [0.0, 1.5, 0.0], [0.3, 1.5, 0.0]]))  # grown: points
    mirror.sync(world)
    assert kinds(sent, f"{ROOT}/spring/g0") == {"SceneNodeUpdateMessage"}
    assert np.allclose(drawn(mirror, "spring"), [[0.0, 0.0, 0.0], [0.0, 1.5, 0.0], [0.3, 1.5, 0.0]], atol=1e-6)
