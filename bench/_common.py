"""Helpers shared by the benchmarks: build an example and import its generated app."""

from __future__ import annotations

import importlib.util
import sys
import tempfile
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


def build_and_import(spec: Path, out_root: Path | None = None) -> tuple[ModuleType, Path]:
    """Build ``spec`` into a temporary folder and import its app.py as a module."""
    from ejsgen.cli import build

    out_root = out_root or Path(tempfile.mkdtemp(prefix="ejsgen-bench-"))
    out = build(spec, out_root / spec.name.split(".")[0])
    name = f"bench_app_{spec.name.split('.')[0]}"
    mod_spec = importlib.util.spec_from_file_location(name, out / "app.py")
    module = importlib.util.module_from_spec(mod_spec)  # type: ignore[arg-type]
    sys.modules[name] = module
    mod_spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module, out
