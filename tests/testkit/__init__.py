"""The test suite's helpers, in one importable place (``pythonpath = ["tests"]`` in pyproject).

``testkit`` holds paths and process helpers; its modules hold the helpers of one area each:
``clock`` (an injected fake clock), ``browser`` (Chromium through playwright), ``browser_lab``
and ``view_lab`` (small hand-written apps), ``guard_client`` (a raw viser websocket client),
``labs`` (headless runs of the paper labs), ``robots`` (scene bindings of robots) and
``robotics`` (the arm models and fixtures).
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
ARTIFACTS = ROOT / "test-artifacts"


def imported_modules(path: Path) -> set[str]:
    """Every module a Python file imports by absolute name, at its top or inside functions."""
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.add(node.module)
    return out


def run_app(app_dir: Path, *args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    """Run a built app's ``app.py`` with arguments; returns the finished process."""
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    return subprocess.run([sys.executable, str(app_dir / "app.py"), *args], capture_output=True, text=True, timeout=timeout, env=env)


def bench_module(name: str):
    """Import ``bench/<name>.py`` by its path: the checkout itself stays off ``sys.path``."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"bench_{name}", ROOT / "bench" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up while the class is made
    spec.loader.exec_module(module)
    return module
