"""The language reference's generated tables, and the ``ejsgen docs`` command.

``specs/language.md`` is hand-written prose with generated tables between markers::

    <!-- generated: view-elements -->
    ... (made by this module from the pydantic models in ejsgen/spec.py) ...
    <!-- end generated -->

The tables of keys, element kinds and properties (type, default, what it does) come from
the models' fields and docstrings; the prelude and reserved names come from the lists the
compiler checks code against (``ejsgen.validate``, ``ejsgen._resolve``) and the runtime
methods behind them. ``python -m ejsgen._docs`` rewrites the tables in place; a test fails
when the committed file is stale.
"""

from __future__ import annotations

import argparse
import ast
import inspect
import keyword
import re
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ejsgen.errors import EjsError

if TYPE_CHECKING:
    from pydantic import BaseModel

__all__ = [
    "SECTIONS",
    "DOC_FILES",
    "REGENERATE",
    "docs_dir",
    "generate",
    "update",
    "stale_sections",
    "cmd_docs",
]

#: the command that rewrites the generated tables of specs/language.md
REGENERATE = "python -m ejsgen._docs"

#: the user documents, by the name ``ejsgen docs NAME`` takes
DOC_FILES = {"language": "language.md", "tutorial": "tutorial.md", "reference": "reference.md"}

_MARK = re.compile(r"<!-- generated: ([a-z0-9-]+) -->\n(.*?)<!-- end generated -->", re.S)

# How the models' type aliases read in the tables (the aliases are named in spec.py).
_NAMES = {
    "str": "text",
    "float": "number",
    "int": "integer",
    "bool": "true/false",
    "Any": "any value",
    "Expr": "expression",
    "Number": "number",
    "NumOrExpr": "number or expression",
    "BoolOrExpr": "true/false or expression",
    "VecOrExpr": "list or expression",
    "MatOrExpr": "matrix or expression",
    "ColorValue": "colour",
    "Code": "code",
    "EvolutionPage": "page (`ode:` or `code:`)",
}
# Models that have a table of their own: (section title in language.md, anchor)
_MODEL_LINKS = {
    "Model": ("model", "model"),
    "Simulation": ("simulation settings", "simulation"),
    "Program": ("program", "robot-programs"),
    "OdeEvent": ("event", "events"),
    "SeriesEl": ("series", "plot-series"),
    "CodePage": ("code page", "code-pages"),
    "Ode": ("ODE", "ode-pages"),
    "Fmu": ("FMU", "fmus"),
    "Plant": ("plant", "remote-laboratories-plant"),
    "PlantVideo": ("plant video", "the-plants-camera"),
}


# -- formatting ---------------------------------------------------------------------------


def _cell(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|")


def _annotation(cls: type[BaseModel], field: str) -> str:
    """The field's annotation as written in spec.py (the models use postponed annotations)."""
    for base in cls.__mro__:
        ann = getattr(base, "__annotations__", {}).get(field)
        if ann is not None:
            return ann if isinstance(ann, str) else getattr(ann, "__name__", repr(ann))
    return "Any"


def _literal(node: ast.expr, cls: type[BaseModel], field: str) -> str:
    if isinstance(node, ast.Constant):
        return f"`{node.value}`"
    if isinstance(node, ast.Tuple):
        return ", ".join(_literal(e, cls, field) for e in node.elts)
    # Literal[NAME]: the values are in the resolved annotation
    from typing import get_args

    values = get_args(cls.model_fields[field].annotation)
    return ", ".join(f"`{v}`" for v in values)


def _type_text(node: ast.expr, cls: type[BaseModel], field: str) -> str:
    if isinstance(node, ast.Name):
        if node.id in _MODEL_LINKS:
            title, anchor = _MODEL_LINKS[node.id]
            return f"[{title}](#{anchor})"
        if node.id in _NAMES:
            return _NAMES[node.id]
        if node.id.endswith("El"):
            return "mapping"
        return f"`{node.id}`"
    if isinstance(node, ast.Constant) and node.value is None:
        return "none"
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.BitOr):
        parts = [_type_text(n, cls, field) for n in (node.left, node.right)]
        parts = [p for p in parts if p != "none"]  # optional: the default says so
        return " or ".join(parts)
    if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name):
        head, arg = node.value.id, node.slice
        if head == "Literal":
            return "one of " + _literal(arg, cls, field)
        if head == "list":
            inner = _type_text(arg, cls, field)
            if field in ("children", "view"):
                return "list of elements"
            return f"list of {inner}"
        if head == "dict" and isinstance(arg, ast.Tuple) and len(arg.elts) == 2:
            value = arg.elts[1]
            if field == "tabs":
                return "mapping of tab label to list of elements"
            if field == "variables":
                return "mapping of name to value or long form"
            if field == "equations":
                return "mapping of state variable to rate (" + _type_text(value, cls, field) + ")"
            return "mapping of name to " + _type_text(value, cls, field)
        if head in ("Union", "Optional"):
            elts = arg.elts if isinstance(arg, ast.Tuple) else [arg]
            parts = [p for p in (_type_text(e, cls, field) for e in elts) if p != "none"]
            if "number" in parts and "integer" in parts:
                parts.remove("integer")
            return " or ".join(dict.fromkeys(parts))
    return f"`{ast.unparse(node)}`"


def _bounds(info: Any) -> str:
    out = []
    for m in info.metadata:
        for attr, sign in (("gt", ">"), ("ge", "≥"), ("lt", "<"), ("le", "≤")):
            value = getattr(m, attr, None)
            if value is not None:
                out.append(f"{sign} {value:g}" if isinstance(value, float) else f"{sign} {value}")
    return ", ".join(out)


def field_type(cls: type[BaseModel], field: str) -> str:
    """Plain words for a field's type, with its bounds: ``number, > 0``."""
    text = _type_text(ast.parse(_annotation(cls, field), mode="eval").body, cls, field)
    bounds = _bounds(cls.model_fields[field])
    return f"{text}, {bounds}" if bounds else text


def _yaml_value(value: Any) -> str:
    if value is None:
        return "none"
    if value is True:
        return "true"
    if value is False:
        return "false"
    if isinstance(value, float) and value == int(value) and abs(value) < 1e15:
        return f"{value:.1f}" if abs(value) < 1e4 else f"{value:g}"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, str):
        return '""' if value == "" else value
    if isinstance(value, list):
        return "[" + ", ".join(_yaml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{}" if not value else str(value)
    return str(value)


def field_default(cls: type[BaseModel], field: str) -> str:
    """The field's default as it would be written in YAML, or **required**."""
    from pydantic_core import PydanticUndefined

    info = cls.model_fields[field]
    if info.is_required():
        return "**required**"
    if info.default_factory is not None:
        value = info.default_factory()
    else:
        value = info.default
    if value is PydanticUndefined:
        return "**required**"
    if value is None:
        return "—"
    if hasattr(type(value), "model_fields"):  # a pydantic model: its own table lists its defaults
        return "see its table"
    return f"`{_yaml_value(value)}`"


def field_table(cls: type[BaseModel], fields: Sequence[str] | None = None) -> str:
    """A Markdown table of the model's fields: key, type, default, what it does."""
    rows = ["| key | type | default | what it does |", "|---|---|---|---|"]
    for name in fields if fields is not None else cls.model_fields:
        info = cls.model_fields[name]
        rows.append(f"| `{name}` | {field_type(cls, name)} | {field_default(cls, name)} | {_cell(info.description or '')} |")
    return "\n".join(rows) + "\n"


def _doc(cls: type) -> str:
    return _cell((cls.__doc__ or "").strip().split("\n\n")[0])


# -- the sections ---------------------------------------------------------------------------


def _scene_common() -> list[str]:
    """The properties every 3D element has (fields shared by all of them, in order)."""
    from ejsgen.spec import SCENE_ELEMENT_MODELS

    models = list(SCENE_ELEMENT_MODELS.values())
    first = list(models[0].model_fields)
    return [f for f in first if all(f in m.model_fields for m in models)]


def _kinds_table(models: dict[str, type[BaseModel]], extra: dict[str, str] | None = None) -> str:
    rows = ["| kind | what it is |", "|---|---|"]
    for kind, cls in models.items():
        rows.append(f"| [`{kind}`](#{kind}) | {_doc(cls)} |")
    for kind, text in (extra or {}).items():
        rows.append(f"| `{kind}` | {text} |")
    return "\n".join(rows) + "\n"


def _per_kind(models: dict[str, type[BaseModel]], skip: Sequence[str] = ()) -> str:
    out = []
    first = next(iter(models.values()), None)
    for kind, cls in models.items():
        # its own keys, and a common key it gives its own meaning (an ellipse's position: its centre)
        own = [f for f in cls.model_fields if f not in skip or cls.model_fields[f].description != first.model_fields[f].description]  # type: ignore[union-attr]
        out.append(f"#### `{kind}`\n\n{_doc(cls)}\n")
        if own:
            out.append(field_table(cls, own))
        else:
            out.append("No properties of its own.\n")
    return "\n".join(out)


def _signature(fn: Callable[..., Any], name: str) -> str:
    sig = inspect.signature(fn)
    params = [p for p in sig.parameters.values() if p.name != "self"]
    text = ", ".join(str(p.replace(annotation=inspect.Parameter.empty)) for p in params)
    return f"{name}({text})"


def _first_line(fn: Callable[..., Any]) -> str:
    return _cell((inspect.getdoc(fn) or "").split("\n\n")[0].replace("``", "`"))


def _prelude() -> str:
    from ejsrl.sim.model import ModelBase
    from ejsrl.sim.programs import Program

    from ejsgen.validate import CONTROL_NAMES, MATH_NAMES, PROGRAM_COMMANDS

    rows = ["| name | what it does |", "|---|---|", "| `np` | NumPy (`np.array`, `np.linalg.norm`, ...) |"]
    rows.append("| " + " ".join(f"`{n}`" for n in MATH_NAMES) + " | the functions and constants of Python's `math` module |")
    for name in CONTROL_NAMES:
        fn = getattr(ModelBase, name)
        rows.append(f"| `{_signature(fn, name)}` | {_first_line(fn)} |")
    out = "\n".join(rows) + "\n\nIn robot programs only (see [Robot programs](#robot-programs)):\n\n"
    rows = ["| command | what it does |", "|---|---|"]
    for name in PROGRAM_COMMANDS:
        fn = getattr(Program, name)
        rows.append(f"| `{_signature(fn, name)}` | {_first_line(fn)} |")
    return out + "\n".join(rows) + "\n"


def _reserved() -> str:
    import builtins

    from ejsgen._resolve import BUILTIN_NAMES
    from ejsgen.validate import APP_NAMES, MODEL_NAMES, PRELUDE_NAMES

    hidden = sorted(n for n in dir(builtins) if not n.startswith("_") and n not in BUILTIN_NAMES)
    hidden.append("__import__")
    words = sorted(keyword.kwlist)
    model = sorted(n for n in MODEL_NAMES if not n.startswith(("__", "_ejs")) and n not in PRELUDE_NAMES)
    app = sorted(n for n in APP_NAMES if n not in PRELUDE_NAMES)
    return (
        "- The prelude's names (above): " + ", ".join(f"`{n}`" for n in PRELUDE_NAMES) + ".\n"
        "- Python's keywords: " + ", ".join(f"`{w}`" for w in words) + ".\n"
        "- The names the generated model's base class defines: " + ", ".join(f"`{n}`" for n in model) + ", and `self`.\n"
        "- Names starting with `_ejs` (the runtime's own) or `__` (Python's own).\n"
        "- A variable may not have the name of a method the generated model defines for the spec (`_rates`, `_page1`, `_button_go`, ...).\n"
        "\nAn import (`import m as NAME`, `from m import NAME`) may not bind a variable's or custom function's name, "
        "a prelude name, or a name of the generated app's module or methods: " + ", ".join(f"`{n}`" for n in app) + ".\n"
        "\nNot available in spec code (an error says so): " + ", ".join(f"`{n}`" for n in sorted(hidden)) + "; "
        "`open` only reads a file listed under `assets:` (`open('notes.txt')`).\n"
    )


def _methods() -> str:
    from ejsgen.spec import ODE_METHODS, Ode

    default = Ode.model_fields["method"].default
    return ", ".join(f"`{m}`" + (" (default)" if m == default else "") for m in ODE_METHODS) + "\n"


def _vision_signature(obj: Any, name: str) -> str:
    """``name(params)`` with the defaults and the ``*`` before keyword-only parameters,
    without annotations (what a lab's code writes)."""
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):  # a builtin or C function without a signature
        return f"{name}(...)"
    params = [p.replace(annotation=inspect.Parameter.empty) for p in sig.parameters.values() if p.name != "self"]
    return name + str(sig.replace(parameters=params, return_annotation=inspect.Signature.empty))


def _vision_rows(name: str, obj: Any) -> list[str]:
    """Rows of the vision table for one public name: a function, or a class and its public
    methods and properties, or a constant (its kind and size)."""
    if inspect.isclass(obj):
        rows = [f"| `{_vision_signature(obj, name)}` | {_first_line(obj)} |"]
        for attr, member in vars(obj).items():
            if attr.startswith("_"):
                continue
            if isinstance(member, property):
                rows.append(f"| `{name}.{attr}` | {_first_line(member.fget) if member.fget else ''} |")
            elif isinstance(member, (staticmethod, classmethod)) or inspect.isfunction(member):
                fn = getattr(obj, attr)
                rows.append(f"| `{_vision_signature(fn, f'{name}.{attr}')}` | {_first_line(fn)} |")
        return rows
    if callable(obj):
        return [f"| `{_vision_signature(obj, name)}` | {_first_line(obj)} |"]
    import numpy as np

    if isinstance(obj, np.ndarray):
        what = f"array, shape {obj.shape}, {obj.dtype}"
    elif isinstance(obj, dict):
        what = "mapping of " + ", ".join(f"`{k}`" for k in obj)
    else:
        what = f"{type(obj).__name__} of {len(obj)} names" if hasattr(obj, "__len__") else type(obj).__name__
    doc = _constant_doc(name)
    return [f"| `{name}` | {_cell(doc.replace('``', '`')) + ' — ' if doc else ''}{_cell(what)} |"]


def _constant_doc(name: str) -> str:
    """The ``#:`` comment above ``name``'s assignment in the vision package's source (its docstring)."""
    import pkgutil

    import ejsrl.vision as vision

    modules = [vision.__name__] + [f"{vision.__name__}.{m.name}" for m in pkgutil.iter_modules(vision.__path__)]
    pattern = re.compile(rf"^#: (.*)\n{re.escape(name)}\s*[:=]", re.M)
    for module in modules:
        loaded = sys.modules.get(module)  # what ``import ejsrl.vision`` loaded (not the optional numba kernels)
        if loaded is None:
            continue
        try:
            source = inspect.getsource(loaded)
        except (OSError, TypeError):
            continue
        found = pattern.search(source)
        if found:
            return found.group(1).strip()
    return ""


def _vision() -> str:
    """Every public name of ``ejsrl.vision`` (its ``__all__``), grouped by the module that
    defines it (titled by that module's docstring), with signatures and first docstring lines."""
    import importlib

    import ejsrl.vision as vision

    groups: dict[str, list[str]] = {}
    constants: list[str] = []
    for name in vision.__all__:
        obj = getattr(vision, name)
        module = getattr(obj, "__module__", None) if (inspect.isclass(obj) or callable(obj)) else None
        if module is None or not module.startswith("ejsrl.vision"):
            constants.append(name)
        else:
            groups.setdefault(module, []).append(name)
    out = []
    for module, names in groups.items():
        doc = (importlib.import_module(module).__doc__ or module).strip().split("\n\n")[0]
        title = " ".join(doc.split()).rstrip(".")
        rows = ["| name | what it does |", "|---|---|"]
        for name in names:
            rows.extend(_vision_rows(name, getattr(vision, name)))
        out.append(f"#### {title}\n\n`{module}`\n\n" + "\n".join(rows) + "\n")
    rows = ["| name | what it is |", "|---|---|"]
    for name in constants:
        rows.extend(_vision_rows(name, getattr(vision, name)))
    out.append("#### Constants\n\n" + "\n".join(rows) + "\n")
    return "\n".join(out)


def _sections() -> dict[str, Callable[[], str]]:
    from ejsgen import spec
    from ejsgen import _spec2d  # after spec, which registers the drawing element from it
    from ejsgen import _spec_plant

    common = _scene_common()
    return {
        "top-level": lambda: field_table(spec.Spec),
        "variable": lambda: field_table(spec.Variable),
        "model": lambda: field_table(spec.Model),
        "code-page": lambda: field_table(spec.CodePage),
        "ode": lambda: field_table(spec.Ode),
        "ode-methods": _methods,
        "events": lambda: field_table(spec.OdeEvent),
        "evolution-pages": lambda: "`ode:` page\n\n" + field_table(spec.OdePage) + "\n`code:` page\n\n" + field_table(spec.CodeEvolutionPage),
        "program": lambda: field_table(spec.Program),
        "simulation": lambda: field_table(spec.Simulation),
        "fmu": lambda: field_table(spec.Fmu),
        "plant": lambda: field_table(spec.Plant),
        "plant-command": lambda: field_table(_spec_plant.PlantCommand),
        "plant-measurement": lambda: field_table(_spec_plant.PlantMeasurement),
        "plant-video": lambda: field_table(_spec_plant.PlantVideo),
        "view-elements": lambda: _kinds_table(spec.GUI_ELEMENT_MODELS, {"scene": "The 3D world: a list of 3D elements (see [3D elements](#3d-elements))."}),
        "view-properties": lambda: _per_kind(spec.GUI_ELEMENT_MODELS),
        "plot-series": lambda: field_table(spec.SeriesEl),
        "drawing-elements": lambda: _spec2d.docs_kinds(),
        "drawing-properties": lambda: _spec2d.docs_properties(),
        "drag": lambda: _spec2d.docs_drag(),
        "scene-elements": lambda: _kinds_table(spec.SCENE_ELEMENT_MODELS),
        "scene-common": lambda: field_table(spec.SCENE_ELEMENT_MODELS[next(iter(spec.SCENE_ELEMENT_MODELS))], common),
        "scene-properties": lambda: _per_kind(spec.SCENE_ELEMENT_MODELS, skip=common),
        "prelude": _prelude,
        "reserved": _reserved,
        "vision": _vision,
    }


#: the names of the generated sections, each of which language.md must hold once
SECTIONS: tuple[str, ...] = (
    "top-level", "variable", "model", "code-page", "ode", "ode-methods", "events", "evolution-pages",
    "program", "simulation", "fmu", "view-elements", "view-properties", "plot-series", "drawing-elements", "drawing-properties", "drag", "scene-elements",
    "scene-common", "scene-properties", "prelude", "reserved", "vision", "plant", "plant-command", "plant-measurement",
    "plant-video",
)


def generate(name: str) -> str:
    """The Markdown of one generated section."""
    makers = _sections()
    if name not in makers:
        raise EjsError(f"unknown generated section '{name}' (known: {', '.join(makers)})")
    return makers[name]()


def update(text: str) -> str:
    """``text`` with every generated section rewritten from the models.

    Raises ``EjsError`` when a section is unknown, repeated or missing."""
    seen: list[str] = [m.group(1) for m in _MARK.finditer(text)]
    missing = [s for s in SECTIONS if s not in seen]
    repeated = sorted({s for s in seen if seen.count(s) > 1})
    if missing or repeated:
        raise EjsError(f"language reference: missing generated sections {missing}, repeated {repeated}")
    return _MARK.sub(lambda m: f"<!-- generated: {m.group(1)} -->\n{generate(m.group(1))}<!-- end generated -->", text)


def stale_sections(text: str) -> list[str]:
    """The generated sections of ``text`` that differ from what the models say now."""
    return [m.group(1) for m in _MARK.finditer(text) if m.group(2) != generate(m.group(1))]


# -- where the documents are ------------------------------------------------------------------


def docs_dir() -> Path | None:
    """The folder holding language.md and tutorial.md: shipped in the package as
    ``ejsgen.specs`` (wheel installs), else ``specs/`` of the source checkout."""
    try:
        from importlib.resources import files

        shipped = Path(str(files("ejsgen.specs")))
        if (shipped / "language.md").is_file():
            return shipped
    except (ModuleNotFoundError, TypeError):
        pass
    checkout = Path(__file__).resolve().parents[1] / "specs"
    return checkout if (checkout / "language.md").is_file() else None


def cmd_docs(args: argparse.Namespace) -> int:
    """``ejsgen docs [language|tutorial|reference] [--path]``: print a document or its path."""
    folder = docs_dir()
    if folder is None:
        raise EjsError("the documentation is not installed with this copy of ejsgen; see specs/language.md in its source")
    path = folder / DOC_FILES[args.document]
    if not path.is_file():
        raise EjsError(f"{path} is missing from this copy of ejsgen")
    try:
        if args.path:
            print(path)
        else:
            sys.stdout.write(path.read_text(encoding="utf-8"))
            sys.stdout.flush()
    except BrokenPipeError:  # `ejsgen docs | head`: the reader stopped early
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


def add_parser(sub: Any) -> None:
    """Add the ``docs`` subcommand to ``ejsgen``'s subparsers."""
    d = sub.add_parser("docs", help="print the language reference or the tutorial (or, with --path, where it is)")
    d.add_argument("document", nargs="?", default="language", choices=sorted(DOC_FILES), help="which document (default: language)")
    d.add_argument("--path", action="store_true", help="print the file's path instead of its text")


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m ejsgen._docs [FILE]``: rewrite the generated tables of specs/language.md."""
    p = argparse.ArgumentParser(prog="python -m ejsgen._docs", description="Regenerate the tables of the language reference.")
    p.add_argument("file", nargs="?", default=str(Path(__file__).resolve().parents[1] / "specs" / "language.md"))
    args = p.parse_args(argv)
    path = Path(args.file)
    try:
        text = path.read_text(encoding="utf-8")
        new = update(text)
    except (OSError, EjsError) as exc:
        print(f"{path}: error: {exc}", file=sys.stderr)
        return 1
    if new != text:
        path.write_text(new, encoding="utf-8")
        print(f"updated {path}")
    else:
        print(f"{path} is up to date")
    return 0


if __name__ == "__main__":
    sys.exit(main())
