"""Benchmark: one full ``collisions()`` check of a 7-joint arm (PA-10) among ten objects.

What a model's ``collisions()`` costs every frame in an app: the robot element is drawn
by ``SceneSync`` (links posed by ``fkine_all``), and ``WorldFunctions.collisions()``
brings the arm up to date with the model's joints, moves the link capsules and joint
cylinders, and runs the broad and narrow phases against ten objects (4 boxes, 3 spheres,
3 cylinders) placed around the arm. The arm sweeps through poses that reach into the
objects at some times and are clear at others.

Target (design brief): under 2 ms per check on the 2-core development machine.
Run: ``python bench/robots_collision.py``.
"""

from __future__ import annotations

import time
from types import SimpleNamespace
from typing import Any

import numpy as np

from ejsrl.robotics import models
from ejsrl.view.elements import Dynamic, Node3D
from ejsrl.world.binding import SceneSync
from ejsrl.world.functions import WorldFunctions

TARGET_MS = 2.0


def build_cell() -> tuple[SceneSync, WorldFunctions, Any]:
    """The PA-10 and ten objects in a SceneSync; returns (scene, world functions, model)."""
    rng = np.random.default_rng(11)
    m = SimpleNamespace(robot=models.pa10(), q=np.zeros(7))
    elements = [Node3D(kind="robot", name="pa10", props={"model": Dynamic(lambda m: m.robot, "robot"), "q": Dynamic(lambda m: m.q, "q")})]

    def place() -> tuple[tuple[float, ...], tuple[float, ...]]:
        radius, angle, z = rng.uniform(0.35, 0.75), rng.uniform(-np.pi, np.pi), rng.uniform(0.1, 0.9)
        return (radius * np.cos(angle), radius * np.sin(angle), z), tuple(rng.uniform(-np.pi, np.pi, 3))

    for k in range(4):
        pos, rot = place()
        elements.append(Node3D(kind="box", name=f"box{k}", props={"size": tuple(rng.uniform(0.08, 0.2, 3))}, position=pos, rotation=rot))
    for k in range(3):
        pos, _ = place()
        elements.append(Node3D(kind="sphere", name=f"ball{k}", props={"radius": float(rng.uniform(0.04, 0.1))}, position=pos))
    for k in range(3):
        pos, rot = place()
        elements.append(Node3D(kind="cylinder", name=f"can{k}", props={"radius": float(rng.uniform(0.03, 0.08)), "height": float(rng.uniform(0.1, 0.25))},
                               position=pos, rotation=rot))
    sync = SceneSync(elements)
    sync.update(m, first=True)
    return sync, WorldFunctions(sync, m), m


def sweep(n: int) -> np.ndarray:
    """``n`` joint vectors (n, 7) of a smooth sweep through the PA-10's workspace."""
    t = np.linspace(0, 2 * np.pi, n)
    qs = np.column_stack([np.sin(t * (k + 1) / 2 + k) * (2.0 - 0.15 * k) for k in range(7)])
    qs[:, 1] = 0.9 * np.sin(3 * t) + 0.4  # the shoulder and the elbow lean out and back
    qs[:, 3] = 0.9 * np.sin(2 * t + 1) + 0.9
    return qs


def main() -> None:
    sync, wf, m = build_cell()
    qs = sweep(2000)
    wf.collisions()  # builds the checker once
    times = np.empty(len(qs))
    hits = 0
    for i, q in enumerate(qs):
        m.q = q
        t0 = time.perf_counter()
        pairs = wf.collisions()
        times[i] = time.perf_counter() - t0
        hits += bool(pairs)
    med, best, p95 = (float(x) * 1e3 for x in (np.median(times), times.min(), np.percentile(times, 95)))
    print(f"collisions(): PA-10 (7 joints, {sum(len(l.shapes) for l in sync.world['pa10'].links)} link shapes) + 10 objects, "
          f"{len(qs)} poses, {hits} with contacts")
    print(f"one check: median {med:.3f} ms, best {best:.3f} ms, 95th percentile {p95:.3f} ms (target < {TARGET_MS} ms)")
    print("OK" if med < TARGET_MS else "SLOWER THAN TARGET")


if __name__ == "__main__":
    main()
