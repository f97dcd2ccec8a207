"""Benchmark: one full collision check of a 7-link arm (7 capsules) among ten objects.

The scene is a table-top cell: a 7-DOF arm whose links are capsules between its joint
origins, moving along a sweep so that it reaches into the objects at some poses and is
clear at others, plus ten objects (4 boxes, 3 spheres, 3 cylinders). One "check" is what
a model does every frame: move the chain to the new joint origins and call ``pairs()``.

Target (design brief): under 2 ms per check on the 2-core development machine.
Run: ``python bench/collision.py``.
"""

from __future__ import annotations

import time

import numpy as np

from ejsrl.robotics.transforms import rpy2tr, transl
from ejsrl.world.collision import CollisionShape, CollisionWorld, intersects

TARGET_MS = 2.0


def arm_points(q: np.ndarray) -> np.ndarray:
    """Joint origins (8, 3) of a simple 7-DOF arm (alternating z/y axes, link lengths 0.1-0.3 m)."""
    lengths = [0.30, 0.25, 0.25, 0.20, 0.20, 0.10, 0.10]
    T = np.eye(4)
    pts = [T[:3, 3].copy()]
    for k, (qk, L) in enumerate(zip(q, lengths)):
        c, s = np.cos(qk), np.sin(qk)
        R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]]) if k % 2 == 0 else np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        step = np.eye(4)
        step[:3, :3] = R
        T = T @ step @ transl(0, 0, L)
        pts.append(T[:3, 3].copy())
    return np.array(pts)


def build() -> tuple[CollisionWorld, list[str]]:
    rng = np.random.default_rng(7)
    cw = CollisionWorld()
    links = [f"link{k}" for k in range(1, 8)]
    cw.add_chain(links, arm_points(np.zeros(7)), radius=0.04)
    for k in range(4):
        T = transl(*rng.uniform([-0.6, -0.6, 0.05], [0.6, 0.6, 0.6])) @ rpy2tr(*rng.uniform(-np.pi, np.pi, 3))
        cw.add(f"box{k}", CollisionShape.box(rng.uniform(0.05, 0.2, 3)), T)
    for k in range(3):
        cw.add(f"ball{k}", CollisionShape.sphere(rng.uniform(0.03, 0.1)), transl(*rng.uniform([-0.6, -0.6, 0.05], [0.6, 0.6, 0.6])))
    for k in range(3):
        T = transl(*rng.uniform([-0.6, -0.6, 0.05], [0.6, 0.6, 0.6])) @ rpy2tr(*rng.uniform(-np.pi, np.pi, 3))
        cw.add(f"can{k}", CollisionShape.cylinder(rng.uniform(0.03, 0.08), rng.uniform(0.1, 0.25)), T)
    return cw, links


def main() -> None:
    cw, links = build()
    n = 2000
    t = np.linspace(0, 2 * np.pi, n)
    qs = np.column_stack([np.sin(t * (k + 1) / 3) * (1.2 - 0.1 * k) for k in range(7)])
    qs[:, 1] += 0.8
    pts = [arm_points(q) for q in qs]
    for p in pts[:50]:  # warm up
        cw.set_chain(links, p)
        cw.pairs()
    hits = 0
    cand = 0
    start = time.perf_counter()
    for p in pts:
        cw.set_chain(links, p)
        hits += len(cw.pairs())
    elapsed = time.perf_counter() - start
    for p in pts[::10]:
        cw.set_chain(links, p)
        cand += len(cw.candidates())
    ms = 1000 * elapsed / n
    # worst case: every one of the 136 - 6 (ignored) pairs through the narrow phase, no broad phase
    names = cw.names
    ignored = {(a, b) for a, b in zip(links[:-1], links[1:])}
    all_pairs = [(a, b) for i, a in enumerate(names) for b in names[i + 1 :] if (a, b) not in ignored]
    m = 200
    start = time.perf_counter()
    for p in pts[:m]:
        cw.set_chain(links, p)
        for a, b in all_pairs:
            intersects(cw.shape(a), cw.pose(a), cw.shape(b), cw.pose(b))
    worst_ms = 1000 * (time.perf_counter() - start) / m
    print(f"scene: 7 capsule links + 10 objects (4 boxes, 3 spheres, 3 cylinders), {len(cw)} shapes")
    print(f"mean broad-phase candidate pairs per check: {cand / len(pts[::10]):.1f}; colliding pairs per check: {hits / n:.2f}")
    print(f"one full check (set_chain + pairs): {ms:.3f} ms over {n} poses; target < {TARGET_MS} ms: "
          + ("MET" if ms < TARGET_MS else "NOT MET"))
    print(f"worst case without the broad phase ({len(all_pairs)} narrow-phase pairs): {worst_ms:.3f} ms")


if __name__ == "__main__":
    main()
