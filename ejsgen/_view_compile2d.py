"""Compile the ``drawing`` element (a 2D panel) and the ``keyboard`` element into runtime records.

A drawing becomes ``E.Drawing(children=[E.Shape2D(...), ...], keys={...})``; each child's
properties become constants or ``E.Dynamic`` as the other elements' do. The children are
validated here, kind by kind (``ejsgen._spec2d.CHILD_MODELS``), so that every mistake is
reported at its FILE:LINE:COL: an unknown kind or property, a position whose shape is not
[x, y] or N x 2, a drag bound to something that is not a variable, a key the browser does
not report, a curve that is not a custom function.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Any

from ejsgen._shapes import infer_shape
from ejsgen._spec2d import CHILD_MODELS, KEY_ALIASES, KEY_NAMES, key_schema_note
from ejsgen._spec2d_mobile import compile_prop as compile_mobile_prop
from ejsgen._suggest import did_you_mean
from ejsgen.errors import SpecError
from ejsgen.plan import Call, Src
from ejsgen.validate import ViewItem, _validate_model
from ejsgen.yamlload import Path_

if TYPE_CHECKING:
    from ejsgen._view_compile import ViewCompiler

__all__ = ["compile_drawing", "compile_keyboard"]

_NAME = re.compile(r"[A-Za-z0-9_.:\-]{1,64}")
#: properties holding a point [x, y] (or N x 2 for a set)
_POINT_PROPS = ("position", "start", "end", "vector", "point")
_NUM_PROPS = ("size", "radius", "width", "head", "spacing")
_COLOR_PROPS = ("fill", "stroke")
_PLAIN_PROPS = ("shape", "align", "coils", "max_points")
#: the kinds that can be dragged, and those whose drag may take the end (handle: end)
_DRAGGABLE = ("point", "particle", "circle", "segment", "arrow", "spring", "text", "image", "vehicle")
_TWO_ENDS = ("segment", "arrow", "spring")
#: the kinds that may be sets (position N x 2)
_SETS = ("point", "particle", "circle", "segment", "arrow")


def _slug(text: str) -> str:
    return re.sub(r"\W+", "_", text.lower()).strip("_")[:30].strip("_") or "x"


def _key_name(vc: ViewCompiler, key: Any, path: Path_) -> str | None:
    """The key's name in the runtime's ``keys`` (aliases resolved), or None after an error."""
    text = str(key)
    name = KEY_ALIASES.get(text, text)
    if name in KEY_NAMES:
        return name
    close = did_you_mean(text, [*KEY_NAMES, *KEY_ALIASES]) or did_you_mean(text.capitalize(), [*KEY_NAMES])
    vc.c.errors.append(SpecError(vc.c.doc.key_loc(path), f"'{text}' is not a key a panel can report", close or f"keys: {key_schema_note()}"))
    return None


def _keys(vc: ViewCompiler, keys: dict[str, Any], path: Path_, base: str) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, code in keys.items():
        kpath = path + ("keys", key)
        name = _key_name(vc, key, kpath)
        if name is None:
            continue
        if name in out:
            vc.c.errors.append(SpecError(vc.c.doc.key_loc(kpath), f"the key '{name}' is mapped twice"))
            continue
        action = vc.code(f"_{base}_key_{_slug(name if len(name) > 1 else f'{name}_{ord(name)}')}", code, kpath, f"the action of key '{name}'")
        if action is not None:
            out[name] = action
    return out


def _point(vc: ViewCompiler, value: Any, path: Path_, what: str, *, sets: bool) -> Any:
    """[x, y] (numbers or expressions), or an expression giving [x, y] (or N x 2 if ``sets``)."""
    c = vc.c
    if isinstance(value, str):
        res = c.expr_source(path, what)
        if res is None:
            return None
        shape = infer_shape(res[1], c.var_shapes)
        ok = shape is None or shape == (2,) or (sets and len(shape) == 2 and shape[1] == 2)
        if not ok:
            need = "[x, y] or an N x 2 array" if sets else "[x, y]"
            hint = "a 2 x N array: transpose it with .T" if len(shape) == 2 and shape[0] == 2 else ""
            c.errors.append(SpecError(c.loc(path), f"{what} must be {need}, but '{value}' has shape {shape}", hint or c.text_hint(value)))
            return None
        return vc.dynamic(path, "", what, value)
    return vc.vector(value, path, "", what, 2)


def _points(vc: ViewCompiler, value: Any, path: Path_, what: str) -> Any:
    """A list of [x, y] rows, or an expression giving an N x 2 array."""
    c = vc.c
    if isinstance(value, str):
        res = c.expr_source(path, what)
        if res is None:
            return None
        shape = infer_shape(res[1], c.var_shapes)
        if shape is not None and not (len(shape) == 2 and shape[1] == 2):
            hint = "a 2 x N array: transpose it with .T" if len(shape) == 2 and shape[0] == 2 else c.text_hint(value) or "np.column_stack([xs, ys]) makes one"
            c.errors.append(SpecError(c.loc(path), f"{what} must be an N x 2 array of [x, y] rows, but '{value}' has shape {shape}", hint))
            return None
        return vc.dynamic(path, "", what, value)
    for i, row in enumerate(value):
        if len(row) != 2:
            c.errors.append(SpecError(c.loc(path + (i,)), f"{what}: each point is [x, y], but row {i + 1} has {len(row)} numbers"))
            return None
    return vc.matrix(value, path, "", what, None)


def _number(vc: ViewCompiler, value: Any, path: Path_, what: str, *, positive: bool) -> Any:
    if not isinstance(value, str) and positive and not value > 0:
        vc.c.errors.append(SpecError(vc.c.loc(path), f"{what} must be above 0, got {value}"))
        return None
    return vc.number(value, path, "", what)


def _limits(vc: ViewCompiler, target: str) -> tuple[float | None, float | None]:
    """The declared ``min`` and ``max`` of the variable a drag writes (of its array, for ``p[0]``)."""
    decl = vc.c.var_decls.get(target.split("[")[0].strip())
    if decl is None:
        return (None, None)
    lo, hi = getattr(decl.decl, "min", None), getattr(decl.decl, "max", None)
    return (None if lo is None else float(lo), None if hi is None else float(hi))


def _curve(vc: ViewCompiler, text: str, path: Path_) -> Src | None:
    """``curve(model, x, y)``: a custom function's name, or a lambda of the pointer's (x, y)
    (``lambda px, py: [px, 0.1*px**2]``), giving the point of the curve."""
    import ast

    c = vc.c
    fn = text.removesuffix("()")
    if fn.isidentifier():
        if fn not in c.names.functions:
            c.errors.append(SpecError(c.loc(path), f"the curve '{text}' is not a function of custom code",
                                      did_you_mean(fn, c.names.functions) or "define def on_curve(x, y): ... return [x, y] under model: custom:"))
            return None
        return Src(f"lambda self, x, y: self.{fn}(x, y)")
    try:
        node = ast.parse(text, mode="eval").body
    except SyntaxError:
        node = None
    if not (isinstance(node, ast.Lambda) and len(node.args.args) == 2 and not node.args.defaults):
        c.errors.append(SpecError(c.loc(path), f"a curve is the name of a custom function, or a lambda of the pointer's x and y, got '{text}'",
                                  "e.g. curve: 'lambda px, py: [px, 0.1*px**2]' (the parabola under the pointer)"))
        return None
    res = c.expr_source(path, "the drag's curve")
    if res is None:
        return None
    return Src(f"lambda self, x, y: ({res[0]})(x, y)")


def _drag(vc: ViewCompiler, kind: str, name: str, d: Any, path: Path_) -> Call | None:
    c = vc.c
    if kind not in _DRAGGABLE:
        c.errors.append(SpecError(c.loc(path), f"a {kind} cannot be dragged", f"draggable: {', '.join(_DRAGGABLE)}"))
        return None
    kw: dict[str, Any] = {}
    along = d.along
    if isinstance(d.bind, list):
        if len(d.bind) != 2:
            c.errors.append(SpecError(c.loc(path + ("bind",)), f"a drag binds [x_variable, y_variable], got {len(d.bind)} names"))
            return None
        vtypes = []
        for j, target in enumerate(d.bind):
            b = vc.bind(target, path + ("bind", j), "drag")
            if b is None:
                return None
            vtypes.append(b[2])
            if b[2] not in ("float", "int"):
                c.errors.append(SpecError(c.loc(path + ("bind", j)), f"a drag writes numbers, but '{target}' is {b[2]}",
                                          "bind one element of an array, like p[0]" if b[2] == "array" else ""))
                return None
        kw["bind"] = tuple(d.bind)
        limits = tuple(_limits(vc, target) for target in d.bind)
        if any(lim != (None, None) for lim in limits):
            kw["limits"] = limits
        ints = tuple(v == "int" for v in vtypes)
        if any(ints):
            kw["ints"] = ints
    else:
        b = vc.bind(d.bind, path + ("bind",), "drag")
        if b is None:
            return None
        var = d.bind.split("[")[0].strip()
        shape = c.var_shapes.get(var)
        if b[2] == "array" and "[" not in d.bind:
            if kind not in _SETS:
                c.errors.append(SpecError(c.loc(path + ("bind",)), f"'{d.bind}' is an array: only a set (a {', '.join(_SETS)} whose position is N x 2) is dragged by rows of one array"))
                return None
            if shape is not None and not (len(shape) == 2 and shape[1] == 2):
                c.errors.append(SpecError(c.loc(path + ("bind",)), f"a set is dragged by the rows of an N x 2 array, but '{var}' has shape {shape}"))
                return None
        elif along not in ("x", "y"):
            c.errors.append(SpecError(c.loc(path + ("bind",)), f"one variable ('{d.bind}') is one coordinate: say which with along: x or along: y",
                                      f"or bind both: bind: [{d.bind}, y_variable]"))
            return None
        kw["bind"] = (d.bind,)
        if b[2] != "array":
            lim = _limits(vc, d.bind)
            if lim != (None, None):
                kw["limits"] = (lim,)
            if b[2] == "int":
                kw["ints"] = (True,)
    if along == "curve":
        if d.curve is None:
            c.errors.append(SpecError(c.loc(path + ("along",)), "along: curve needs curve: the name of a custom function f(x, y) -> [x, y]"))
            return None
        curve = _curve(vc, d.curve.strip(), path + ("curve",))
        if curve is None:
            return None
        kw["curve"] = curve
    elif d.curve is not None:
        c.errors.append(SpecError(c.loc(path + ("curve",)), "curve: is used with along: curve", "add along: curve"))
        return None
    if along == "region" and d.region is None:
        c.errors.append(SpecError(c.loc(path + ("along",)), "along: region needs region: [xmin, xmax, ymin, ymax]"))
        return None
    if d.region is not None:
        region = vc.vector(d.region, path + ("region",), "", "the drag's region", 4)
        if region is None:
            return None
        if isinstance(region, tuple) and not (region[0] < region[1] and region[2] < region[3]):
            c.errors.append(SpecError(c.loc(path + ("region",)), "a region is [xmin, xmax, ymin, ymax] with xmin < xmax and ymin < ymax"))
            return None
        kw["region"] = region
    if d.handle == "end" and kind not in _TWO_ENDS:
        c.errors.append(SpecError(c.loc(path + ("handle",)), f"a {kind} has one point to drag; handle: end is for {', '.join(_TWO_ENDS)}"))
        return None
    kw["along"] = along
    kw["handle"] = d.handle
    for key in ("on_drag", "on_release"):
        code = getattr(d, key)
        if code is not None:
            kw[key] = vc.code(f"_drag_{_slug(name)}_{key.removeprefix('on_')}", code, path + (key,), f"the {key} of '{name}'")
    return Call("E.Drag2D", [], kw)


def _child(vc: ViewCompiler, raw: Any, path: Path_, names: set[str], counts: dict[str, int]) -> Call | None:
    c = vc.c
    kinds = ", ".join(CHILD_MODELS)
    if not isinstance(raw, dict) or len(raw) != 1:
        c.errors.append(SpecError(c.loc(path), "each 2D element is a one-key mapping 'kind: {properties}'", f"kinds: {kinds}"))
        return None
    ((kind, data),) = raw.items()
    kpath = path + (kind,)
    model = CHILD_MODELS.get(kind)
    if model is None:
        c.errors.append(SpecError(c.doc.key_loc(kpath), f"unknown 2D element kind '{kind}'", did_you_mean(str(kind), CHILD_MODELS) or f"kinds: {kinds}"))
        return None
    p = _validate_model(c.doc, model, data, kpath, c.errors)
    if p is None:
        return None
    name = p.name
    if name is None:
        counts[kind] = counts.get(kind, 0) + 1
        name = f"{kind}{counts[kind]}"
        while name in names:
            counts[kind] += 1
            name = f"{kind}{counts[kind]}"
    elif not _NAME.fullmatch(name):
        c.errors.append(SpecError(c.loc(kpath + ("name",)), f"the name '{name}' may hold letters, digits, _ . : - only (at most 64)"))
        return None
    elif name in names:
        c.errors.append(SpecError(c.loc(kpath + ("name",)), f"the panel already has an element named '{name}'"))
        return None
    names.add(name)
    props: dict[str, Any] = {}
    ok = True
    for prop in model.model_fields:
        if prop in ("name", "visible", "color", "drag"):
            continue
        value = getattr(p, prop)
        if prop not in p.model_fields_set or value is None:
            continue  # the runtime's default
        ppath = kpath + (prop,)
        what = f"the {prop} of {kind} '{name}'"
        handled, got = compile_mobile_prop(vc, kind, prop, value, ppath, what)  # issue #27's kinds
        if handled:
            pass
        elif prop == "size" and kind == "image":
            got = vc.vector(value, ppath, "", what, 2)
        elif prop in _POINT_PROPS:
            got = _point(vc, value, ppath, what, sets=kind in _SETS)
        elif prop == "points":
            got = _points(vc, value, ppath, what)
        elif prop in _NUM_PROPS:
            got = _number(vc, value, ppath, what, positive=prop != "radius" or kind == "circle")
        elif prop in _COLOR_PROPS:
            got = vc.color(value, ppath, "")
        elif prop == "text":
            got = vc.interpolated(ppath, value, "", what)
        elif prop == "source":
            got = vc.dynamic(ppath, "", what, value)
        elif prop == "file":
            got = c.asset(value, ppath, "image file")
        else:
            got = value
        if got is None:
            ok = False
            continue
        props[prop] = got
    if kind == "image":
        if (p.source is None) == (p.file is None):
            c.errors.append(SpecError(c.loc(kpath), "an image takes source: (an array expression) or file: (an image file), one of them"))
            ok = False
    kw: dict[str, Any] = {"kind": kind, "name": name, "props": props}
    if "visible" in p.model_fields_set:
        kw["visible"] = vc.dynamic(kpath + ("visible",), "", f"the visibility of '{name}'", p.visible) if isinstance(p.visible, str) else bool(p.visible)
    if p.color is not None:
        kw["color"] = vc.color(p.color, kpath + ("color",), "")
    if p.drag is not None:
        drag = _drag(vc, kind, name, p.drag, kpath + ("drag",))
        if drag is None:
            ok = False
        else:
            kw["drag"] = drag
    if not ok:
        return None
    kw["where"] = c.where(kpath)
    return Call("E.Shape2D", [], kw)


def compile_drawing(vc: ViewCompiler, item: ViewItem, n: int) -> Call | None:
    """``E.Drawing(...)`` for a ``drawing`` element (its children validated and compiled here)."""
    from ejsrl.world.colors import CSS_COLORS, is_color_literal

    c, p, path = vc.c, item.props, item.path
    kw: dict[str, Any] = {}
    kw["title"] = vc.interpolated(path + ("title",), p.title, "", "the drawing's title")
    for axis in ("x_range", "y_range"):
        value = getattr(p, axis)
        got = vc.vector(value, path + (axis,), "", f"the drawing's {axis}", 2)
        if isinstance(got, tuple) and not got[0] < got[1]:
            c.errors.append(SpecError(c.loc(path + (axis,)), f"{axis} is [min, max] with min < max, got {list(value)}"))
        kw[axis] = got
    if not is_color_literal(p.background):
        c.errors.append(SpecError(c.loc(path + ("background",)), f"unknown colour '{p.background}'", did_you_mean(p.background, CSS_COLORS) or "use a CSS name or '#rrggbb'"))
    kw.update(aspect=p.aspect, height=p.height, axes=p.axes, grid=p.grid, x_label=p.x_label, y_label=p.y_label, background=p.background)
    base = f"drawing{n}"
    kw["keys"] = _keys(vc, p.keys, path, base)
    names: set[str] = set()
    counts: dict[str, int] = {}
    children = [_child(vc, raw, path + ("children", i), names, counts) for i, raw in enumerate(p.children)]
    kw["children"] = [ch for ch in children if ch is not None]
    kw["where"] = c.where(path)
    return Call("E.Drawing", [], kw, children="children")


def _has_scene(items: Any) -> bool:
    """Whether a view's raw list (with folders and tabs) holds a ``scene``."""
    for it in items if isinstance(items, list) else ():
        if not isinstance(it, dict):
            continue
        if "scene" in it:
            return True
        props = next(iter(it.values()), None) if len(it) == 1 else None
        if isinstance(props, dict):
            if _has_scene(props.get("children")) or any(_has_scene(ch) for ch in (props.get("tabs") or {}).values()):
                return True
    return False


def compile_keyboard(vc: ViewCompiler, item: ViewItem, n: int) -> Call | None:
    """``E.SceneKeys(keys={...})`` for a ``keyboard`` element (the 3D view's keys)."""
    if not _has_scene(vc.c.doc.data.get("view")):
        vc.c.errors.append(SpecError(vc.c.doc.key_loc(item.path), "a keyboard acts on the 3D view, and this view has no scene",
                                     "give the keys to a drawing panel instead: drawing: {keys: {...}}"))
        return None
    keys = _keys(vc, item.props.keys, item.path, f"keyboard{n}")
    return Call("E.SceneKeys", [], {"keys": keys, "where": vc.c.where(item.path)})
