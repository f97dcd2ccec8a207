"""The world is mirrored into viser, and a frame sends only what changed."""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.robotics.transforms import q2r
from ejsrl.view._scene_mirror import ROOT, SceneMirror
from ejsrl.world.scene import Box, Group, Line, MeshNode, Node, Part, Points, Sphere, Text3D, World


def handle(served, name):
    return served.view.scene._nodes[name]


def scene_messages(served):
    """Scene messages (named nodes) queued since the test last cleared ``served.sent``."""
    return [m for m in served.sent if hasattr(m, "name") and type(m).__name__ != "GuiUpdateMessage"]


def test_every_world_node_is_in_the_viser_scene(served):
    nodes = served.server.scene._handle_from_node_name
    for name in ("arm", "block", "ball", "origin", "post", "path", "handle"):
        assert f"{ROOT}/{name}" in nodes, name
    block = handle(served, "block")
    assert block.geoms[0].dimensions == pytest.approx((0.2, 0.2, 0.2))
    assert block.geoms[0].color == (255, 0, 0)
    # the child's world pose: group at x (0) + local offset z 0.5
    assert handle(served, "block").frame.position == pytest.approx((0.0, 0.0, 0.5))


def test_a_frame_with_no_change_sends_no_scene_messages(served):
    served.app.frame()
    served.sent.clear()
    served.app.frame()
    assert scene_messages(served) == []


def test_moving_a_group_sends_only_the_poses_that_changed(served):
    served.app.frame()
    served.sent.clear()
    before = dict(served.view.scene.counters)
    served.app.model.t = 1.0
    served.app.step_once()  # t -> 1.1, x = sin(1.1)
    served.app.frame()
    moved = {m.name for m in served.sent if type(m).__name__ == "SetPositionMessage"}
    # and the pieces over the trail's newest segments (ejsrl.view._lines), which follow its point
    trail_head = {name for name in moved if name.startswith(f"{ROOT}/path/g")}
    assert moved - trail_head == {f"{ROOT}/arm", f"{ROOT}/block"}
    assert served.view.scene.counters["create"] == before["create"]
    x = np.sin(1.1)
    assert handle(served, "block").frame.position == pytest.approx((x, 0.0, 0.5))


def test_a_shape_change_updates_the_box_in_place(served):
    box_handle = handle(served, "block").geoms[0]
    served.app.model.size = 0.4
    served.app.frame()
    assert handle(served, "block").geoms[0] is box_handle
    assert box_handle.dimensions == pytest.approx((0.4, 0.4, 0.4))


def test_a_colour_change_is_sent_as_a_prop(served):
    served.app.model.on = False
    served.app.frame()
    assert handle(served, "block").geoms[0].color == (0, 0, 255)


def test_trails_grow_and_are_cleared_on_reset(served):
    served.app.model.L = 1.0
    served.app.play()
    for _ in range(5):
        served.app.frame()
    trail = handle(served, "path").geoms[0]
    assert trail.visible and trail.points.shape == (5, 2, 3)  # 6 points (first from init)
    served.app.reset()
    served.app.frame()
    assert not trail.visible


def test_dragging_a_gizmo_calls_apply_gizmo(served):
    gizmo = handle(served, "handle").frame
    gizmo._impl.position = np.array([0.5, 0.0, 0.0])
    gizmo._impl.wxyz = np.array([1.0, 0.0, 0.0, 0.0])

    class Event:
        phase = "update"

    for cb in gizmo._impl_aux.update_cb:
        cb(Event())
    assert served.app.model.k == pytest.approx(2.5)  # the element's set: k = T[0, 3] + 2
    # while dragging, the server's pose (identity here) does not snap the gizmo back
    served.app.frame()
    assert gizmo.position == pytest.approx((0.5, 0.0, 0.0))
    served.view.scene._dragging["handle"] = 0.0  # the drag ended long ago
    served.app.frame()
    assert gizmo.position == pytest.approx((0.0, 0.0, 0.0))


# -- the mirror on its own world -------------------------------------------------------


@pytest.fixture
def scene(served):
    return served.server.scene


def test_hidden_parents_hide_their_children(scene):
    w = World()
    g = w.add(Group("g"))
    w.add(Sphere("s", radius=0.1), g)
    mirror = SceneMirror(scene)
    mirror.sync(w)
    assert mirror._nodes["s"].frame.visible
    g.set(visible=False)
    mirror.sync(w)
    assert not mirror._nodes["s"].frame.visible and not mirror._nodes["g"].frame.visible


def test_points_lines_and_text_update_in_place(scene):
    w = World()
    p = w.add(Points("p", points=np.zeros((3, 3)), size=0.05))
    line = w.add(Line("l", points=np.zeros((2, 3))))
    t = w.add(Text3D("t", text="a"))
    mirror = SceneMirror(scene)
    mirror.sync(w)
    handles = [mirror._nodes[n].geoms[0] for n in "plt"]
    p.set(points=np.ones((7, 3)))
    line.set(points=np.arange(210.0).reshape(70, 3))  # (a line of up to 24 segments would be drawn anew as pieces)
    t.set(text="b")
    mirror.sync(w)
    assert [mirror._nodes[n].geoms[0] for n in "plt"] == handles
    assert handles[0].points.shape == (7, 3)
    assert handles[1].points.shape == (69, 2, 3)
    assert handles[2].text == "b"
    assert mirror.counters["create"] == 3


class Linkage(Node):
    """A robot-like node: fixed link meshes that move with ``q``."""

    kind = "linkage"
    GEOMETRY_PROPS = ("q",)
    DEFAULTS = {"q": 0.0}
    _cube = Box("c", size=(0.1, 0.1, 0.5)).parts()[0]

    def _make_parts(self):
        T = np.eye(4)
        T[:3, 3] = (self.props["q"], 0.0, 0.0)
        return [Part(self._cube.vertices, self._cube.faces, (0.2, 0.3, 0.4), T_node_part=T)]


def test_nodes_whose_parts_only_move_send_poses_not_meshes(scene):
    w = World()
    link = w.add(Linkage("robot"))
    mirror = SceneMirror(scene)
    mirror.sync(w)
    mesh = mirror._nodes["robot"].geoms[0]
    assert mesh.color == (51, 77, 102)
    link.set(q=0.7)
    mirror.sync(w)
    assert mirror._nodes["robot"].geoms[0] is mesh
    assert mesh.position == pytest.approx((0.7, 0.0, 0.0))
    assert mirror.counters["part_poses"] == 1 and mirror.counters["geometry"] == 0


def test_meshes_with_face_colours_are_split_by_colour(scene):
    cube = Box("c").parts()[0]
    face_rgb = np.zeros((12, 3))
    face_rgb[6:] = (1.0, 1.0, 0.0)
    w = World()
    w.add(MeshNode("m", mesh_parts=(Part(cube.vertices, cube.faces, face_rgb=face_rgb),)))
    mirror = SceneMirror(scene)
    mirror.sync(w)
    colours = sorted(h.color for h in mirror._nodes["m"].geoms)
    assert colours == [(0, 0, 0), (255, 255, 0)]
    assert sum(len(h.faces) for h in mirror._nodes["m"].geoms) == 12


def test_removed_nodes_leave_the_scene(scene):
    w = World()
    w.add(Sphere("s"))
    mirror = SceneMirror(scene)
    mirror.sync(w)
    del w.nodes["s"]
    w.roots.clear()
    mirror.sync(w)
    assert "s" not in mirror._nodes and f"{ROOT}/s" not in scene._handle_from_node_name


def test_poses_are_sent_as_wxyz(scene):
    w = World()
    T = np.eye(4)
    T[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]  # 90 degrees about z
    w.add(Box("b", T_parent_local=T))
    mirror = SceneMirror(scene)
    mirror.sync(w)
    wxyz = mirror._nodes["b"].frame.wxyz
    assert wxyz == pytest.approx((np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)))
    assert q2r(wxyz) == pytest.approx(T[:3, :3])
