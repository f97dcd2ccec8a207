"""The eye-in-hand servoing lab on a cube instead of the flat square (issue #28): SUSAN finds the
cube's corners in the rendered picture, and IBVS and PBVS bring the cube's true top face to the
desired square (checked by a pinhole projection of the scene's geometry, not by the lab's own
detector)."""

from __future__ import annotations

import numpy as np
import pytest

from testkit import EXAMPLES
from testkit.labs import headless, matrices, pinhole

FLAT = 'box: {name: square, position: [0.55, 0.15, 0.203], size: [0.16, 0.16, 0.002], color: "#202020"}'
CUBE = 'box: {name: square, position: [0.55, 0.15, 0.252], size: [0.1, 0.1, 0.1], color: "#202020"}'


@pytest.fixture(scope="module")
def cube_lab(tmp_path_factory) -> object:
    from ejsgen.cli import build

    text = (EXAMPLES / "paper" / "visual_servoing_eih.ejs.yaml").read_text(encoding="utf-8")
    assert FLAT in text and "plate_z: {value: 0.202," in text and "side: {value: 0.16," in text
    text = text.replace(FLAT, CUBE).replace("plate_z: {value: 0.202,", "plate_z: {value: 0.302,").replace("side: {value: 0.16,", "side: {value: 0.1,")
    d = tmp_path_factory.mktemp("cube")
    (d / "cube.ejs.yaml").write_text(text, encoding="utf-8")
    return build(d / "cube.ejs.yaml", d / "app")


@pytest.mark.parametrize("mode", ["IBVS", "PBVS"])
def test_the_servo_brings_the_cubes_top_to_the_goal(cube_lab, mode: str) -> None:
    d = headless(cube_lab, 6.0, vars="t,found,err_px,done,T_cam", every=15, sets={"mode": mode})
    assert np.all(d["found"] == 4)
    done = np.flatnonzero(d["done"] == 1)
    assert len(done) and d["t"][done[0]] < 6.0
    # the cube's true top corners, as the camera at the end sees them: on the desired square
    h = 0.05
    top = np.array([[0.55 + sx * h, 0.15 + sy * h, 0.302] for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
    seen = pinhole(top, matrices(d, "T_cam")[-1], 320, 240, 50)
    goal = np.array([[159.5 + x, 119.5 + y] for x in (-50, 50) for y in (-50, 50)])
    dist = np.linalg.norm(seen[:, None] - goal[None], axis=2).min(axis=1)
    assert dist.max() < 1.5, dist
