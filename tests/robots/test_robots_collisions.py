"""collisions(): objects and robot links that touch, as the student sees them.

References are geometric: boxes placed on a link's axis (computed from fkine_all), a
sphere at measured clearances from the drawn link surface, arms folded so two links
cross, arms turned away with large analytic clearances.
"""

from __future__ import annotations

import time

import numpy as np

from ejsrl.robotics import models
from ejsrl.robotics.transforms import rpy2tr, transl
from ejsrl.view.elements import Dynamic, Node3D

from testkit.robots import Model, random_q, robot, scene


def box(name: str, position, size=(0.1, 0.1, 0.1), **kw) -> Node3D:
    return Node3D(kind="box", name=name, props={"size": size}, position=position, **kw)


def point_segment_distance(p, a, b) -> float:
    ab = b - a
    s = np.clip(np.dot(p - a, ab) / np.dot(ab, ab), 0.0, 1.0)
    return float(np.linalg.norm(p - (a + s * ab)))


def test_an_arm_near_a_box_collides_in_known_configurations_and_not_in_others() -> None:
    r = models.rrr()  # shoulder 0.4 m up, upper arm 0.4 m, forearm 0.3 m
    q_hit = np.array([0.0, 0.3, -0.6])
    F = r.fkine_all(q_hit)
    mid_forearm = (F[2][:3, 3] + F[3][:3, 3]) / 2
    m = Model(robot=r, q=q_hit)
    _sync, wf = scene(robot("arm"), box("crate", tuple(mid_forearm)), model=m)
    assert wf.collisions() == [("arm.link3", "crate")]
    for q_free in ([np.pi, 0.3, -0.6], [np.pi / 2, 0.3, -0.6], [0.0, 1.4, -0.2]):
        m.q = np.array(q_free)
        F = r.fkine_all(m.q)
        clearance = min(point_segment_distance(mid_forearm, F[i][:3, 3], F[i + 1][:3, 3]) for i in range(3))
        assert clearance > 0.25  # far from every link, whatever their thickness
        assert wf.collisions() == []
    m.q = q_hit
    assert wf.collisions() == [("arm.link3", "crate")]


def test_contact_starts_where_the_drawn_link_surface_meets_the_object() -> None:
    """The collision capsule is the drawn rod: a sphere touches exactly at the rod's radius."""
    r = models.rrr()
    q = np.array([0.2, 0.5, -0.9])
    F = r.fkine_all(q)
    a, b = F[1][:3, 3], F[2][:3, 3]  # the upper arm
    mid = (a + b) / 2
    normal = np.cross(b - a, [0.0, 0.0, 1.0])
    normal /= np.linalg.norm(normal)
    m = Model(robot=r, q=q, ball=mid + normal)
    ball = Node3D(kind="sphere", name="ball", props={"radius": 0.05}, position=(9.0, 9.0, 9.0))
    sync, wf = scene(robot("arm"), ball, model=m)
    link = sync.world["arm.link2"]
    T = link.T_world()
    v = np.concatenate([p.vertices for p in link.parts() if p.rgb is None]) @ T[:3, :3].T + T[:3, 3]  # the rod, not the joints
    u = (b - a) / np.linalg.norm(b - a)
    along = (v - a) @ u
    beside = (along >= -1e-9) & (along <= np.linalg.norm(b - a) + 1e-9)  # the rod's side, not its round ends
    drawn_radius = np.max(np.linalg.norm((v - a) - np.outer(along, u), axis=1)[beside])
    assert 0.01 < drawn_radius < 0.05
    for gap, touching in ((-0.002, True), (0.002, False)):
        wf.move_object("ball", mid + normal * (0.05 + drawn_radius + gap))
        assert (("arm.link2", "ball") in wf.collisions()) is touching, gap


def test_neighbouring_links_are_never_reported_but_a_folded_arm_hits_itself() -> None:
    rng = np.random.default_rng(3)
    arms = {"puma": models.puma560(), "pa10": models.pa10(), "ur5": models.ur5(), "planar": models.planar(3)}
    m = Model(**{name: r for name, r in arms.items()}, **{f"q_{name}": np.zeros(r.n) for name, r in arms.items()})
    elements = [robot(name, model=name, q=f"q_{name}", position=(3.0 * k, 0.0, 0.0)) for k, name in enumerate(arms)]
    sync, wf = scene(*elements, model=m)
    assert wf.collisions() == []  # the zero poses touch nothing
    seen = set()
    for _ in range(100):
        for name, r in arms.items():
            setattr(m, f"q_{name}", random_q(r, rng))
        for a, b in wf.collisions():
            ra, ia = a.rsplit(".link", 1)
            rb, ib = b.rsplit(".link", 1)
            assert ra == rb  # the arms stand 3 m apart
            assert abs(int(ia) - int(ib)) >= 2, (a, b)
            seen.add((a, b))
    # folded back on itself, the planar arm's forearm crosses its first link
    m.q_planar = np.array([0.0, np.pi - 0.1, np.pi - 0.1])
    F = arms["planar"].fkine_all(m.q_planar)
    assert F[2][1, 3] > 0.05 and F[3][1, 3] < -0.05  # link 3 runs from above to below link 1 (the x axis)
    assert ("planar.link1", "planar.link3") in wf.collisions()
    m.q_planar = np.array([0.0, 0.3, 0.3])
    assert not [p for p in wf.collisions() if p[0].startswith("planar")]


def test_two_arms_touching_each_other_are_reported() -> None:
    left, right = models.rrr(), models.rrr()
    # both reach straight towards each other: tool tips 0.7 m from each base
    m = Model(left=left, right=right, ql=np.zeros(3), qr=np.zeros(3), gap=1.6)
    sync, wf = scene(
        robot("left", model="left", q="ql"),
        robot("right", model="right", q="qr",
              base=Dynamic(lambda m: transl(m.gap, 0.0, 0.0) @ rpy2tr(0.0, 0.0, np.pi), "transl(gap, 0, 0) @ trotz(pi)")),
        model=m,
    )
    assert wf.collisions() == []  # tips 0.2 m apart
    m.gap = 1.38
    pairs = wf.collisions()
    assert ("left.link3", "right.link3") in pairs
    assert all(a.split(".")[0] != b.split(".")[0] for a, b in pairs)


def test_a_grasped_object_does_not_collide_with_its_gripper_but_with_the_world() -> None:
    r = models.puma560()
    q = np.array([0.0, 0.6, -2.6, 0.0, 0.5, 0.0])
    tool = r.fkine(q)[:3, 3]
    m = Model(robot=r, q=q)
    sync, wf = scene(robot("arm"), box("part", tuple(tool), size=(0.06, 0.06, 0.06)),
                     box("wall", (0.0, 0.0, -5.0), size=(0.05, 2.0, 2.0)),
                     box("ghost", (0.0, 0.0, -5.0), visible=False), model=m)
    assert ("arm.link6", "part") in wf.collisions()
    wf.attach("part", "arm")
    assert wf.collisions() == []
    T_part = wf.object_pose("part")
    wf.move_object("wall", T_part[:3, 3] + [0.04, 0.0, 0.0])  # the wall's face cuts the part
    wf.move_object("ghost", T_part[:3, 3])  # hidden objects take no part
    pairs = wf.collisions()
    assert ("part", "wall") in pairs and not any("ghost" in p for p in pairs)


def test_collisions_from_model_code_in_a_built_app(tmp_path) -> None:
    from ejsgen.cli import build

    from testkit.robots import load_built

    spec = tmp_path / "cell.ejs.yaml"
    spec.write_text(
        "ejs: 1\ntitle: Cell\nimports: [from ejsrl.robotics import models]\n"
        "model:\n  variables:\n    robot: {expr: 'models.rrr()'}\n    q: [0.0, 0.3, -0.6]\n    hits: 0\n"
        "    t: 0.0\n  evolution:\n    - code: 't = t + 0.1'\n"
        "  fixed_relations: |\n    hits = len(collisions())\n"
        "view:\n  - scene:\n      - robot: {name: arm, model: robot, q: q}\n"
        "      - box: {name: crate, position: [0.5254, 0.0, 0.4739], size: [0.1, 0.1, 0.1]}\n"
    )
    app = load_built(build(spec, tmp_path / "cell"))
    assert app.error is None
    assert app.model.collisions() == [("arm.link3", "crate")]
    app.step_once()  # the fixed relations run after a step
    assert app.model.hits == 1
    app.model.q = np.array([np.pi, 0.3, -0.6])
    assert app.model.collisions() == []
    app.step_once()
    assert app.model.hits == 0


def test_one_check_of_a_seven_joint_arm_among_ten_objects_takes_under_two_milliseconds() -> None:
    from testkit import bench_module

    bench = bench_module("robots_collision")
    build_cell, sweep = bench.build_cell, bench.sweep

    sync, wf, m = build_cell()
    qs = sweep(200)
    hits = 0
    times = []
    for q in qs:
        m.q = q
        t0 = time.perf_counter()
        hits += bool(wf.collisions())
        times.append(time.perf_counter() - t0)
    assert 0 < hits < len(qs)  # the sweep reaches into the objects at some poses only
    assert min(times) < 2e-3 and np.median(times) < 4e-3, (min(times), np.median(times))
