"""Shared fixtures: paths, building examples, running built apps."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
ARTIFACTS = ROOT / "test-artifacts"


def imported_modules(path: Path) -> set[str]:
    """Every module a Python file imports by absolute name, at its top or inside functions."""
    import ast

    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.add(node.module)
    return out


def pytest_configure(config: pytest.Config) -> None:
    ARTIFACTS.mkdir(exist_ok=True)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Browser tests share one xdist worker (with ``--dist loadgroup``): one Chromium at a time."""
    for item in items:
        if item.get_closest_marker("browser") is not None:
            item.add_marker(pytest.mark.xdist_group("browser"))


@pytest.fixture(scope="session")
def built(tmp_path_factory: pytest.TempPathFactory):
    """Build an example once per session: ``built("pendulum")`` -> the app folder."""
    from ejsgen.cli import build

    cache: dict[str, Path] = {}

    def _build(name: str) -> Path:
        if name not in cache:
            spec = EXAMPLES / f"{name}.ejs.yaml"
            out = tmp_path_factory.mktemp("apps") / Path(name).name
            cache[name] = build(spec, out)
        return cache[name]

    return _build


def run_app(app_dir: Path, *args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    """Run a built app's ``app.py`` with arguments; returns the finished process."""
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    return subprocess.run([sys.executable, str(app_dir / "app.py"), *args], capture_output=True, text=True, timeout=timeout, env=env)
