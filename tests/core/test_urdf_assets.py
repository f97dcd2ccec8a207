"""A URDF file listed in ``assets:`` brings the meshes it names into the app (session 11's second trial: a
URDF's own mesh was left behind, and the built app failed at start with "mesh file not found"),
and a broken URDF is a build error at its ``assets:`` line, not a misleading message at run time.

Reference: the arm's tool position from the URDF's own numbers (two links of 0.4 and 0.3 m in a
vertical plane, the shoulder 0.1 m up), computed by hand, read from the built app's headless run."""

from __future__ import annotations

import csv
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

from ejsgen.cli import build
from ejsgen.errors import SpecErrors

URDF = """<?xml version="1.0"?>
<robot name="planar2">
  <link name="base"><visual><geometry><mesh filename="package://planar2/meshes/base.stl"/></geometry></visual></link>
  <link name="link1">
    <visual><origin xyz="0.2 0 0"/><geometry><box size="0.4 0.04 0.04"/></geometry></visual>
    <inertial><origin xyz="0.2 0 0"/><mass value="2.0"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.03"/></inertial>
  </link>
  <link name="link2">
    <visual><geometry><mesh filename="meshes/tip.stl" scale="1 1 1"/></geometry></visual>
    <inertial><origin xyz="0.15 0 0"/><mass value="1.0"/><inertia ixx="0.0005" ixy="0" ixz="0" iyy="0.008" iyz="0" izz="0.008"/></inertial>
  </link>
  <link name="tip"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="link1"/>
    <origin xyz="0 0 0.1" rpy="1.5708 0 0"/><axis xyz="0 0 1"/><limit lower="-3.14" upper="3.14" effort="50" velocity="2"/></joint>
  <joint name="elbow" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="0.4 0 0"/><axis xyz="0 0 1"/><limit lower="-2.5" upper="2.5" effort="30" velocity="2"/></joint>
  <joint name="tool" type="fixed"><parent link="link2"/><child link="tip"/><origin xyz="0.3 0 0"/></joint>
</robot>
"""

SPEC = """\
ejs: 1
title: My URDF arm
assets: [robot/planar2.urdf]
imports:
  - from ejsrl.robotics import load_urdf
model:
  variables:
    robot: {expr: "load_urdf('robot/planar2.urdf', tip='tip')"}
    q: {value: [0.5, -0.8]}
    x: 0.0
    z: 0.0
    t: 0.0
  evolution:
    - code: |
        t = t + 0.1
        T = robot.fkine(q)
        x = float(T[0, 3])
        z = float(T[2, 3])
view:
  - scene:
      - robot: {name: arm, model: robot, q: q}
"""


def _folder(tmp_path: Path, urdf: str = URDF) -> Path:
    (tmp_path / "robot" / "meshes").mkdir(parents=True)
    (tmp_path / "robot" / "planar2.urdf").write_text(urdf)
    trimesh.creation.cylinder(radius=0.06, height=0.05).export(tmp_path / "robot" / "meshes" / "base.stl")
    trimesh.creation.box((0.3, 0.03, 0.03)).export(tmp_path / "robot" / "meshes" / "tip.stl")
    spec = tmp_path / "arm.ejs.yaml"
    spec.write_text(SPEC)
    return spec


def test_the_urdfs_meshes_travel_with_it_and_the_app_runs(tmp_path: Path) -> None:
    app = build(_folder(tmp_path), tmp_path / "app")
    assert (app / "robot" / "meshes" / "tip.stl").is_file() and (app / "robot" / "meshes" / "base.stl").is_file()
    out = tmp_path / "run.csv"
    run = subprocess.run([sys.executable, str(app / "app.py"), "--headless", "--steps", "2", "--vars", "t,x,z", "--csv", str(out)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    row = list(csv.DictReader(out.open()))[-1]
    # the links turn about the shoulder's z, which the rpy (pi/2 about x) lays horizontal: the arm
    # moves in the x-z plane, 0.1 m up
    q1, q2 = 0.5, -0.8
    x = 0.4 * math.cos(q1) + 0.3 * math.cos(q1 + q2)
    z = 0.1 + 0.4 * math.sin(q1) + 0.3 * math.sin(q1 + q2)
    assert np.allclose([float(row["x"]), float(row["z"])], [x, z], atol=1e-4), (row, x, z)


@pytest.mark.parametrize("change, words", [
    (lambda u: u[: len(u) // 2], ("robot/planar2.urdf", "not well-formed XML", "at its line")),
    (lambda u: u.replace("meshes/tip.stl", "meshes/elbow.stl"), ("names the mesh 'meshes/elbow.stl'", "not in the spec's folder")),
    (lambda u: u.replace("meshes/tip.stl", "../../outside.stl"), ("names the mesh '../../outside.stl'", "not in the spec's folder")),
    (lambda u: u.replace("<robot name", "<!DOCTYPE r [<!ENTITY a 'x'>]>\n<robot name"), ("DOCTYPE or entities",)),
    (lambda u: u.replace("<robot name=\"planar2\">", "<model>").replace("</robot>", "</model>"), ("<model> at its root, not <robot>",)),
])
def test_a_broken_urdf_is_an_error_at_its_assets_line(tmp_path: Path, change, words) -> None:
    spec = _folder(tmp_path, change(URDF))
    with pytest.raises(SpecErrors) as info:
        build(spec, tmp_path / "app")
    text = str(info.value)
    assert text.startswith("arm.ejs.yaml:3:10: error: ") or "arm.ejs.yaml:3:10: error: " in text, text
    for w in words:
        assert w in text, (w, text)
    assert not (tmp_path / "app").exists()  # nothing half-written
