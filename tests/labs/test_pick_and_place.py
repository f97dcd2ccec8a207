"""The pick-and-place lab: the program places every box at its slot, the arm never touches the table."""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.app import load_app
from testkit import EXAMPLES


@pytest.fixture(scope="module")
def lab_dir(tmp_path_factory):
    from ejsgen.cli import build

    return build(EXAMPLES / "paper" / "pick_and_place.ejs.yaml", tmp_path_factory.mktemp("pp") / "pick_and_place")


@pytest.mark.parametrize("boxes", [3, 5])
def test_every_box_lands_on_its_slot_without_touching_the_table(lab_dir, boxes: int) -> None:
    app = load_app(lab_dir, overrides={"n_objects": boxes})
    model = app.model
    app.play()
    model.start_program("pick_and_place")
    program = model._ejs_programs.programs["pick_and_place"]
    grasped_at = {}
    for _ in range(20000):
        app.step_once()
        if program.grasped is not None:
            grasped_at.setdefault(program.grasped, model.t)
        if program.state != "running":
            break
    assert program.state == "done", program.status()
    assert app.error is None and model.placed == boxes
    assert model.table_hits == 0  # collisions() never reported the arm against the table
    for i in range(boxes):
        box = app.world[f"box{i + 1}"]
        assert box.parent is None  # released
        assert np.allclose(box.T_world()[:3, 3], model.slot(i), atol=1e-6)
        assert np.allclose(box.T_world()[:3, :3], np.eye(3), atol=1e-6)  # the row is neat: no box turned
    assert sorted(grasped_at) == [f"box{i + 1}" for i in range(boxes)]
    assert list(grasped_at.values()) == sorted(grasped_at.values())  # picked in arrival order
    # boxes beyond the chosen number stay hidden and never move
    for i in range(boxes, 6):
        assert not app.world[f"box{i + 1}"].visible
    # the program ends at home, the gripper open
    assert np.allclose(model.q, model.home, atol=1e-9) and model.grip == 1.0


def test_the_belt_stops_boxes_at_the_pick_point_in_a_queue(lab_dir) -> None:
    app = load_app(lab_dir, overrides={"n_objects": 4})
    app.play()
    for _ in range(int(12 / app.model.dt)):
        app.step_once()
    ys = [app.world[f"box{i + 1}"].T_world()[1, 3] for i in range(4)]
    pick_y, gap = app.model.pick[1], app.model.spacing
    assert np.allclose(ys, [pick_y - gap * i for i in range(4)], atol=1e-9)
