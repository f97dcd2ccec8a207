"""The reference's script that builds a world and renders it (specs/reference.md, *Virtual
cameras*) runs as written: every name it imports is where it says, and the vertex it projects
lands on the cube's corner in the picture (its depth there is the vertex's)."""

from __future__ import annotations

import re

import numpy as np

from testkit import ROOT


def test_the_references_world_script_runs_and_projects_onto_the_picture() -> None:
    text = (ROOT / "specs" / "reference.md").read_text(encoding="utf-8")
    code = next(b for b in re.findall(r"```python\n(.*?)```", text, re.S) if "w = World()" in b)
    env: dict = {}
    exec(compile(code, "reference.md", "exec"), env)  # noqa: S102 - the project's own documentation
    rgb, depth, uv, cam, T = env["rgb"], env["depth"], env["uv"], env["cam"], env["T"]
    assert rgb.shape == (480, 640, 3) and depth.shape == (480, 640)
    x, y = np.round(uv[0]).astype(int)
    assert 0 <= x < 640 and 0 <= y < 480
    # the top vertex (0.05, 0.05, 0.1) of the cube turned 0.4 rad: the projected point of the
    # cube's own corner is within a pixel of where depth says the cube's top face ends
    corner = env["w"].T_world("cube") @ np.array([0.05, 0.05, 0.05, 1.0])
    uvc = cam.project(corner[None, :3], T)[0]
    z = cam.depth(corner[None, :3], T)[0]
    xi, yi = np.round(uvc).astype(int)
    window = depth[yi - 1 : yi + 2, xi - 1 : xi + 2]
    assert np.abs(window - z).min() < 0.01
