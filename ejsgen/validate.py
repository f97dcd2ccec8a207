"""Validate a loaded document against the language, with spec locations in every error.

``validate(doc)`` returns a ``Checked`` spec: the pydantic ``Spec`` plus the view as a tree
of ``ViewItem`` (kind, validated properties, path), and the variables in long form.
Problems are collected and raised together as ``SpecErrors``.
"""

from __future__ import annotations

import keyword
from dataclasses import dataclass, field
from collections.abc import Iterable
from typing import Any

from pydantic import BaseModel, ValidationError

from ejsrl.sim import names as _names

from ejsgen._suggest import did_you_mean, did_you_mean_key
from ejsgen._view_union import SCENE_ELEMENT, VIEW_ELEMENT, gui_models, scene_models, view_adapter
from ejsgen.errors import SpecError, SpecErrors
from ejsgen.spec import GUI_ELEMENT_MODELS, SCENE_ELEMENT_MODELS, Spec, Strict, Variable
from ejsgen.yamlload import Document, Path_

__all__ = [
    "Checked",
    "ViewItem",
    "VarDecl",
    "validate",
    "PRELUDE_NAMES",
    "CONTROL_NAMES",
    "MATH_NAMES",
    "PROGRAM_COMMANDS",
    "MODEL_NAMES",
    "APP_NAMES",
    "model_name_clash",
    "import_name_clash",
    "free_name",
    "prelude_clash",
]

# Every name ejsgen knows about is read from the runtime (ejsrl.sim.names): the prelude from the
# methods of ModelBase and Program marked as prelude names, the reserved names from ModelBase itself.
MATH_NAMES: tuple[str, ...] = _names.MATH_NAMES
CONTROL_NAMES: tuple[str, ...] = _names.control_names()
PROGRAM_COMMANDS: tuple[str, ...] = _names.command_names()
PRELUDE_NAMES: tuple[str, ...] = _names.prelude_names()
#: every attribute of the generated model's base class (a variable or function would replace it)
MODEL_NAMES: frozenset[str] = _names.model_attributes()
#: module globals of the generated app.py, and names bound inside its generated methods
APP_NAMES: frozenset[str] = _names.APP_GLOBALS | frozenset(MATH_NAMES) | _names.METHOD_LOCALS


def free_name(name: str, taken: Iterable[str] = ()) -> str:
    """A name like ``name`` that collides with nothing reserved (nor with ``taken``): ``name_``, ``name_2``..."""
    used = set(taken)
    base = name
    if base.startswith(_names.RUNTIME_PREFIX):
        base = base.removeprefix(_names.RUNTIME_PREFIX).lstrip("_")
    if base.startswith("__"):
        base = base.strip("_")
    base = base or "x"

    def bad(n: str) -> bool:
        return n in used or n in PRELUDE_NAMES or n in MODEL_NAMES or n in APP_NAMES or keyword.iskeyword(n)

    if base != name and not bad(base):
        return base
    candidate, i = base + "_", 2
    while bad(candidate):
        candidate, i = f"{base}_{i}", i + 1
    return candidate


def model_name_clash(name: str, what: str) -> tuple[str, str] | None:
    """Why ``name`` cannot name a ``what`` (a variable, custom function or program), or None.

    Variables and custom functions become attributes of the generated model, so none may take
    a prelude name, a name the model's base class defines, ``self``, or a name the runtime
    keeps for itself (``_ejs...``) or Python mangles (``__...``). Returns (message, hint).
    """
    if name in PRELUDE_NAMES:
        return prelude_clash(name, what)
    if name.startswith(_names.RUNTIME_PREFIX):
        return f"names starting with '{_names.RUNTIME_PREFIX}' are reserved for the runtime ('{name}')", f"rename the {what} (e.g. '{free_name(name)}')"
    if name.startswith("__"):
        return f"names starting with '__' are Python's own or mangled in the generated class ('{name}')", f"rename the {what} (e.g. '{free_name(name)}')"
    if name in MODEL_NAMES or name == "self":
        return f"'{name}' is a name the generated app uses", f"rename the {what} (e.g. '{free_name(name)}')"
    return None


#: what the prelude's constants are, for the message that refuses them as names
_PRELUDE_MEANINGS = {"pi": "the constant π = 3.14159...", "e": "Euler's number 2.71828...", "inf": "infinity", "np": "NumPy"}
#: names that say what authors usually mean by a prelude name they give a variable
_MEANT = {
    "e": ("restitution", "eccentricity"), "log": ("history", "records"), "step": ("h", "step_size"),
    "floor": ("ground", "floor_y"), "degrees": ("angle_deg",), "radians": ("angle_rad",), "exp": ("exponent",),
    "wait": ("delay",), "release": ("released",), "reset": ("restart",), "alert": ("warning",),
}


def prelude_clash(name: str, what: str) -> tuple[str, str]:
    """Why a prelude name cannot name a ``what``, and names to use instead: (message, hint).

    Refused, not shadowed: the prelude name means the same in every block of every spec
    (``e`` is Euler's number in a spec that declares a restitution too), so a lab's code
    reads the same to whoever opens it. The hint offers ``name_`` and, for the names authors
    often mean something else by, names that say what it is.
    """
    if name in _PRELUDE_MEANINGS:
        meaning = _PRELUDE_MEANINGS[name]
    elif name in MATH_NAMES:
        meaning = f"the function {name}() of Python's math module"
    elif name in PROGRAM_COMMANDS:
        meaning = f"the motion command {name}() of robot programs"
    else:
        meaning = f"the prelude's function {name}()"
    others = ", ".join(f"'{n}'" for n in (free_name(name), *_MEANT.get(name, ())))
    return (
        f"'{name}' is a prelude name ({meaning}) and cannot name a {what}: every code block and expression of the spec reads '{name}' as the prelude's",
        f"rename the {what}, e.g. {others}",
    )


def import_name_clash(name: str, variables: Iterable[str], functions: Iterable[str] = ()) -> str | None:
    """Why an import cannot bind ``name`` (it becomes a module global of app.py), or None."""
    if name in set(variables):
        return f"the import binds '{name}', which is also a variable"
    if name in set(functions):
        return f"the import binds '{name}', which is also a custom function"
    if name in PRELUDE_NAMES:
        return f"the import binds '{name}', which is a prelude name"
    if name.startswith(_names.RUNTIME_PREFIX):
        return f"the import binds '{name}'; names starting with '{_names.RUNTIME_PREFIX}' are reserved for the runtime"
    if name in APP_NAMES or name.startswith("__"):
        return f"the import binds '{name}', a name the generated app uses"
    return None


@dataclass
class ViewItem:
    """One element of the view: ``kind``, validated ``props``, ``path`` in the document."""

    kind: str
    props: Any
    path: Path_
    children: list[ViewItem] = field(default_factory=list)
    tabs: list[tuple[str, list[ViewItem]]] = field(default_factory=list)


@dataclass
class VarDecl:
    """A variable in long form, with its ``path`` in the document."""

    name: str
    decl: Variable
    path: Path_


@dataclass
class Checked:
    """A validated spec."""

    doc: Document
    spec: Spec
    variables: list[VarDecl]
    view: list[ViewItem]


_TYPE_WORDS = {
    "float_type": "a number",
    "float_parsing": "a number",
    "int_type": "an integer",
    "int_parsing": "an integer",
    "int_from_float": "an integer",
    "string_type": "text (an expression)",
    "bool_type": "true or false",
    "bool_parsing": "true or false",
    "list_type": "a list",
    "dict_type": "a mapping",
    "model_type": "a mapping",
    "model_attributes_type": "a mapping",
    "literal_error": "one of the allowed values",
}


def _describe(value: Any) -> str:
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, bool):
        return f"{str(value).lower()}"
    if value is None:
        return "nothing (null)"
    return repr(value)


def _data_at(data: Any, path: Path_) -> tuple[Path_, Any]:
    """Follow ``path`` through ``data`` as far as it goes; returns (path followed, value)."""
    followed: list[Any] = []
    cur = data
    for key in path:
        if isinstance(cur, dict) and isinstance(key, str) and key in cur:
            cur = cur[key]
        elif isinstance(cur, list) and isinstance(key, int) and 0 <= key < len(cur):
            cur = cur[key]
        else:
            continue
        followed.append(key)
    return tuple(followed), cur


def pydantic_errors(doc: Document, exc: ValidationError, base: Path_, model: type[BaseModel], data: Any) -> list[SpecError]:
    """Turn a pydantic ``ValidationError`` into spec errors at the right places."""
    return _spec_errors(doc, exc.errors(include_url=False), base, model, data)


def _spec_errors(doc: Document, errors: Iterable[Any], base: Path_, model: type[BaseModel], data: Any) -> list[SpecError]:
    """Spec errors for pydantic's ``errors`` (locations relative to ``data`` at ``base``)."""
    grouped: dict[Path_, list[dict[str, Any]]] = {}
    order: list[Path_] = []
    for err in errors:
        loc = tuple(err["loc"])
        if err["type"] in ("extra_forbidden", "missing"):
            followed = loc
        else:
            followed, _ = _data_at(data, loc)
        key = followed if err["type"] not in ("extra_forbidden", "missing") else loc
        if key not in grouped:
            grouped[key] = []
            order.append(key)
        grouped[key].append(err)
    out: list[SpecError] = []
    for key in order:
        errs = grouped[key]
        types = {e["type"] for e in errs}
        path = base + key
        if "extra_forbidden" in types:
            name = key[-1]
            parent_path, parent_val = _data_at(data, key[:-1])
            fields = _fields_at(model, key[:-1], data)
            hint = did_you_mean_key(str(name), fields)
            allowed = "" if hint else (f"allowed: {', '.join(sorted(fields))}" if fields else "")
            out.append(SpecError(doc.key_loc(path), f"unknown key '{name}'", hint or allowed))
            continue
        if "missing" in types:
            name = key[-1]
            parent, _ = _data_at(data, key[:-1])
            out.append(SpecError(doc.key_loc(base + parent) if parent else doc.loc(base + parent), f"missing required key '{name}'"))
            continue
        _, value = _data_at(data, key)
        lit = [e for e in errs if e["type"] == "literal_error"]
        if lit and isinstance(value, str):
            expected = lit[0].get("ctx", {}).get("expected", "")
            options = [o.strip().strip("'") for o in expected.replace(" or ", ", ").split(",") if o.strip()]
            hint = did_you_mean(value, options)
            field_name = key[-1] if key else ""
            out.append(
                SpecError(doc.loc(path), f"'{value}' is not a valid {field_name}", hint or f"choose one of: {', '.join(options)}")
            )
            continue
        if lit and key == ("ejs",):
            out.append(SpecError(doc.loc(path), f"unsupported format version {_describe(value)}", "this ejsgen reads 'ejs: 1'"))
            continue
        custom = [e for e in errs if e["type"] in ("value_error", "assertion_error")]
        if custom:
            msg = str(custom[0]["msg"]).removeprefix("Value error, ")
            out.append(SpecError(doc.loc(path), msg))
            continue
        bounds = [e for e in errs if e["type"] in ("greater_than", "greater_than_equal", "less_than", "less_than_equal")]
        if bounds:
            msg = str(bounds[0]["msg"]).replace("Input should be", "must be")
            out.append(SpecError(doc.loc(path), f"'{key[-1]}' {msg}, got {_describe(value)}"))
            continue
        words = []
        for e in errs:
            w = _TYPE_WORDS.get(e["type"])
            if w and w not in words:
                words.append(w)
        if "a number" in words and "an integer" in words:
            words.remove("an integer")
        expected = " or ".join(words) if words else errs[0]["msg"]
        what = f"'{key[-1]}'" if key and isinstance(key[-1], str) else "this value"
        hint = ""
        if isinstance(value, (list, dict)) and "text (an expression)" in words:
            hint = "write an expression as text in quotes, e.g. \"[x, 0, y]\""
        out.append(SpecError(doc.loc(path), f"{what} must be {expected}, got {_describe(value)}", hint))
    return out


def _fields_at(model: type[BaseModel], loc: Path_, data: Any) -> list[str]:
    """The field names of the model that validates the mapping at ``loc``."""
    cur: Any = model
    for key in loc:
        if isinstance(key, int):
            continue
        if isinstance(cur, type) and issubclass(cur, BaseModel):
            info = cur.model_fields.get(str(key))
            if info is None:
                return []
            cur = _model_in(info.annotation)
        else:
            return []
    if isinstance(cur, type) and issubclass(cur, BaseModel):
        return list(cur.model_fields)
    return []


def _model_in(annotation: Any) -> Any:
    import typing

    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def _check_name(doc: Document, name: str, path: Path_, what: str, errors: list[SpecError]) -> bool:
    loc = doc.key_loc(path)
    if not name.isidentifier():
        errors.append(SpecError(loc, f"'{name}' is not a valid {what} name", "use letters, digits and _ (not starting with a digit)"))
        return False
    if keyword.iskeyword(name):
        errors.append(SpecError(loc, f"'{name}' is a Python keyword and cannot name a {what}"))
        return False
    clash = model_name_clash(name, what)
    if clash is not None:
        errors.append(SpecError(loc, *clash))
        return False
    return True


def _validate_model(doc: Document, cls: type[Strict], data: Any, path: Path_, errors: list[SpecError]) -> Any:
    if not isinstance(data, dict):
        errors.append(SpecError(doc.loc(path), f"expected a mapping of properties, got {_describe(data)}"))
        return None
    try:
        return cls.model_validate(data)
    except ValidationError as exc:
        errors.extend(pydantic_errors(doc, exc, path, cls, data))
        return None


def _view_items(doc: Document, items: Any, path: Path_, errors: list[SpecError]) -> list[ViewItem]:
    """The view tree, validated in one go by pydantic (``ejsgen._view_union``)."""
    if not isinstance(items, list):
        errors.append(SpecError(doc.loc(path), f"expected a list of view elements, got {_describe(items)}"))
        return []
    try:
        validated = view_adapter.validate_python(items)
    except ValidationError as exc:
        errors.extend(_view_errors(doc, exc.errors(include_url=False), path, items))
        return []
    return _tree(validated, path)


def _tree(items: list[Any], path: Path_) -> list[ViewItem]:
    """ViewItems (with their paths in the document) for a validated list of elements."""
    out: list[ViewItem] = []
    for i, item in enumerate(items):
        (kind,) = item.model_fields_set
        kpath = path + (i, kind)
        props = getattr(item, kind)
        if kind == "scene":
            out.append(ViewItem(kind, None, kpath, children=_tree(props, kpath)))
            continue
        vi = ViewItem(kind, props, kpath)
        if kind == "tabs":
            vi.tabs = [(label, _tree(children, kpath + ("tabs", label))) for label, children in props.tabs.items()]
        elif "children" in type(props).model_fields and kind != "drawing":  # a drawing's 2D children: ejsgen._view_compile2d
            vi.children = _tree(props.children, kpath + ("children",))
        out.append(vi)
    return out


def _element_at(loc: tuple[Any, ...]) -> tuple[Path_, str | None, tuple[Any, ...]]:
    """Split a location in the validated tree into (document path of the innermost element's
    properties, its kind, location inside them); the union's tags are dropped."""
    path: list[Any] = []
    kind: str | None = None
    start = 0
    j = 0
    while j < len(loc):
        path.append(loc[j])
        if isinstance(loc[j], int) and j + 2 < len(loc) and loc[j + 1] == loc[j + 2]:  # index, tag, field
            kind = loc[j + 1]
            path.append(kind)
            j += 3
            start = len(path)
            continue
        j += 1
    return tuple(path[:start]), kind, tuple(path[start:])


def _view_errors(doc: Document, errs: list[Any], base: Path_, data: Any) -> list[SpecError]:
    """Spec errors for pydantic's errors in the view tree, worded as for a hand walk."""
    out: list[SpecError] = []
    grouped: dict[Path_, tuple[str, list[dict[str, Any]]]] = {}
    for err in errs:
        element, kind, inner = _element_at(tuple(err["loc"]))
        if err["type"] in (VIEW_ELEMENT, SCENE_ELEMENT):
            ipath = element + inner
            _, item = _data_at(data, ipath)
            out.append(_item_error(doc, item, base + ipath, scene=err["type"] == SCENE_ELEMENT))
            continue
        assert kind is not None
        if not inner:  # the element's value itself
            _, value = _data_at(data, element)
            what = "a list of 3D elements" if kind == "scene" else "a mapping of properties"
            out.append(SpecError(doc.loc(base + element), f"expected {what}, got {_describe(value)}"))
            continue
        grouped.setdefault(element, (kind, []))[1].append({**err, "loc": inner})
    for element, (kind, kind_errs) in grouped.items():
        model = scene_models.get(kind) or gui_models[kind]
        _, props = _data_at(data, element)
        out.extend(_spec_errors(doc, kind_errs, base + element, model, props))
    return out


def _item_error(doc: Document, item: Any, ipath: Path_, *, scene: bool) -> SpecError:
    """Why ``item`` is not an element of its list (a scene's if ``scene``, else the view's)."""
    kinds = SCENE_ELEMENT_MODELS if scene else {**GUI_ELEMENT_MODELS, "scene": None}
    where = "3D element" if scene else "view element"
    if isinstance(item, dict) and len(item) > 1 and next(iter(item)) in kinds:
        return _misplaced_key(doc, item, ipath, kinds)
    if not isinstance(item, dict) or len(item) != 1:
        return SpecError(doc.loc(ipath), f"each {where} is a one-key mapping 'kind: {{properties}}'", f"kinds: {', '.join(kinds)}")
    (kind,) = item
    kpath = ipath + (kind,)
    other = GUI_ELEMENT_MODELS if scene else SCENE_ELEMENT_MODELS
    if kind in other:
        msg = f"'{kind}' is a {'GUI' if scene else '3D'} element and cannot stand {'in a scene' if scene else 'outside a scene'}"
        return SpecError(doc.key_loc(kpath), msg)
    return SpecError(doc.key_loc(kpath), f"unknown {where} kind '{kind}'", did_you_mean(str(kind), kinds) or f"kinds: {', '.join(kinds)}")


def _misplaced_key(doc: Document, item: dict[str, Any], ipath: Path_, kinds: dict[str, Any]) -> SpecError:
    """A '- ' item with a second key: a property indented like its element, or two elements."""
    kind, other = list(item)[:2]
    where = doc.key_loc(ipath + (other,))
    if other in kinds:
        return SpecError(where, f"'{other}' and '{kind}' are in one '- ' item", f"start '{other}' on its own line with '- '")
    return SpecError(
        where,
        f"'{other}' is indented like '{kind}', so it stands beside the element instead of being one of its properties",
        f"indent '{other}' under '{kind}', like its other properties",
    )


def validate(doc: Document) -> Checked:
    """Check a loaded document against the language; raises ``SpecErrors``."""
    errors: list[SpecError] = []
    data = doc.data
    if not isinstance(data, dict):
        raise SpecErrors([SpecError(doc.loc(()), "a spec is a mapping with 'ejs', 'title', 'model' and 'view'")])
    try:
        spec = Spec.model_validate(data)
    except ValidationError as exc:
        raise SpecErrors(pydantic_errors(doc, exc, (), Spec, data)) from None

    variables: list[VarDecl] = []
    for name, raw in spec.model.variables.items():
        vpath = ("model", "variables", name)
        if not _check_name(doc, name, vpath, "variable", errors):
            continue
        if isinstance(raw, dict):
            decl = _validate_model(doc, Variable, raw, vpath, errors)
            if decl is None:
                continue
        else:
            decl = Variable(value=raw)
        variables.append(VarDecl(name, decl, vpath))

    seen_programs = {v.name for v in variables}
    for pname in spec.model.programs:
        ppath = ("model", "programs", pname)
        if _check_name(doc, pname, ppath, "program", errors) and pname in seen_programs:
            errors.append(SpecError(doc.key_loc(ppath), f"the program '{pname}' has the name of a variable"))

    view = _view_items(doc, data.get("view", []), ("view",), errors)
    if errors:
        raise SpecErrors(errors)
    return Checked(doc, spec, variables, view)
