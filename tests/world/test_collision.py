"""Collision checking against analytic distances, brute-force references and LP feasibility."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import linprog, minimize
from scipy.spatial.transform import Rotation

from ejsrl.world import CollisionShape, CollisionWorld, World, shape_from_node
from ejsrl.world.collision import distance, intersects
from ejsrl.world.scene import Box, Cylinder, Group, MeshNode, Part, Sphere

S2 = math.sqrt(2)


def T(xyz=(0, 0, 0), rotvec=(0, 0, 0)) -> np.ndarray:
    M = np.eye(4)
    M[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    M[:3, 3] = xyz
    return M


def rz(angle: float) -> tuple[float, float, float]:
    return (0.0, 0.0, angle)


# -- analytic distances, one per pair type ----------------------------------------------------------
ANALYTIC = [
    # (shape a, pose a, shape b, pose b, expected distance)
    ("sphere-sphere", CollisionShape.sphere(0.3), T((1, 2, 3)), CollisionShape.sphere(0.2), T((1, 2, 3) + np.array([0.6, 0.8, 0.0])), 0.5),
    ("sphere-box face", CollisionShape.sphere(0.1), T((0, 0, 1)), CollisionShape.box([1, 1, 1]), T(), 0.4),
    ("sphere-box corner", CollisionShape.sphere(0.1), T((1, 1, 1)), CollisionShape.box([1, 1, 1]), T(), math.sqrt(3) * 0.5 - 0.1),
    ("capsule-capsule crossed", CollisionShape.capsule((-1, 0, 0), (1, 0, 0), 0.1), T(), CollisionShape.capsule((0, -1, 0), (0, 1, 0), 0.05), T((0, 0, 0.5)), 0.35),
    ("capsule-capsule parallel", CollisionShape.capsule((0, 0, 0), (0, 0, 1), 0.1), T((0.3, 0, 0.5)), CollisionShape.capsule((0, 0, 0), (0, 0, 1), 0.1), T(), 0.1),
    ("capsule-sphere beyond end", CollisionShape.capsule((0, 0, 0), (0, 0, 1), 0.1), T(), CollisionShape.sphere(0.2), T((0, 0.3, 1.4)), 0.2),
    ("capsule-box face", CollisionShape.capsule((0, 0, -2), (0, 0, 2), 0.05), T((0.6, 0.1, 0)), CollisionShape.box([1, 1, 1]), T(), 0.05),
    # a box turned 45 degrees about z shows an edge at x = sqrt(2)/2
    ("capsule-box 45deg edge", CollisionShape.capsule((0, 0, -2), (0, 0, 2), 0.05), T((1, 0, 0)), CollisionShape.box([1, 1, 1]), T(rotvec=rz(math.pi / 4)), 1 - S2 / 2 - 0.05),
    # a capsule lying along y across a box turned 45 degrees about x: the top edge is at z = sqrt(2)/2
    ("capsule-box tilted", CollisionShape.capsule((0, -3, 0), (0, 3, 0), 0.1), T((0.2, 0, 1)), CollisionShape.box([1, 1, 1]), T(rotvec=(math.pi / 4, 0, 0)), 1 - S2 / 2 - 0.1),
    ("box-box 45deg", CollisionShape.box([1, 1, 1]), T(), CollisionShape.box([1, 1, 1]), T((2, 0, 0), rz(math.pi / 4)), 2 - 0.5 - S2 / 2),
    # edge against edge: A turned 45 deg about y (edge along y at x = +sqrt(2)/2), B turned 45 deg about x
    # (edge along x at y = ... ) placed beyond along x and z so that the two edges cross at right angles
    ("box-box edge-edge", CollisionShape.box([1, 1, 1]), T(rotvec=(0, math.pi / 4, 0)), CollisionShape.box([1, 1, 1]), T((0, 0, 2), (math.pi / 4, 0, 0)), 2 - S2),
    ("cylinder-sphere side", CollisionShape.cylinder(0.2, 1.0), T((0, 0, 0)), CollisionShape.sphere(0.1), T((0.5, 0, 0.2)), 0.2),
    ("cylinder-sphere rim", CollisionShape.cylinder(0.2, 1.0), T(), CollisionShape.sphere(0.1), T((0.5 / S2, 0.5 / S2, 0.9)), math.hypot(0.3, 0.4) - 0.1),
    ("cylinder-cylinder parallel", CollisionShape.cylinder(0.2, 1.0), T((0.1, 0, 0)), CollisionShape.cylinder(0.3, 0.5), T((0.1, 0.7, 0.3)), 0.2),
    # a cylinder lying along x (turned about y) on a box: its lowest line is radius below its axis
    ("cylinder-box lying", CollisionShape.cylinder(0.1, 2.0), T((0, 0, 0.75), (0, math.pi / 2, 0)), CollisionShape.box([1, 1, 1]), T(), 0.15),
    ("capsule-cylinder end cap", CollisionShape.capsule((0, 0, 0), (0, 0, 1), 0.05), T((0.1, 0, 0.7)), CollisionShape.cylinder(0.2, 1.0), T(), 0.15),
    ("convex-sphere", CollisionShape.convex([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]), T(), CollisionShape.sphere(0.1), T((1, 1, 1)), 2 / math.sqrt(3) - 0.1),
    ("convex-box", CollisionShape.convex([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]), T((0, 0, 1.5)), CollisionShape.box([1, 1, 1]), T(), 1.0),
]


@pytest.mark.parametrize(("a", "Ta", "b", "Tb", "expected"), [c[1:] for c in ANALYTIC], ids=[c[0] for c in ANALYTIC])
def test_distance_matches_the_analytic_value(a, Ta, b, Tb, expected) -> None:
    assert distance(a, Ta, b, Tb) == pytest.approx(expected, abs=1e-9)
    assert distance(b, Tb, a, Ta) == pytest.approx(expected, abs=1e-9)
    # moving b straight towards a by more than the gap makes them collide, less keeps them apart
    assert not intersects(a, Ta, b, Tb)
    assert intersects(a, Ta, b, Tb, margin=expected + 1e-6)
    assert not intersects(a, Ta, b, Tb, margin=expected - 1e-6)


def test_overlapping_shapes_are_at_distance_zero() -> None:
    box = CollisionShape.box([1, 1, 1])
    for other, pose in [
        (CollisionShape.sphere(0.1), T((0.55, 0, 0))),
        (CollisionShape.capsule((-2, 0, 0), (2, 0, 0), 0.01), T((0, 0.3, 0.3))),  # pierces right through
        (CollisionShape.box([0.2, 0.2, 0.2]), T((0.5, 0.5, 0.5), (0.3, 0.2, 0.1))),
        (CollisionShape.cylinder(0.1, 3.0), T((0.5, 0, 0))),
        (CollisionShape.convex(np.eye(3) * 0.1), T((0.2, 0.2, 0.2))),  # a flat triangle inside
    ]:
        assert distance(box, T(), other, pose) == 0.0
        assert intersects(other, pose, box, T())


# -- known colliding and free configurations --------------------------------------------------------
def chain_near_box(gap: float) -> CollisionWorld:
    """Three 4 cm capsules going up along z then over; the last link ends ``gap`` from a box face."""
    cw = CollisionWorld()
    cw.add("box", CollisionShape.box([0.2, 0.2, 0.2]), T((0.5, 0, 0.5)))
    r = 0.04
    x_tip = 0.5 - 0.1 - r - gap
    points = [[0, 0, 0], [0, 0, 0.5], [0.2, 0, 0.5], [x_tip, 0, 0.5]]
    cw.add_chain(["link1", "link2", "link3"], points, r)
    return cw


@pytest.mark.parametrize(("gap", "hit"), [(-0.01, True), (0.0, True), (0.001, False), (0.05, False)])
def test_chain_touching_or_penetrating_collides_and_clear_by_1mm_does_not(gap: float, hit: bool) -> None:
    cw = chain_near_box(gap)
    assert cw.pairs() == ([("box", "link3")] if hit else [])
    assert cw.in_collision() is hit
    assert cw.distance("box", "link3") == pytest.approx(max(gap, 0.0), abs=1e-12)


def test_margin_flags_near_misses() -> None:
    cw = chain_near_box(0.001)
    assert cw.pairs(margin=0.002) == [("box", "link3")]
    assert cw.pairs(margin=0.0005) == []
    assert CollisionWorld(margin=0.002).margin == 0.002


def test_adjacent_links_are_ignored_but_folding_links_are_reported() -> None:
    # a chain that folds back: link3 comes back down onto link1
    points = [[0, 0, 0], [0, 0, 0.5], [0.1, 0, 0.5], [0.1, 0, 0.1]]
    cw = CollisionWorld()
    cw.add_chain(["l1", "l2", "l3"], points, 0.06)
    assert cw.pairs() == [("l1", "l3")]
    raw = CollisionWorld()
    raw.add_chain(["l1", "l2", "l3"], points, 0.06, ignore_adjacent=False)
    assert raw.pairs() == [("l1", "l2"), ("l1", "l3"), ("l2", "l3")]
    # straightened out, only the (ignored) adjacent contacts remain
    cw.set_chain(["l1", "l2", "l3"], [[0, 0, 0], [0, 0, 0.5], [0, 0, 1.0], [0, 0, 1.5]])
    assert cw.pairs() == []


def test_pairs_are_sorted_and_ordered_within_each_pair() -> None:
    cw = CollisionWorld()
    for name, x in [("zeta", 0.0), ("alpha", 0.15), ("mid", 0.3), ("beta", 5.0)]:
        cw.add(name, CollisionShape.sphere(0.1), T((x, 0, 0)))
    assert cw.pairs() == [("alpha", "mid"), ("alpha", "zeta")]
    assert cw.colliding("alpha") == ["mid", "zeta"]
    cw.ignore("zeta", "alpha")
    assert cw.pairs() == [("alpha", "mid")]
    cw.set_pose("beta", T((0.45, 0.1, 0)))
    assert cw.pairs() == [("alpha", "mid"), ("beta", "mid")]
    cw.remove("mid")
    assert cw.pairs() == []
    with pytest.raises(KeyError, match="did you mean 'alpha'"):
        cw.set_pose("alpah", np.eye(4))
    with pytest.raises(ValueError, match="already has a shape named 'beta'"):
        cw.add("beta", CollisionShape.sphere(1))


def test_shapes_reject_bad_sizes() -> None:
    with pytest.raises(ValueError, match="box size"):
        CollisionShape.box([1, 0, 1])
    with pytest.raises(ValueError, match="sphere radius"):
        CollisionShape.sphere(-1)
    with pytest.raises(ValueError, match="4x4"):
        CollisionWorld().add("a", CollisionShape.sphere(1), np.eye(3))


# -- shapes from scene nodes -----------------------------------------------------------------------
def test_shapes_from_scene_nodes_follow_their_world_poses() -> None:
    world = World()
    base = world.add(Group("base", T_parent_local=T((1, 0, 0))))
    world.add(Box("table", size=(1.0, 1.0, 0.1)), base)
    world.add(Sphere("ball", radius=0.1, T_parent_local=T((1, 0, 0.2))))
    world.add(Cylinder("can", radius=0.05, height=0.3, T_parent_local=T((3, 0, 0))))
    tet = Part([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    world.add(MeshNode("wedge", mesh_parts=[tet], scale=0.2, T_parent_local=T((3, 0, 0.2))))
    cw = CollisionWorld()
    assert cw.add_world(world) == ["table", "ball", "can", "wedge"]  # the Group has no geometry
    assert shape_from_node(world["ball"]).kind == "sphere"  # exact, not the tessellation
    assert cw.shape("wedge").kind == "convex"
    np.testing.assert_allclose(cw.shape("wedge").hi, [0.2, 0.2, 0.2])  # the node's scale applied
    # ball rests 0.1 above the table top (z = 0.05): free; the can reaches z = 0.15, the wedge starts at 0.2
    assert cw.pairs() == []
    assert cw.distance("ball", "table") == pytest.approx(0.05)
    assert cw.distance("can", "wedge") == pytest.approx(0.05)
    world["ball"].set(T_parent_local=T((1, 0, 0.12)))
    world["can"].set(height=0.5)  # now reaches z = 0.25
    cw.sync()
    assert cw.pairs() == [("ball", "table"), ("can", "wedge")]
    with pytest.raises(ValueError, match="no solid geometry"):
        shape_from_node(world["base"])


# -- randomized cross-checks against brute-force references -------------------------------------------
def hull_distance_reference(A: np.ndarray, B: np.ndarray) -> float:
    """min |a - b| over the convex hulls, as a QP in barycentric weights (SLSQP)."""
    na, nb = len(A), len(B)

    def f(w: np.ndarray) -> float:
        d = w[:na] @ A - w[na:] @ B
        return float(d @ d)

    def g(w: np.ndarray) -> np.ndarray:
        d = w[:na] @ A - w[na:] @ B
        return np.concatenate([2 * A @ d, -2 * B @ d])

    best = math.inf
    for start in (np.full(na + nb, 1.0), np.random.default_rng(0).uniform(0.1, 1, na + nb)):
        w0 = np.concatenate([start[:na] / start[:na].sum(), start[na:] / start[na:].sum()])
        cons = [{"type": "eq", "fun": lambda w: w[:na].sum() - 1}, {"type": "eq", "fun": lambda w: w[na:].sum() - 1}]
        res = minimize(f, w0, jac=g, bounds=[(0, 1)] * (na + nb), constraints=cons, method="SLSQP", options={"ftol": 1e-16, "maxiter": 500})
        best = min(best, math.sqrt(max(res.fun, 0.0)))
    return best


def hulls_intersect_lp(A: np.ndarray, B: np.ndarray) -> bool:
    """Exact test: is there a point in both hulls? (LP feasibility in barycentric weights)"""
    na, nb = len(A), len(B)
    A_eq = np.zeros((5, na + nb))
    A_eq[:3, :na] = A.T
    A_eq[:3, na:] = -B.T
    A_eq[3, :na] = 1
    A_eq[4, na:] = 1
    res = linprog(np.zeros(na + nb), A_eq=A_eq, b_eq=[0, 0, 0, 1, 1], bounds=[(0, None)] * (na + nb), method="highs")
    return res.status == 0


def world_vertices(shape: CollisionShape, pose: np.ndarray) -> np.ndarray:
    return shape.vertices @ pose[:3, :3].T + pose[:3, 3]


def random_pose(rng: np.random.Generator, spread: float) -> np.ndarray:
    return T(rng.uniform(-spread, spread, 3), Rotation.random(random_state=rng).as_rotvec())


def test_gjk_matches_a_qp_reference_on_random_convex_hulls() -> None:
    rng = np.random.default_rng(1)
    seen_zero = seen_positive = 0
    for _ in range(40):
        a = CollisionShape.convex(rng.normal(size=(rng.integers(4, 12), 3)) * rng.uniform(0.1, 0.5, 3))
        b = CollisionShape.convex(rng.normal(size=(rng.integers(4, 12), 3)) * rng.uniform(0.1, 0.5, 3))
        Ta, Tb = random_pose(rng, 0.6), random_pose(rng, 0.6)
        A, B = world_vertices(a, Ta), world_vertices(b, Tb)
        d = distance(a, Ta, b, Tb)
        overlap = hulls_intersect_lp(A, B)
        if overlap:
            assert d == 0.0
            seen_zero += 1
        else:
            ref = hull_distance_reference(A, B)
            assert d == pytest.approx(ref, abs=2e-6)
            # GJK is exact; SLSQP may stop a little high, never below the true distance
            assert d <= ref + 1e-9
            seen_positive += 1
    assert seen_zero >= 5 and seen_positive >= 5  # both cases were exercised


def test_box_sat_agrees_with_lp_on_random_near_contact_boxes() -> None:
    rng = np.random.default_rng(2)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    hits = 0
    for _ in range(150):
        sa, sb = rng.uniform(0.1, 0.6, 3), rng.uniform(0.1, 0.6, 3)
        Ta, Tb = random_pose(rng, 0.4), random_pose(rng, 0.4)
        a, b = CollisionShape.box(sa), CollisionShape.box(sb)
        A = (corners * sa / 2) @ Ta[:3, :3].T + Ta[:3, 3]
        B = (corners * sb / 2) @ Tb[:3, :3].T + Tb[:3, 3]
        truth = hulls_intersect_lp(A, B)
        assert intersects(a, Ta, b, Tb) is truth  # the separating-axis test
        assert (distance(a, Ta, b, Tb) == 0.0) is truth  # GJK on the same pair
        hits += truth
    assert 20 < hits < 130


def test_capsule_and_box_closed_forms_match_dense_sampling() -> None:
    """Segment distances are 1-Lipschitz along the segment, so sampling every h bounds the error by h/2."""
    rng = np.random.default_rng(3)
    n = 20001
    t = np.linspace(0, 1, n)[:, None]
    for _ in range(40):
        half = rng.uniform(0.05, 0.4, 3)
        p0, p1 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
        q0, q1 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
        box_pose = random_pose(rng, 0.3)
        pts = p0 + t * (p1 - p0)
        local = (pts - box_pose[:3, 3]) @ box_pose[:3, :3]
        ref_box = np.linalg.norm(local - np.clip(local, -half, half), axis=1).min()
        capsule = CollisionShape.capsule(p0, p1, 1e-3)
        h = np.linalg.norm(p1 - p0) / (n - 1)
        got = distance(capsule, np.eye(4), CollisionShape.box(2 * half), box_pose) + 1e-3
        if ref_box > 2e-3:
            assert got == pytest.approx(ref_box, abs=h)
            assert got <= ref_box + 1e-12
        # segment to segment: closest point of segment q to every sample of p, by projection
        d = q1 - q0
        s = np.clip(((pts - q0) @ d) / (d @ d), 0, 1)[:, None]
        ref_seg = np.linalg.norm(pts - (q0 + s * d), axis=1).min()
        other = CollisionShape.capsule(q0, q1, 1e-3)
        got = distance(capsule, np.eye(4), other, np.eye(4)) + 2e-3
        if ref_seg > 3e-3:
            assert got == pytest.approx(ref_seg, abs=h)
            assert got <= ref_seg + 1e-12


def test_cylinder_gjk_matches_sampled_surface() -> None:
    """A cylinder against a sphere: compare with the distance to a dense sampling of the cylinder."""
    rng = np.random.default_rng(4)
    r, height = 0.2, 0.6
    th = np.linspace(0, 2 * np.pi, 721)[:-1]
    zs = np.linspace(-height / 2, height / 2, 301)
    side = np.stack(np.broadcast_arrays(r * np.cos(th)[:, None], r * np.sin(th)[:, None], zs[None, :]), -1).reshape(-1, 3)
    rho = np.linspace(0, r, 101)
    disc = np.stack(np.broadcast_arrays(rho[:, None] * np.cos(th)[None], rho[:, None] * np.sin(th)[None], 0 * th[None]), -1).reshape(-1, 3)
    surface = np.concatenate([side, disc + (0, 0, height / 2), disc - (0, 0, height / 2)])
    cyl = CollisionShape.cylinder(r, height)
    for _ in range(20):
        pose = random_pose(rng, 0.0)
        c = rng.normal(size=3)
        c *= rng.uniform(0.45, 0.8) / np.linalg.norm(c)
        ref = np.linalg.norm(surface @ pose[:3, :3].T + pose[:3, 3] - c, axis=1).min() - 0.05
        got = distance(cyl, pose, CollisionShape.sphere(0.05), T(c))
        # sampling overestimates by at most the grid spacing (about 2 mm here)
        assert ref - 2.5e-3 <= got <= ref + 1e-9


def test_collisions_follows_a_world_as_it_changes() -> None:
    from ejsrl.world.collision import collisions

    world = World()
    world.add(Box("table", size=(1.0, 1.0, 0.1)))
    gripper = world.add(Box("gripper", size=(0.1, 0.1, 0.1), T_parent_local=T((0, 0, 0.5))))
    world.add(Sphere("cube", radius=0.05, T_parent_local=T((0.3, 0, 0.1))))
    assert collisions(world) == [("cube", "table")]  # the cube rests 0 above the table top
    # the gripper picks the cube up: it now touches the gripper, its parent, which is not reported
    world.reparent("cube", "gripper")
    world.set_world_pose("cube", T((0, 0, 0.4)))
    assert collisions(world) == []
    gripper.set(T_parent_local=T((0, 0, 0.15)))  # lowered: the cube (a child) reaches the table
    assert collisions(world) == [("cube", "table")]
    assert collisions(world, ignore=[("table", "cube")]) == []
    world["cube"].set(visible=False)  # a hidden object is not there
    assert collisions(world) == []  # the gripper's bottom (z = 0.10) is clear of the table top (0.05)
    world["cube"].set(visible=True)
    assert collisions(world) == [("cube", "table")]
    world.add(Cylinder("post", radius=0.05, height=1.0, T_parent_local=T((0.5, 0.5, 0))))
    assert ("post", "table") in collisions(world)


def test_gjk_handles_flat_segment_and_point_hulls() -> None:
    """Degenerate hulls (points, segments, flat polygons) make degenerate GJK simplices."""
    rng = np.random.default_rng(5)
    for _ in range(40):
        pa = rng.normal(size=(rng.integers(1, 6), 3))
        pa[:, 2] = 0
        pb = rng.normal(size=(rng.integers(1, 6), 3)) * 0.5
        pb[:, 1] = 0
        a, b = CollisionShape.convex(pa), CollisionShape.convex(pb)
        Ta, Tb = random_pose(rng, 1.0), random_pose(rng, 1.0)
        A, B = world_vertices(a, Ta), world_vertices(b, Tb)
        d = distance(a, Ta, b, Tb)
        if hulls_intersect_lp(A, B):
            assert d < 1e-9
        else:
            assert d == pytest.approx(hull_distance_reference(A, B), abs=2e-6)
