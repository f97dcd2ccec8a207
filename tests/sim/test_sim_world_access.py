"""``sim`` reaches the world only through ``WorldAccess`` (a small typed interface).

The model's world functions and ``capture()`` go through it, the app implements it over
its world binding, and no module of ``ejsrl.sim`` imports the view, the app or the world.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

import ejsrl.sim
from ejsrl.sim.model import Controller
from ejsrl.sim.world_access import WorldAccess, WorldFunctionsAccess
from testkit import imported_modules

ROOT = Path(__file__).resolve().parents[2]
SIM = Path(ejsrl.sim.__file__).parent



@pytest.mark.parametrize("path", sorted(SIM.glob("*.py")), ids=lambda p: p.name)
def test_sim_imports_neither_view_nor_app_nor_world(path: Path) -> None:
    bad = sorted(m for m in imported_modules(path) if m.split(".")[:2] in (["ejsrl", "view"], ["ejsrl", "app"], ["ejsrl", "world"]))
    assert bad == [], f"{path.name} imports {bad}: reach the world through ejsrl.sim.world_access.WorldAccess"


def test_the_app_is_the_models_world_access(tmp_path) -> None:
    from ejsgen.cli import build
    from ejsrl.app import load_app

    app = load_app(build(ROOT / "tests" / "robots" / "specs" / "conveyor.ejs.yaml", tmp_path / "conveyor"))
    assert isinstance(app, WorldAccess)
    assert app.model._ejs_world is app
    functions = app.world_functions()
    assert isinstance(functions, WorldFunctionsAccess)
    # the model's prelude sees what the world functions say
    assert np.array_equal(app.model.object_pose("part1"), functions.object_pose("part1"))
    assert app.model.object_pose("part1")[:3, 3] == pytest.approx([0.2, -0.15, 0.3], abs=1e-12)


class _FakeWorld(Controller):
    """A world that is not an app: a camera that sees grey, one object at the origin."""

    def __init__(self) -> None:
        super().__init__()
        self.calls: list[tuple[str, Any]] = []

    def capture(self, name: str) -> np.ndarray:
        self.calls.append(("capture", name))
        return np.full((2, 3, 3), 128, dtype=np.uint8)

    def world_functions(self) -> Any:
        world = self

        class Functions:
            def object_pose(self, name: str) -> np.ndarray:
                world.calls.append(("object_pose", name))
                return np.eye(4)

            def move_object(self, name: str, pose: Any) -> None:
                world.calls.append(("move_object", name))

            def attach(self, name: str, robot: str, link: int | None = None) -> None:
                world.calls.append(("attach", (name, robot, link)))

            def release(self, name: str) -> None:
                world.calls.append(("release", name))

            def collisions(self) -> list[tuple[str, str]]:
                world.calls.append(("collisions", None))
                return [("a", "b")]

            def graspable_near(self, robot: Any, point: Any, reach: float) -> tuple[str, str] | None:
                return None

        return Functions()


def test_a_model_uses_any_world_access_it_is_given() -> None:
    from ejsrl.sim.model import ModelBase

    world = _FakeWorld()
    assert isinstance(world, WorldAccess)
    model = ModelBase(world, start=False)
    assert model.capture("cam").shape == (2, 3, 3)
    assert np.array_equal(model.object_pose("box"), np.eye(4))
    model.move_object("box", [1.0, 2.0, 3.0])
    model.attach("box", "arm")
    model.release("box")
    assert model.collisions() == [("a", "b")]
    assert world.calls == [("capture", "cam"), ("object_pose", "box"), ("move_object", "box"),
                           ("attach", ("box", "arm", None)), ("release", "box"), ("collisions", None)]


def test_a_model_without_a_world_says_so() -> None:
    from ejsrl.sim.model import ModelBase

    model = ModelBase(start=False)
    with pytest.raises(RuntimeError, match="needs a scene"):
        model.capture("cam")
    with pytest.raises(RuntimeError, match="without a scene"):
        model.object_pose("box")
