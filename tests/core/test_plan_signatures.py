"""Every runtime call a generated app makes fits the runtime's own signature.

The plan holds the app's runtime calls as data (``ejsgen.plan.Call``); nothing in the
compiler writes a runtime signature as text. Two independent checks, over every example:

- the calls of the plan are bound with ``inspect.signature`` of the runtime object the name
  means (positional count and every keyword name);
- the emitted ``app.py`` is parsed, each call of a name it imports from ``ejsrl`` (or of
  ``E.<element>``) is resolved through the app's own imports and bound the same way, and every
  runtime name the app imports is used.
"""

from __future__ import annotations

import ast
import importlib
import inspect
from pathlib import Path
from typing import Any

import pytest

from ejsgen.cli import load_plan
from ejsgen.emit import runtime_callable
from ejsgen.generate import render_app
from testkit import EXAMPLES

SPECS = sorted(EXAMPLES.glob("*.ejs.yaml")) + sorted((EXAMPLES / "paper").glob("*.ejs.yaml")) + sorted((EXAMPLES / "tutorial").glob("*.ejs.yaml"))


def _id(p: Path) -> str:
    return str(p.relative_to(EXAMPLES)).removesuffix(".ejs.yaml")


def _bind(fn: Any, n_args: int, keywords: list[str], what: str) -> None:
    sig = inspect.signature(fn)
    try:
        sig.bind(*([object()] * n_args), **{k: object() for k in keywords})
    except TypeError as exc:
        pytest.fail(f"{what}: {exc} (signature {sig})")


@pytest.mark.parametrize("spec", SPECS, ids=_id)
def test_plan_calls_match_the_runtime_signatures(spec: Path) -> None:
    plan = load_plan(spec)
    calls = plan.calls()
    assert {"SimConfig", "AppMeta"} <= {c.fn for c in calls}
    for call in calls:
        _bind(runtime_callable(call.fn), len(call.args), list(call.kwargs), f"{_id(spec)}: {call.fn}")


def _runtime_names(tree: ast.Module) -> dict[str, Any]:
    """The names app.py binds from the runtime (``from ejsrl.x import Y``, ``... as E``)."""
    out: dict[str, Any] = {}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "ejsrl":
            module = importlib.import_module(node.module)
            for alias in node.names:
                value = getattr(module, alias.name, None)
                if value is None:  # a submodule: from ejsrl.view import elements as E
                    value = importlib.import_module(f"{node.module}.{alias.name}")
                out[alias.asname or alias.name] = value
    return out


def _resolve(func: ast.expr, names: dict[str, Any]) -> tuple[str, Any] | None:
    parts: list[str] = []
    while isinstance(func, ast.Attribute):
        parts.insert(0, func.attr)
        func = func.value
    if not isinstance(func, ast.Name) or func.id not in names:
        return None
    obj = names[func.id]
    for p in parts:
        obj = getattr(obj, p)
    return ".".join([func.id, *parts]), obj


@pytest.mark.parametrize("spec", SPECS, ids=_id)
def test_emitted_runtime_calls_match_the_runtime_signatures(spec: Path) -> None:
    plan = load_plan(spec)
    text = render_app(plan)
    tree = ast.parse(text)
    user = {(a.asname or a.name).split(".")[0] for line in plan.user_imports for n in ast.walk(ast.parse(line)) if isinstance(n, ast.alias) for a in [n]}
    names = {k: v for k, v in _runtime_names(tree).items() if k not in user}  # the spec's own imports are its code's business
    settings = {"SimConfig"} if "\nSIMULATION = SimConfig(" in text else set()  # left out when all run settings are defaults
    assert {"ModelBase", "E", "main", "AppMeta"} | settings <= set(names)
    called: set[str] = set()
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        got = _resolve(node.func, names)
        if got is None or not callable(got[1]):
            continue
        name, fn = got
        called.add(name.split(".")[0])
        starred = any(isinstance(a, ast.Starred) for a in node.args) or any(k.arg is None for k in node.keywords)
        assert not starred, f"{name}: the app should spell its arguments out"
        _bind(fn, len(node.args), [k.arg for k in node.keywords if k.arg], f"{_id(spec)}: app.py line {node.lineno}: {name}")
    unused = set(names) - called - {"ModelBase"}  # ModelBase is the base class, not called
    assert unused == set(), f"app.py imports runtime names it does not use: {sorted(unused)}"


def test_a_call_with_a_keyword_the_runtime_lacks_is_caught() -> None:
    """The check can fail: a slider with a misspelt keyword does not bind."""
    from ejsrl.view import elements as E

    with pytest.raises(pytest.fail.Exception, match="minimum"):
        _bind(E.Slider, 0, ["bind", "minimum"], "E.Slider")


@pytest.mark.parametrize("spec", SPECS, ids=_id)
def test_the_app_imports_only_the_prelude_names_it_uses(spec: Path, tmp_path: Path) -> None:
    """``from math import ...`` and ``import numpy as np`` name only what the app's code uses."""
    from ejsgen.cli import build

    tree = ast.parse((build(spec, tmp_path / "app") / "app.py").read_text())
    imported = {a.asname or a.name for node in tree.body if isinstance(node, ast.ImportFrom) and node.module == "math" for a in node.names}
    imported |= {a.asname or a.name for node in tree.body if isinstance(node, ast.Import) for a in node.names if a.name == "numpy"}
    used = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}
    assert imported - used == set(), f"{_id(spec)}: app.py imports {sorted(imported - used)} and never uses them"
