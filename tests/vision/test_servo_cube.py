"""The eye-in-hand servoing lab on a cube instead of the flat square, sharp and with the camera's
blur (issue #28): SUSAN finds the cube's corners in the rendered picture (reading the blur,
``blur='auto'``), and IBVS and PBVS bring the cube's true top face to the desired square
(checked by a pinhole projection of the scene's geometry, not by the lab's own detector)."""

from __future__ import annotations

import numpy as np
import pytest

from testkit.labs import headless, matrices, pinhole


@pytest.mark.parametrize(("mode", "blur"), [("IBVS", 0.0), ("PBVS", 0.0), ("IBVS", 1.5)])
def test_the_servo_brings_the_cubes_top_to_the_goal(built, mode: str, blur: float) -> None:
    d = headless(built("paper/visual_servoing_eih"), 6.0, vars="t,found,err_px,done,T_cam", every=15,
                 sets={"mode": mode, "target": "cube", "cam_blur": str(blur)})
    assert np.all(d["found"] == 4)
    done = np.flatnonzero(d["done"] == 1)
    assert len(done) and d["t"][done[0]] < 6.0
    # the cube's true top corners (side 0.1 m, top at z = 0.302), as the camera at the end sees them
    h = 0.05
    top = np.array([[0.55 + sx * h, 0.15 + sy * h, 0.302] for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
    seen = pinhole(top, matrices(d, "T_cam")[-1], 320, 240, 50)
    goal = np.array([[159.5 + x, 119.5 + y] for x in (-50, 50) for y in (-50, 50)])
    dist = np.linalg.norm(seen[:, None] - goal[None], axis=2).min(axis=1)
    assert dist.max() < 1.5, dist
