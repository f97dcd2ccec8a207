"""The URDF arm example (examples/urdf_arm.ejs.yaml), built and run as a student would.

References: Pinocchio's poses of the same URDF (fixtures/urdf_pinocchio.json) and the STL
files read with trimesh directly, not through the runtime."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
import trimesh

from ejsrl.robotics import models
from ejsrl.view.elements import Folder, Slider
from testkit import run_app
from testkit.robotics import FIXTURES
from testkit.robots import load_built

REF = json.loads((FIXTURES / "urdf_pinocchio.json").read_text())["arms"]["ur5"]["rows"]
STL = ["base", "shoulder", "upperarm", "forearm", "wrist1", "wrist2", "wrist3"]


@pytest.fixture(scope="module")
def app_dir(built):
    return built("urdf_arm")


def test_urdf_example_runs_headless_and_its_tool_pose_is_pinocchios(app_dir) -> None:
    row = REF[0]
    q_deg = np.degrees(row["q"]).tolist()
    res = run_app(app_dir, "--headless", "--duration", "0.5", "--csv", "-", "--vars", "t,T_tool,manip",
                  "--set", f"q_deg={q_deg}", timeout=180)
    assert res.returncode == 0, res.stderr
    d = np.genfromtxt(io.StringIO(res.stdout), delimiter=",", names=True, deletechars="")
    T = np.array([[d[f"T_tool[{i}][{j}]"][-1] for j in range(4)] for i in range(4)])
    np.testing.assert_allclose(T, row["T"], atol=1e-12)
    J = np.array(row["J"])
    np.testing.assert_allclose(d["manip"][-1], np.sqrt(np.linalg.det(J @ J.T)), rtol=1e-9)
    assert "yourdfpy" in (app_dir / "requirements.txt").read_text()


def test_urdf_example_draws_the_urdf_meshes_at_the_link_frames(app_dir) -> None:
    app = load_built(app_dir)
    q = np.array(REF[1]["q"])
    sliders = {el.bind: el for folder in app.view if isinstance(folder, Folder) for el in folder.children
               if isinstance(el, Slider)}
    for j in range(6):  # as a student drags the sliders (the fixed relations run after each)
        app.apply_control(sliders[f"q_deg[{j}]"], float(np.degrees(q[j])))
    app.frame()
    assert app.error is None
    robot = models.ur5_urdf()
    F = robot.fkine_all(q)
    urdf_turns = robot.urdf_frames  # the URDF link frame of model frame i is F[i] @ turn[i].T
    for i, name in enumerate(STL):
        node = app.world[f"ur5.link{i}"]
        np.testing.assert_allclose(node.T_world(), F[i], atol=1e-12)
        ref = trimesh.load(models.UR5_URDF.parent / "meshes" / f"{name}.stl", force="mesh", process=False)
        (part,) = node.parts()
        assert len(part.vertices) == len(ref.vertices)
        T_urdf = F[i] @ np.linalg.inv(urdf_turns[i])
        world_drawn = part.vertices @ F[i][:3, :3].T + F[i][:3, 3]
        world_ref = np.asarray(ref.vertices) @ T_urdf[:3, :3].T + T_urdf[:3, 3]
        np.testing.assert_allclose(np.sort(world_drawn, axis=0), np.sort(world_ref, axis=0), atol=1e-9)
        assert part.rgb is not None
    # the drawn tool flange frame is the URDF's tool0, 0.0823 m past wrist 3
    np.testing.assert_allclose(app.world.T_world("tool_frame"), np.array(REF[1]["T"]), atol=1e-12)


def test_urdf_example_demo_follows_the_mstraj_path(app_dir) -> None:
    app = load_built(app_dir)
    app.model.demo = True
    for _ in range(5):
        app.step_once()
    assert app.error is None
    np.testing.assert_allclose(app.model.q_deg, app.model.path[5])
    np.testing.assert_allclose(app.world.T_world("ur5.link6"),
                               models.ur5_urdf().fkine_all(np.radians(app.model.path[5]))[6], atol=1e-12)
