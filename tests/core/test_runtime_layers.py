"""The runtime's layers: ``ejsrl.app`` split into loop, headless and command line;
``ejsrl.world.render`` one thing (the function); the world binding in ``ejsrl.world``."""

from __future__ import annotations

import importlib
import importlib.util
import io
from pathlib import Path

import numpy as np
import pytest

import ejsrl.app
import ejsrl.world
from testkit import imported_modules

RUNTIME = Path(ejsrl.world.__file__).resolve().parents[1]
SPECS = Path(__file__).parent / "specs"



def test_the_public_names_of_ejsrl_app_stay_where_generated_apps_and_scripts_find_them() -> None:
    assert sorted(ejsrl.app.__all__) == sorted(["App", "SimConfig", "AppMeta", "main", "parse_set", "csv_columns", "load_app", "app_assets", "bundle_assets"])
    for name in ejsrl.app.__all__:
        assert getattr(ejsrl.app, name) is not None
    # the parts of the package
    assert ejsrl.app.App.__module__ == "ejsrl.app._loop"
    assert ejsrl.app.main.__module__ == "ejsrl.app.cli"
    assert ejsrl.app.csv_columns.__module__ == "ejsrl.app.headless"


def test_the_loop_and_headless_runs_do_not_parse_command_lines_or_handle_signals() -> None:
    folder = RUNTIME / "app"
    for name in ("_loop.py", "headless.py"):
        imports = imported_modules(folder / name)
        assert "argparse" not in imports and "ejsrl.app.cli" not in imports, name
    assert "signal" not in imported_modules(folder / "_loop.py")


def test_a_headless_run_is_a_function_of_the_app(tmp_path) -> None:
    from ejsgen.cli import build
    from ejsrl.app.headless import run_headless

    app = ejsrl.app.load_app(build(SPECS / "runtime_checks.ejs.yaml", tmp_path / "checks"))
    out, log = io.StringIO(), io.StringIO()
    assert run_headless(app, 0.5, csv_file=out, variables=["t"], log=log) == 0
    rows = out.getvalue().splitlines()
    assert rows[0] == "t" and float(rows[-1]) == pytest.approx(0.5, abs=1e-9)


def test_world_render_is_only_the_function() -> None:
    assert callable(ejsrl.world.render) and ejsrl.world.render.__name__ == "render"
    assert importlib.util.find_spec("ejsrl.world.render") is None  # no module of that name
    rendering = importlib.import_module("ejsrl.world.rendering")
    assert rendering.render is ejsrl.world.render
    assert np.array_equal(ejsrl.world.BACKGROUND, rendering.BACKGROUND)


def test_the_world_binding_lives_in_the_world_package() -> None:
    from ejsrl.world.binding import SceneSync, scene_elements

    assert SceneSync.__module__ == "ejsrl.world.binding" and callable(scene_elements)
    assert importlib.util.find_spec("ejsrl.view.scene_sync") is None
