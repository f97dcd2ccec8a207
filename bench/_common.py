"""Helpers shared by the benchmarks: build an example and import its generated app."""

from __future__ import annotations

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
    from ejsrl.app import load_app

    return sys.modules[load_app(out).model_cls.__module__], out
