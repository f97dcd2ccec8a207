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
from ejsrl.view._lines import rigid_fit
from ejsrl.view._scene_mirror import ROOT, SceneMirror
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


def segments(mirror: SceneMirror, name: str) -> list[np.ndarray]:
    """The line's segments (2, 3) as the browser places them: each handle's points under its pose."""
    out = []
    for g in mirror._nodes[name].geoms:
        R = q2r(np.asarray(g.wxyz, dtype=float))
        for seg in np.asarray(g.points, dtype=float):
            out.append(seg @ R.T + np.asarray(g.position, dtype=float))
    return out


def drawn(mirror: SceneMirror, name: str) -> np.ndarray:
    """The points (N, 3) of a line drawn as one segment set (a polyline), as the browser places them."""
    segs = segments(mirror, name)
    return np.vstack([np.array([s[0] for s in segs]), segs[-1][1:]])


def covers_exactly(mirror: SceneMirror, name: str, p0: np.ndarray, p1: np.ndarray) -> bool:
    """Whether the drawn pieces of a two-point line lie on the segment p0-p1 and cover all of it, no more."""
    return covers_segment(segments(mirror, name), p0, p1)


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


def test_a_swinging_rod_is_sent_as_poses_in_step_with_its_bob(mirrored):
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
        # the rod's pieces are moved by poses, as the bob is: no points are sent
        for piece in ("g0", "g1"):
            assert kinds(sent, f"{ROOT}/rod/{piece}") <= {"SetPositionMessage", "SetOrientationMessage"}
        assert "SetOrientationMessage" in kinds(sent, f"{ROOT}/rod/g1")
        assert "SetPositionMessage" in kinds(sent, f"{ROOT}/bob")
        assert covers_exactly(mirror, "rod", np.zeros(3), end)


def test_a_stretching_spring_is_sent_as_poses_until_its_length_leaves_the_pieces_band(mirrored):
    world, mirror, sent = mirrored
    spring = world.add(Line("spring", points=np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])))
    mirror.sync(world)
    sent_points = 0
    for k, length in enumerate(np.linspace(1.0, 3.0, 21)[1:]):  # stretches threefold while turning
        a = 0.1 * k
        end = length * np.array([np.cos(a), np.sin(a), 0.0])
        spring.set(points=np.array([[0.0, 0.0, 0.0], end]))
        sent.clear()
        mirror.sync(world)
        got = kinds(sent, f"{ROOT}/spring/g0") | kinds(sent, f"{ROOT}/spring/g1")
        assert "RemoveSceneNodeMessage" not in got and "LineSegmentsMessage" not in got  # never rebuilt
        sent_points += "SceneNodeUpdateMessage" in got
        if "SceneNodeUpdateMessage" not in got:  # a pose frame: exactly the new segment
            assert covers_exactly(mirror, "spring", np.zeros(3), end)
    # points only when the length leaves [h, 2h]: past 4/3 (h = 1/1.5 when made), then while it
    # is within twice the shortest (1) at each new longest the band has not room for (h the
    # middle, by ratio, of longest / 2 and shortest), then once past 2 (h = 0.75 * 2.1): a
    # quarter of the frames of a steady stretch, none once it stays in its band
    assert sent_points == 5, sent_points


def test_a_spring_oscillating_within_twice_its_shortest_length_is_sent_as_poses_once_it_has_swung(mirrored):
    world, mirror, sent = mirrored
    spring = world.add(Line("spring", points=np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -0.7]])))  # made at its shortest
    mirror.sync(world)
    frames_with_points = []
    for k, t in enumerate(np.arange(0.0, 6.0, 1 / 30)):
        length = 1.0 - 0.3 * np.cos(7 * t)  # from 0.7 (h = 0.47) up to 1.3: within twice the shortest
        end = np.array([0.3 * np.sin(2 * t), 0.0, -length])
        spring.set(points=np.array([[0.0, 0.0, 0.0], end]))
        sent.clear()
        mirror.sync(world)
        got = kinds(sent, f"{ROOT}/spring/g0") | kinds(sent, f"{ROOT}/spring/g1")
        if "SceneNodeUpdateMessage" in got:
            frames_with_points.append(k)
        else:
            assert covers_exactly(mirror, "spring", np.zeros(3), end)
    assert 1 <= len(frames_with_points) <= 3 and frames_with_points[-1] < 30, frames_with_points  # within its first swing


def covers_segment(segs: list[np.ndarray], p0: np.ndarray, p1: np.ndarray) -> bool:
    """Whether the drawn segments ``segs`` (each (2, 3)) lie on the segment p0-p1 and cover all of it, no more."""
    length = float(np.linalg.norm(p1 - p0))
    d = (p1 - p0) / length
    spans = []
    for seg in segs:
        rel = seg - p0
        if np.abs(rel - np.outer(rel @ d, d)).max() > 1e-6:  # off the line
            return False
        spans.append(sorted(rel @ d))
    spans.sort()
    if spans[0][0] < -1e-6 or max(s[1] for s in spans) > length + 1e-6 or abs(spans[0][0]) > 1e-6:
        return False
    reach = spans[0][1]
    for lo, hi in spans[1:]:
        if lo > reach + 1e-6:
            return False  # a gap
        reach = max(reach, hi)
    return abs(reach - length) < 1e-6


def pieces_cover(mirror: SceneMirror, name: str, pts: np.ndarray, first_geom: int = 0) -> bool:
    """Whether a line drawn as pieces (two geometry handles a segment, from ``first_geom`` on)
    covers each segment of ``pts`` (N, 3) exactly, as the browser places them."""
    geoms = mirror._nodes[name].geoms[first_geom:]
    for i in range(len(pts) - 1):
        segs = []
        for g in geoms[2 * i : 2 * i + 2]:
            assert g.visible
            R = q2r(np.asarray(g.wxyz, dtype=float))
            segs += [seg @ R.T + np.asarray(g.position, dtype=float) for seg in np.asarray(g.points, dtype=float)]
        if not covers_segment(segs, pts[i], pts[i + 1]):
            return False
    return True


def zigzag(a: float, b: float, coils: int = 6, amp: float = 0.05) -> np.ndarray:
    """A zigzag spring (2 coils + 3 points) from (a, 0, 0) to (b, 0, 0), across z."""
    x = np.linspace(a, b, 2 * coils + 1)
    z = np.zeros_like(x)
    z[1:-1:2], z[2:-1:2] = amp, -amp
    return np.column_stack([x, np.zeros_like(x), z])


def test_a_line_that_turns_is_a_pose_and_one_whose_shape_changes_is_drawn_anew_as_pieces(mirrored):
    world, mirror, sent = mirrored
    zig = world.add(Line("zigzag", points=np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]])))
    mirror.sync(world)
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    zig.set(points=np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]) @ R.T + [0.5, 0.0, 0.0])  # turned: a pose
    sent.clear()
    mirror.sync(world)
    assert kinds(sent, f"{ROOT}/zigzag/g0") == {"SetPositionMessage", "SetOrientationMessage"}
    assert len(mirror._nodes["zigzag"].geoms) == 1
    new = np.array([[0.0, 0.0, 0.0], [0.0, 1.5, 0.0], [0.3, 1.5, 0.0], [0.3, 2.0, 1.0]])
    zig.set(points=new)  # grown: drawn anew, as pieces (two a segment)
    mirror.sync(world)
    assert len(mirror._nodes["zigzag"].geoms) == 6
    assert pieces_cover(mirror, "zigzag", new)


def test_a_zigzag_spring_that_stretches_is_sent_as_poses(mirrored):
    """A spring of 12 segments between a wall and a moving plate: after it first changes shape
    (drawn anew as pieces), every frame is poses only and the pieces cover every segment exactly."""
    world, mirror, sent = mirrored
    spring = world.add(Line("spring", points=zigzag(0.0, 1.0)))
    mirror.sync(world)
    frames_with_points = 0
    for k, t in enumerate(np.arange(1 / 30, 4.0, 1 / 30)):
        pts = zigzag(0.0, 1.0 + 0.3 * np.sin(9 * t))
        spring.set(points=pts)
        sent.clear()
        mirror.sync(world)
        assert pieces_cover(mirror, "spring", pts), k
        if k == 0:
            continue  # drawn anew
        got = set().union(*(kinds(sent, f"{ROOT}/spring/g{i}") for i in range(24)))
        assert "LineSegmentsMessage" not in got and "RemoveSceneNodeMessage" not in got, k
        frames_with_points += "SceneNodeUpdateMessage" in got
    assert frames_with_points == 0, frames_with_points  # the zigzag's segments change length by 1.1x at most


def test_a_line_of_more_segments_than_pieces_are_made_for_sends_its_points(mirrored):
    from ejsrl.view._lines import MAX_PIECE_SEGMENTS

    world, mirror, sent = mirrored
    long = world.add(Line("long", points=zigzag(0.0, 1.0, coils=MAX_PIECE_SEGMENTS)))  # twice as many segments
    mirror.sync(world)
    new = zigzag(0.0, 1.2, coils=MAX_PIECE_SEGMENTS)
    long.set(points=new)
    sent.clear()
    mirror.sync(world)
    assert kinds(sent, f"{ROOT}/long/g0") == {"SceneNodeUpdateMessage"}
    assert len(mirror._nodes["long"].geoms) == 1
    assert np.allclose(drawn(mirror, "long"), new, atol=1e-6)


def test_a_trail_s_newest_segments_are_pieces_moved_by_poses(mirrored):
    """A trail on an ellipse (its shape changes as it goes): its segment set gets the points, and
    pieces over its newest two segments, moved by poses once their lengths are known, reach the
    newest point in the same update."""
    from ejsrl.view._lines import TRAIL_HEAD
    from ejsrl.world.scene import Trail

    world, mirror, sent = mirrored
    trail = world.add(Trail("path", max_points=20))
    mirror.sync(world)
    pose_only = 0
    for k, t in enumerate(np.arange(0.0, 3.0, 1 / 30)):
        p = np.array([0.45 * np.cos(7 * t), 0.0, 0.25 * np.sin(7 * t)])
        trail.push(p)
        sent.clear()
        mirror.sync(world)
        pts = trail.props["points"]
        geoms = mirror._nodes["path"].geoms
        assert len(geoms) == 1 + 2 * TRAIL_HEAD
        if len(pts) >= TRAIL_HEAD + 1:
            assert pieces_cover(mirror, "path", pts[-TRAIL_HEAD - 1 :], first_geom=1), k
            g = geoms[0]  # the segment set: every point, the newest among them
            assert np.allclose(np.asarray(g.points, dtype=float)[-1, 1] @ q2r(np.asarray(g.wxyz, dtype=float)).T + g.position, p, atol=1e-6)
            heads = set().union(*(kinds(sent, f"{ROOT}/path/g{i}") for i in range(1, 1 + 2 * TRAIL_HEAD)))
            pose_only += heads <= {"SetPositionMessage", "SetOrientationMessage", "SetSceneNodeVisibilityMessage"}
        else:  # fewer segments than pieces: the ones without a segment are hidden
            assert sum(g.visible for g in geoms[1:]) == 2 * max(0, len(pts) - 1), k
    print("head frames sent as poses alone:", pose_only)
    assert pose_only >= 80, pose_only  # of 88 frames with a full head: the speed on the ellipse varies 1.8-fold


def test_a_two_point_line_that_gets_a_third_point_is_drawn_anew(mirrored):
    world, mirror, sent = mirrored
    line = world.add(Line("l", points=np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])))
    mirror.sync(world)
    pts = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]])
    line.set(points=pts)
    mirror.sync(world)
    assert len(mirror._nodes["l"].geoms) == 4  # its shape changed: pieces, two a segment
    assert pieces_cover(mirror, "l", pts)


def test_the_masses_of_a_chain_are_posed_points_once_they_move_apart(mirrored):
    """A point cloud beside a line drawn as pieces keeps step with it: once its points move apart
    (not as a whole) each is its own posed point, and every frame after sends positions alone."""
    from ejsrl.world.scene import Points

    world, mirror, sent = mirrored
    x = np.arange(1, 21) * 0.1
    masses = world.add(Points("masses", points=np.column_stack([x, 0 * x, 0 * x]), size=0.04))
    mirror.sync(world)
    for k, t in enumerate(np.arange(0.0, 1.0, 1 / 30)):
        pts = np.column_stack([x, 0 * x, 0.05 * np.sin(np.pi * x / 3.1) * np.cos(5 * t + 0.1)])
        masses.set(points=pts)
        sent.clear()
        mirror.sync(world)
        geoms = mirror._nodes["masses"].geoms
        assert len(geoms) == 20
        assert np.allclose([np.asarray(g.position) + np.asarray(g.points)[0] for g in geoms], pts, atol=1e-6)
        if k:
            got = set().union(*(kinds(sent, f"{ROOT}/masses/g{i}") for i in range(20)))
            assert got == {"SetPositionMessage"}, got
    # a cloud moved as a whole stays one cloud, sent as a pose
    cloud = world.add(Points("cloud", points=np.random.default_rng(1).normal(size=(200, 3)), size=0.01))
    mirror.sync(world)
    cloud.set(T_parent_local=np.eye(4))
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    cloud.set(points=cloud.props["points"] @ R.T + 1.0)
    sent.clear()
    mirror.sync(world)
    assert kinds(sent, f"{ROOT}/cloud/g0") == {"SetPositionMessage", "SetOrientationMessage"}


def test_an_arrow_that_changes_length_is_moved_by_poses(mirrored):
    """A velocity arrow that grows, shrinks and turns: once its shaft's pieces are made for the
    lengths it has, each frame moves its parts (poses) and re-sends no mesh; what the browser
    draws (each part's vertices under its pose) reaches the arrow's tip and starts at its tail."""
    from ejsrl.world.scene import Arrow

    world, mirror, sent = mirrored
    arrow = world.add(Arrow("v", start=(0.0, 0.0, 0.0), vector=(1.0, 0.0, 0.0), width=0.02))
    mirror.sync(world)
    rebuilt = 0
    for k, t in enumerate(np.arange(1 / 30, 4.0, 1 / 30)):
        length = 0.8 + 0.22 * np.sin(6 * t)  # 0.58 to 1.02 m: at least 20 widths (the head stays), the shaft within 2x
        vec = length * np.array([np.cos(t), np.sin(t), 0.0])
        start = np.array([0.1 * t, 0.0, 0.0])
        arrow.set(start=start, vector=vec)
        sent.clear()
        mirror.sync(world)
        names = {m.name for m in sent if hasattr(m, "name")}
        rebuilt += any(type(m).__name__ == "MeshMessage" for m in sent)
        # the drawn arrow: its vertices, as placed, span exactly from the tail to the tip along vec
        along = []
        for g in mirror._nodes["v"].geoms:
            R = q2r(np.asarray(g.wxyz, dtype=float))
            v = np.asarray(g.vertices, dtype=float) @ R.T + np.asarray(g.position, dtype=float)
            along.append(v @ vec / length - start @ vec / length)
            across = v - np.outer(v @ vec / length, vec / length) - (start - np.outer(start @ vec / length, vec / length)[0])
            assert np.abs(across).max() <= 2.5 * 0.01 + 1e-6, k  # within the head's radius of the axis
        lo, hi = min(a.min() for a in along), max(a.max() for a in along)
        assert abs(lo) < 1e-5 and abs(hi - length) < 1e-5, (k, lo, hi, length)
        # the shaft is covered: the two pieces meet or overlap
        shaft = sorted((a.min(), a.max()) for a in along[1:])
        assert shaft[0][1] >= shaft[1][0] - 1e-6, k
        assert names <= {f"{ROOT}/v/g{i}" for i in range(3)} | {f"{ROOT}/v"}, names
    assert rebuilt <= 3, rebuilt  # the shaft's pieces made again while the lengths seen grow, then none


def test_a_line_with_a_nan_point_leaves_the_scene_going(mirrored):
    """A point that is not a number (an expression divided by zero) is sent as it is, and the
    line's next finite points are drawn again (its rigid fit used to fail on the nan it kept,
    and with it every later frame of the whole scene)."""
    world, mirror, sent = mirrored
    line = world.add(Line("l", points=np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]] * 10)))  # 29 segments
    mirror.sync(world)
    bad = line.props["points"].copy()
    bad[1] = np.nan
    line.set(points=bad)
    mirror.sync(world)
    good = np.column_stack([np.arange(30.0), np.zeros(30), np.zeros(30)])
    line.set(points=good)
    mirror.sync(world)
    assert np.allclose(drawn(mirror, "l"), good, atol=1e-6)
