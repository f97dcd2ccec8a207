"""The 3D view's camera worked out from the world's ``view`` node and ``set_view()``, without a browser.

Poses are checked against what they mean, worked out here independently: a preset looks
along its axis with its up on screen and keeps every framed point inside the picture (a
pinhole projection written in this file); ``set_view`` replaces what it gives and keeps the
rest; Restore view drops it; a followed object is the look-at point of every frame.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ejsrl.view._camera import ViewCamera, resolve
from ejsrl.view._framing import VIEW_ASPECT, VIEW_FOV, framed_points
from ejsrl.world.scene import NODE_KINDS, Sphere, World
from ejsrl.world.view3d import drop_commanded, set_view, view_node


class FakeCamera:
    """A client's camera as viser's handle holds it: what was last set."""

    def __init__(self) -> None:
        self.position = np.array([3.0, 3.0, 3.0])
        self.look_at = np.zeros(3)
        self.up_direction = np.array([0.0, 0.0, 1.0])
        self.fov = VIEW_FOV
        self.sets = 0

    def __setattr__(self, key, value):
        if key != "sets" and hasattr(self, "sets"):
            object.__setattr__(self, "sets", self.sets + 1)
        object.__setattr__(self, key, np.asarray(value, dtype=float) if key != "fov" else float(value))


class App:
    """What ViewCamera needs of an app: its world and its view elements."""

    def __init__(self, world: World) -> None:
        self.world = world
        self.view: list = []


def a_world(**view_props) -> World:
    w = World()
    for name, p in (("a", (0.0, 0.0, 0.0)), ("b", (1.0, 0.0, -1.0)), ("c", (-0.5, 0.2, 0.5))):
        T = np.eye(4)
        T[:3, 3] = p
        w.add(Sphere(name, radius=0.1, T_parent_local=T))
    if view_props is not None:
        w.add(NODE_KINDS["view"]("view1", **view_props))
    return w


def inside(points: np.ndarray, position, target, up, fov: float, aspect: float) -> bool:
    f = (target - position) / np.linalg.norm(target - position)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    rel = points - position
    depth = rel @ f
    x, y = (rel @ r) / depth, (rel @ u) / depth
    return bool(np.all(depth > 0) and np.all(np.abs(y) <= math.tan(fov / 2) + 1e-9) and np.all(np.abs(x) <= math.tan(fov / 2) * aspect + 1e-9))


@pytest.mark.parametrize(
    ("preset", "looks_along", "up"),
    [("front", (0, 1, 0), (0, 0, 1)), ("xz", (0, 1, 0), (0, 0, 1)), ("top", (0, 0, -1), (0, 1, 0)), ("xy", (0, 0, -1), (0, 1, 0)),
     ("right", (-1, 0, 0), (0, 0, 1)), ("left", (1, 0, 0), (0, 0, 1)), ("back", (0, -1, 0), (0, 0, 1)), ("bottom", (0, 0, 1), (0, 1, 0))],
)
def test_a_preset_looks_square_on_and_frames_the_scene(preset, looks_along, up):
    w = a_world(preset=preset)
    pose = resolve(w, view_node(w), spec_position=False)
    d = pose.look_at - pose.position
    assert np.allclose(d / np.linalg.norm(d), looks_along, atol=1e-12)
    assert np.allclose(pose.up, up)
    assert pose.fov == pytest.approx(VIEW_FOV)
    assert inside(framed_points(w), pose.position, pose.look_at, pose.up, pose.fov, VIEW_ASPECT)
    # and not from far away: a point of the framed box touches the picture's edge (5 % margin)
    tight = resolve(w, view_node(w), spec_position=False)
    assert not inside(framed_points(w), tight.look_at + (tight.position - tight.look_at) * 0.9, tight.look_at, tight.up,
                      tight.fov, VIEW_ASPECT)


def test_the_spec_position_target_up_and_fov_are_the_camera():
    w = a_world(target=(0.5, 0.0, 0.0), up=(0.0, 0.0, 1.0), fov=40.0)
    view_node(w).set(T_parent_local=np.array([[1, 0, 0, 0.5], [0, 1, 0, -3.0], [0, 0, 1, 0.2], [0, 0, 0, 1.0]]))
    pose = resolve(w, view_node(w), spec_position=True)
    assert np.allclose(pose.position, [0.5, -3.0, 0.2]) and np.allclose(pose.look_at, [0.5, 0, 0])
    assert pose.fov == pytest.approx(math.radians(40))


def test_set_view_replaces_what_it_gives_and_restore_view_forgets_it():
    w = a_world(preset="front", fov=50.0)
    node = view_node(w)
    set_view(w, target=[0, 0, 1])
    pose = resolve(w, node, spec_position=False)
    assert np.allclose(pose.look_at, [0, 0, 1]) and pose.fov == pytest.approx(math.radians(50))
    d = pose.look_at - pose.position
    assert np.allclose(d / np.linalg.norm(d), [0, 1, 0])  # still the spec's preset
    set_view(w, position=[2, 0, 1])  # a position replaces the preset ...
    pose = resolve(w, node, spec_position=False)
    assert np.allclose(pose.position, [2, 0, 1]) and np.allclose(pose.look_at, [0, 0, 1])
    set_view(w, preset="top")  # ... and a preset the position
    pose = resolve(w, node, spec_position=False)
    assert np.allclose((pose.look_at - pose.position)[:2], 0) and np.allclose(pose.look_at, [0, 0, 1])
    drop_commanded(w)
    pose = resolve(w, node, spec_position=False)
    d = pose.look_at - pose.position
    assert np.allclose(d / np.linalg.norm(d), [0, 1, 0]) and not np.allclose(pose.look_at, [0, 0, 1])


def test_set_view_without_a_view_element_makes_one_and_refuses_bad_values():
    w = a_world()
    w.remove("view1")
    with pytest.raises(ValueError, match="did you mean 'front'"):
        set_view(w, preset="fornt")
    with pytest.raises(KeyError, match="did you mean 'a'"):
        set_view(w, follow="aa")
    with pytest.raises(ValueError, match="1 to 170"):
        set_view(w, fov=180)
    assert view_node(w) is None  # nothing asked yet
    set_view(w, preset="xy", follow="b")
    pose = resolve(w, view_node(w), spec_position=False)
    assert np.allclose(pose.look_at, [1.0, 0.0, -1.0])


def test_a_followed_object_is_looked_at_every_frame_with_or_without_its_offset():
    for offset in (False, True):
        w = a_world(follow="b", follow_offset=offset, preset="front")
        cameras = [FakeCamera(), FakeCamera()]
        view = ViewCamera(App(w))
        view.on_frame(cameras)  # the first frame shows the whole camera
        start = cameras[0].position.copy()
        assert np.allclose(cameras[0].look_at, [1, 0, -1]) and np.allclose(cameras[1].look_at, [1, 0, -1])
        for k in range(1, 5):
            T = np.eye(4)
            T[:3, 3] = (1.0 + 0.3 * k, 0.0, -1.0 + 0.1 * k)
            w["b"].set(T_parent_local=T)
            view.on_frame(cameras)
            for cam in cameras:
                assert np.allclose(cam.look_at, T[:3, 3])
                if offset:  # moves along, keeping its offset
                    assert np.allclose(cam.position - cam.look_at, start - np.array([1, 0, -1]))
                else:  # stays, turning to watch
                    assert np.allclose(cam.position, start)


def test_without_a_view_the_first_view_is_framed_as_before_and_left_alone():
    from ejsrl.view._framing import framing_view

    w = a_world()
    w.remove("view1")
    cam = FakeCamera()
    view = ViewCamera(App(w))
    view.show([cam])
    position, look_at = framing_view(framed_points(w))
    assert np.allclose(cam.position, position) and np.allclose(cam.look_at, look_at)
    before = cam.sets
    view.on_frame([cam])
    assert cam.sets == before  # nothing asked, nothing set: the user's view is the user's


def test_a_view_whose_values_change_is_shown_again_and_only_then():
    w = a_world(preset="front")
    cam = FakeCamera()
    view = ViewCamera(App(w))
    view.on_frame([cam])
    before = cam.sets
    view.on_frame([cam])
    assert cam.sets == before
    view_node(w).set(fov=30.0)  # an expression's new value, as the scene binding writes it
    view.on_frame([cam])
    assert cam.fov == pytest.approx(math.radians(30))


def test_the_restore_view_button_is_in_the_panel_of_a_lab_with_a_scene_only():
    from ejsrl.app import App, AppMeta, SimConfig
    from ejsrl.view.elements import Dynamic, Label
    from ejsrl.view.viser_view import ViserView, make_server
    from testkit.browser_lab import Pendulum, make_app

    server, _url = make_server("127.0.0.1", 0, banner=False)
    try:
        with_scene = ViserView(make_app(), server)
        assert with_scene.reset_view_button is not None and with_scene.reset_view_button.label == "Restore view"
        plain = App(Pendulum, [Label(Dynamic(lambda m: f"t = {m.t}", "f't = {t}'"))], sim=SimConfig(fps=30.0),
                    meta=AppMeta(title="No scene", description="", author="Tests", spec="p.ejs.yaml"))
        assert ViserView(plain, server).reset_view_button is None
    finally:
        server.stop()
