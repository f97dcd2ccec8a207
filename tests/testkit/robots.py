"""Helpers for the robot tests: scenes made from view records, with a plain model object."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from ejsrl.view.elements import Dynamic, Node3D
from ejsrl.world.binding import SceneSync
from ejsrl.world.functions import WorldFunctions


def dyn(expr: str) -> Dynamic:
    """A dynamic property reading an attribute (or item expression) of the model: ``dyn("q")``."""
    return Dynamic(lambda m: eval(expr, {"np": np}, vars(m)), expr)  # noqa: S307 - test expressions only


def robot(name: str, model: str = "robot", q: str = "q", **kw: Any) -> Node3D:
    """A robot element whose model and joints are the model attributes ``model`` and ``q``."""
    props = {"model": dyn(model), "q": dyn(q)}
    for key in ("base", "meshes", "show_frames"):
        if key in kw:
            props[key] = kw.pop(key)
    return Node3D(kind="robot", name=name, props=props, **kw)


def scene(*elements: Node3D, model: Any, base_dir: Path | str = ".") -> tuple[SceneSync, WorldFunctions]:
    """Build the world of ``elements``, show ``model`` once (as an app's first frame)."""
    sync = SceneSync(list(elements), base_dir=base_dir)
    sync.update(model, first=True)
    return sync, WorldFunctions(sync, model)


def random_q(robot: Any, rng: np.random.Generator) -> np.ndarray:
    """Joint values drawn uniformly within the robot's limits (±pi where unlimited)."""
    lim = np.where(np.isfinite(robot.qlim), robot.qlim, np.array([[-np.pi], [np.pi]]))
    return rng.uniform(lim[0], lim[1])


def load_built(app_dir: Path) -> Any:
    """Import a built app's ``app.py`` and make its ``App`` (not serving, not playing)."""
    from ejsrl.app import App, SimConfig

    name = f"robots_app_{abs(hash(str(app_dir)))}"
    spec = importlib.util.spec_from_file_location(name, app_dir / "app.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return App(module.Model, module.VIEW, sim=getattr(module, "SIMULATION", SimConfig()), meta=module.META, base_dir=app_dir)


Model = SimpleNamespace
