"""Compile the view: each element becomes an ``ejsrl.view.elements`` record in ``VIEW``.

Each element becomes a :class:`~ejsgen.plan.Call` of its runtime record. A dynamic property
(an expression) is ``E.Dynamic(lambda self: [self.x, 0, self.y], "[x, 0, y]")``, or
``E.Dynamic("t")`` when it is just a variable (or an element, ``q[2]``), which the runtime
reads itself, as it does ``bind:`` targets. An action or ``on_change`` that is one bare call
(``kick()``) is that method (``Model.kick``); other code becomes a method named after its
element (``_button_solve``).
"""

from __future__ import annotations

import ast
import re
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ejsgen._interpolate import BraceError, split_fields
from ejsgen._shapes import infer_shape, literal_shape
from ejsgen._view_compile_plot import compile_plot
from ejsgen._view_compile3d import check_follows, check_view
from ejsgen._suggest import did_you_mean
from ejsgen.errors import Location, SpecError
from ejsgen.plan import Call, Expr, Ref, Src
from ejsgen.validate import ViewItem
from ejsgen.yamlload import Path_, TextOrigin
from ejsrl.world.kinds import KINDS

if TYPE_CHECKING:
    from ejsgen.compiler import Compiler

__all__ = ["ViewCompiler"]

#: kind -> {property: property type} of the values the compiler turns into a node's props
#: (declared in ejsrl.world.kinds; a gizmo's bind and on_change and a group's children are
#: compiled by the element itself)
def own_props() -> dict[str, dict[str, str]]:
    """kind -> {property: property type} of every declared 3D element kind."""
    return {name: {p.name: p.type for p in kind.props if p.is_value} for name, kind in KINDS.items()}


_OWN_PROPS: dict[str, dict[str, str]] = own_props()


def _slug(text: str) -> str:
    return re.sub(r"\W+", "_", text.lower()).strip("_")[:30].strip("_") or "x"


def _path_of(node: ast.expr, variables: set[str]) -> bool:
    """Whether a rewritten expression is a bind path: ``self.x`` or ``self.x[2]`` (whole numbers)."""
    while isinstance(node, ast.Subscript):
        if _const_index(node.slice) is None:
            return False
        node = node.value
    return isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "self" and node.attr in variables


class ViewCompiler:
    """Compiles the view tree using the model compiler's names, methods and errors."""

    def __init__(self, compiler: Compiler) -> None:
        self.c = compiler
        self.n = 0
        self.scene_names: set[str] = set()
        self.auto_counts: dict[str, int] = {}

    # -- properties --------------------------------------------------------------------------------
    def dynamic(self, path: Path_, base: str, what: str, text: str) -> Call | None:
        """``E.Dynamic``: a variable path read by the runtime, or a lambda of the model."""
        snippet = self.c.snippet(path, what, "eval", text)
        tree = self.c.parse_rewrite(snippet)
        if tree is None:
            return None
        assert isinstance(tree, ast.Expression)
        if _path_of(tree.body, self.c.names.variables):
            return Call("E.Dynamic", [text.strip()])
        expr = self.c.expr(path, what, text=text, lam="self")
        return Call("E.Dynamic", [expr, text]) if expr is not None else None

    def interpolated(self, path: Path_, text: str, base: str, what: str, *, markdown: bool = False, origin: Any = None) -> Any:
        """A text with {expr} / {expr:fmt}: a constant if it has none, else a Dynamic f-string.

        ``markdown``: the text is shown through the Markdown renderer (a ``label``); each
        value is then passed through ``E.escaped`` so that what it holds (text typed by a
        user, say) is shown as text and never read as Markdown or HTML; the author's own
        text stays Markdown. ``origin``: where the text starts, when it is not the scalar at
        ``path`` (a mapping key).
        """
        if origin is None:
            origin = self.c.doc.origins.get(path)
        try:
            parts = split_fields(text)
        except BraceError as err:
            self.c.errors.append(SpecError(self._text_loc(path, origin, text, err.offset), f"{err.message} in {what}{err.detail}", err.hint))
            return text
        if all(isinstance(p, str) for p in parts):
            return "".join(parts)  # type: ignore[arg-type]
        values: list[ast.expr] = []
        for part in parts:
            if isinstance(part, str):
                values.append(ast.Constant(part))
                continue
            field, spec, conv = part.expr, part.spec, part.conversion
            if not field.strip():
                self.c.errors.append(SpecError(self._text_loc(path, origin, text, part.offset - 1), f"empty {{}} in {what}", "put an expression inside, e.g. {t:.2f}"))
                continue
            sub_origin = None
            if origin is not None:
                loc = self._text_loc(path, origin, text, part.offset)
                sub_origin = TextOrigin(loc.line, loc.col, False)
            res = self._expr_with_origin(field, sub_origin, path, f"{{{field}}} in {what}")
            if res is None:
                continue
            if markdown:
                if conv:
                    res = ast.Call(ast.Name({"r": "repr", "s": "str", "a": "ascii"}[conv]), [res], [])
                args: list[ast.expr] = [res] + ([ast.Constant(spec)] if spec else [])
                call = ast.Call(ast.Attribute(ast.Name("E"), "escaped"), args, [])
                values.append(ast.FormattedValue(call, -1, None))
            else:
                fmt = ast.JoinedStr([ast.Constant(spec)]) if spec else None
                values.append(ast.FormattedValue(res, ord(conv) if conv else -1, fmt))
        joined = ast.JoinedStr(values)
        return Call("E.Dynamic", [Expr(ast.unparse(joined), self.c.loc(path), text, "self"), text])

    def _text_loc(self, path: Path_, origin: Any, text: str, offset: int) -> Location:
        """The spec location of character ``offset`` of the text at ``path`` starting at ``origin``."""
        if origin is None:
            return self.c.loc(path)
        before = text[:offset]
        if "\n" not in before:
            return Location(self.c.doc.file, origin.line, origin.col + len(before))
        return Location(self.c.doc.file, origin.line + before.count("\n"), len(before.rsplit("\n", 1)[1]) + (origin.col if origin.block else 1))

    def _unit_of(self, expr: Any) -> str | None:
        """The declared unit of a plain variable (or element of an array variable) expression."""
        if not isinstance(expr, str):
            return None
        try:
            node = ast.parse(expr.strip(), mode="eval").body
        except SyntaxError:
            return None
        if isinstance(node, ast.Subscript):
            node = node.value
        if not isinstance(node, ast.Name) or node.id not in self.c.var_decls:
            return None
        decl = self.c.var_decls[node.id].decl
        unit = getattr(decl, "unit", None)
        if unit is None and node.id == "t" and node.id in self.c.independents:
            unit = "s"  # the independent variable t is time, in seconds, unless declared otherwise
        return unit

    def _axis_title(self, expr: Any) -> str:
        """An x axis title: the expression and its unit, 't (s)'."""
        if not isinstance(expr, str):
            return ""
        unit = self._unit_of(expr)
        return f"{expr.strip()} ({unit})" if unit else expr.strip()

    def _key_origin(self, path: Path_) -> Any:
        """Where the text of the mapping key at ``path`` starts (past an opening quote)."""
        from ejsgen.yamlload import TextOrigin

        loc = self.c.doc.key_loc(path)
        try:
            line_text = self.c.spec_path.read_text(encoding="utf-8").splitlines()[loc.line - 1]
            quoted = line_text[loc.col - 1] in "'\""
        except (OSError, IndexError):
            quoted = False
        return TextOrigin(loc.line, loc.col + (1 if quoted else 0), False)

    def _expr_with_origin(self, text: str, origin: Any, path: Path_, what: str) -> ast.expr | None:
        from ejsgen._resolve import Snippet, parse_snippet, rewrite
        from ejsgen.yamlload import TextOrigin

        snippet = Snippet(text, origin or TextOrigin(*self.c.doc.positions.get(path, (1, 1)), False), self.c.doc.file, what, "eval")
        try:
            tree = parse_snippet(snippet)
        except SpecError as err:
            self.c.errors.append(err)
            return None
        new, errs = rewrite(tree, self.c.names, snippet)
        self.c.errors.extend(errs)
        assert isinstance(new, ast.Expression)
        return new.body

    def number(self, value: Any, path: Path_, base: str, what: str) -> Any:
        if isinstance(value, str):
            return self.dynamic(path, base, what, value)
        return value

    def vector(self, value: Any, path: Path_, base: str, what: str, length: int | None) -> Any:
        """A list of numbers/expressions, or one expression; checked for ``length`` when known."""
        if isinstance(value, str):
            res = self.c.expr_source(path, what)
            if res is None:
                return None
            shape = infer_shape(res[1], self.c.var_shapes)
            if length is not None and shape is not None and shape != (length,):
                self.c.errors.append(SpecError(self.c.loc(path), f"{what} needs {length} numbers, but '{value}' has shape {shape}", self.c.text_hint(value)))
            return self.dynamic(path, base, what, value)
        if not isinstance(value, list):
            self.c.errors.append(SpecError(self.c.loc(path), f"{what} must be a list or an expression"))
            return None
        if length is not None and len(value) != length:
            self.c.errors.append(SpecError(self.c.loc(path), f"{what} needs {length} numbers, got {len(value)}"))
            return None
        if all(not isinstance(v, str) for v in value):
            if any(isinstance(v, list) for v in value):
                return [[float(x) for x in row] for row in value]
            return tuple(float(v) for v in value)
        elts: list[str] = []
        for i, v in enumerate(value):
            if isinstance(v, str):
                res = self.c.expr_source(path + (i,), what)
                elts.append(res[0] if res else "0.0")
            else:
                elts.append(repr(float(v)))
        return Call("E.Dynamic", [Expr(f"[{', '.join(elts)}]", self.c.loc(path), "", "self"), _list_text(value)])

    def matrix(self, value: Any, path: Path_, base: str, what: str, shape: tuple[int, int] | None, cols: int | None = None) -> Any:
        if isinstance(value, str):
            res = self.c.expr_source(path, what)
            if res is None:
                return None
            got = infer_shape(res[1], self.c.var_shapes)
            if shape is not None and got is not None and got != shape:
                self.c.errors.append(SpecError(self.c.loc(path), f"{what} must be {shape[0]}x{shape[1]}, but '{value}' has shape {got}", self.c.text_hint(value)))
            if cols is not None and got is not None and (len(got) != 2 or got[1] != cols):
                self.c.errors.append(SpecError(self.c.loc(path), f"{what} must be N x {cols}, but '{value}' has shape {got}", self.c.text_hint(value)))
            return self.dynamic(path, base, what, value)
        if isinstance(value, list) and value and all(isinstance(r, list) for r in value):
            if any(isinstance(x, str) for r in value for x in r):
                rows = []
                for i, r in enumerate(value):
                    items = []
                    for j, x in enumerate(r):
                        if isinstance(x, str):
                            res = self.c.expr_source(path + (i, j), what)
                            items.append(res[0] if res else "0.0")
                        else:
                            items.append(repr(float(x)))
                    rows.append("[" + ", ".join(items) + "]")
                return Call("E.Dynamic", [Expr(f"[{', '.join(rows)}]", self.c.loc(path), "", "self"), _list_text(value)])
            got, err = literal_shape(value)
            if err:
                self.c.errors.append(SpecError(self.c.loc(path), f"{what}: {err}"))
                return None
            if shape is not None and got != shape:
                self.c.errors.append(SpecError(self.c.loc(path), f"{what} must be {shape[0]}x{shape[1]}, got {got[0]}x{got[1] if len(got) > 1 else 1}"))
            if cols is not None and (got is None or len(got) != 2 or got[1] != cols):
                self.c.errors.append(SpecError(self.c.loc(path), f"{what} must be a list of [x, y, z] points"))
            return [[float(x) for x in r] for r in value]
        self.c.errors.append(SpecError(self.c.loc(path), f"{what} must be a list of rows or an expression"))
        return None

    def color(self, value: Any, path: Path_, base: str) -> Any:
        from ejsrl.world.colors import is_color_literal

        if value is None:
            return None
        if isinstance(value, str):
            if is_color_literal(value):
                return value
            if value.startswith("#"):
                self.c.errors.append(SpecError(self.c.loc(path), f"'{value}' is not a colour: '#' must be followed by six hex digits (0-9, a-f)", 'write it like "#3366aa", in quotes'))
                return None
            if re.fullmatch(r"#?[0-9a-fA-F]{3,8}", value) or (value.isalpha() and value.islower() and value not in self.c.names.variables and value not in self.c.names.functions):
                from ejsrl.world.colors import CSS_COLORS

                self.c.errors.append(SpecError(self.c.loc(path), f"unknown colour '{value}'", did_you_mean(value, CSS_COLORS) or "use a CSS name, '#rrggbb' or an RGB expression"))
                return None
            return self.dynamic(path, base, "a colour", value)
        return self.vector(value, path, base, "a colour", 3)

    # -- binds ------------------------------------------------------------------------------------------
    def bind(self, text: str, path: Path_, kind: str) -> tuple[str, str, str] | None:
        """Check a bind target (a variable or one element, q[2]: the runtime reads and writes it); returns (text, text, vtype)."""
        c = self.c
        before = len(c.errors)
        tree = c.parse_rewrite(c.snippet(path, f"the bind target of a {kind}", "eval"))
        if tree is None or len(c.errors) > before:
            return None
        assert isinstance(tree, ast.Expression)
        node = tree.body
        base = node.value if isinstance(node, ast.Subscript) else node
        if not (isinstance(base, ast.Attribute) and isinstance(base.value, ast.Name) and base.value.id == "self" and base.attr in c.names.variables):
            c.errors.append(SpecError(c.loc(path), f"the bind target '{text}' is not a variable", did_you_mean(text.split("[")[0].strip(), c.names.variables) or "bind names a model variable or one element, like q[2]"))
            return None
        var = base.attr
        vtype = c.var_types.get(var, "auto")
        shape = c.var_shapes.get(var)
        if isinstance(node, ast.Subscript):
            idx = _const_index(node.slice)
            if idx is None:
                c.errors.append(SpecError(c.loc(path), f"the bind target '{text}' must index with whole numbers, like q[2]"))
                return None
            if vtype not in ("array", "auto"):
                c.errors.append(SpecError(c.loc(path), f"'{var}' is not an array, so '{text}' cannot be bound"))
                return None
            if shape is not None:
                if len(idx) != len(shape) or any(not (-n <= i < n) for i, n in zip(idx, shape)):
                    c.errors.append(SpecError(c.loc(path), f"'{text}' is out of range: '{var}' has shape {shape}"))
                    return None
            vtype = "float"
        elif vtype == "array" and kind in ("slider", "number", "checkbox", "text", "dropdown"):
            hint = f"bind one element, e.g. {var}[0]" if shape and len(shape) == 1 else ""
            c.errors.append(SpecError(c.loc(path), f"a {kind} shows one value, but '{var}' is an array of shape {shape}", hint))
            return None
        return (text, text, "float" if vtype == "auto" else vtype)

    # -- elements ------------------------------------------------------------------------------------------
    def compile(self, items: list[ViewItem]) -> list[Call]:
        """The view: one runtime call per element (None for elements with errors dropped)."""
        return [call for call in (self.element(item) for item in items) if call is not None]

    def element(self, item: ViewItem) -> Call | None:
        self.n += 1
        return _ELEMENT_COMPILERS[item.kind](self, item, self.n)

    def _children(self, items: list[ViewItem]) -> list[Call]:
        return [call for call in (self.element(ch) for ch in items) if call is not None]

    def code(self, base: str, code: Any, path: Path_, what: str) -> Any:
        """An action or on_change: the method itself when it is one bare call, else a new method."""
        got = self.c.code_method(base, code, path, what)
        if got is None:
            return None
        return got if isinstance(got, Ref) else Ref(got)

    def _folder(self, item: ViewItem, n: int) -> Call:
        p, path = item.props, item.path
        label = self.interpolated(path + ("label",), p.label, "", "a folder's label")
        kw: dict[str, Any] = {"label": label} | ({} if p.expanded else {"expanded": False})
        kw |= {"where": self.c.where(path), "children": self._children(item.children)}
        return Call("E.Folder", [], kw, children="children")

    def _tabs(self, item: ViewItem, n: int) -> Call:
        path = item.path
        tabs = []
        for label, children in item.tabs:
            shown = self.interpolated(path + ("tabs", label), label, "", "a tab's label", origin=self._key_origin(path + ("tabs", label)))
            tabs.append((shown, self._children(children)))
        return Call("E.Tabs", [], {"where": self.c.where(path), "tabs": tabs}, children="tabs")

    def _markdown(self, item: ViewItem, n: int) -> Call:
        return Call("E.Markdown", [], {"text": item.props.text, "where": self.c.where(item.path)})

    def _label(self, item: ViewItem, n: int) -> Call:
        p, path = item.props, item.path
        text = self.interpolated(path + ("text",), p.text, "", "a label", markdown=True)
        return Call("E.Label", [], {"text": text, "where": self.c.where(path)})

    def _button(self, item: ViewItem, n: int) -> Call:
        p, path = item.props, item.path
        action = self.code(f"_button_{_slug(p.label)}", p.action, path + ("action",), f"the action of button '{p.label}'")
        label = self.interpolated(path + ("label",), p.label, "", f"the label of button '{p.label}'")
        if action is None:  # no code: a button that does nothing
            action = Src("lambda self: None")
        return Call("E.Button", [], {"label": label, "action": action, "where": self.c.where(path)})

    def _image(self, item: ViewItem, n: int) -> Call:
        p, path = item.props, item.path
        src = self.dynamic(path + ("source",), "", "an image source", p.source)
        pts = self.dynamic(path + ("points",), "", "the image's points", p.points) if p.points is not None else None
        label = self.interpolated(path + ("label",), p.label or "", "", "the image's label")
        return Call("E.Image", [], {"source": src, "label": label, "points": pts, "where": self.c.where(path)})

    def _scene(self, item: ViewItem, n: int) -> Call:
        kids = [call for call in (self.node3d(ch) for ch in item.children) if call is not None]
        check_follows(self)
        return Call("E.Scene", [], {"where": self.c.where(item.path), "children": kids}, children="children")

    def control(self, item: ViewItem, n: int) -> Call | None:
        c = self.c
        kind, p, path = item.kind, item.props, item.path
        b = self.bind(p.bind, path + ("bind",), kind)
        if b is None:
            return None
        _, _, vtype = b
        want = {"checkbox": ("bool",), "text": ("str",), "slider": ("float", "int"), "number": ("float", "int")}.get(kind)
        var = p.bind.split("[")[0].strip()
        declared = c.var_types.get(var)
        if want and declared not in ("auto", None) and "[" not in p.bind and vtype not in want:
            decl_value = getattr(c.var_decls[var].decl, "value", None) if var in c.var_decls else None
            hint = ""
            if kind == "checkbox" and isinstance(decl_value, str) and decl_value.lower() in ("yes", "no", "on", "off", "y", "n"):
                hint = f"'{decl_value}' is text in ejsgen's YAML (1.2); declare '{var}' as true or false"
            c.errors.append(SpecError(c.loc(path + ("bind",)), f"a {kind} needs a {' or '.join(want)} variable, but '{var}' is {vtype}", hint))
            return None
        if declared == "auto" and want and "[" not in p.bind:
            vtype = want[0]
        on_change = None
        if p.on_change is not None:
            on_change = self.code(f"_{kind}_{_slug(p.bind)}_changed", p.on_change, path + ("on_change",), f"the on_change of the {kind} of {p.bind}")
        label = self.interpolated(path + ("label",), p.label, "", f"the label of the {kind} of {p.bind}") if p.label is not None else p.bind
        kw: dict[str, Any] = {"bind": p.bind, "label": label, "on_change": on_change, "vtype": vtype}
        decl = c.var_decls.get(var)
        if kind == "slider":
            if p.min >= p.max:
                c.errors.append(SpecError(c.loc(path + ("max",)), f"the slider's max ({p.max}) must be above its min ({p.min})"))
            step = p.step if p.step is not None else (1 if vtype == "int" else abs(p.max - p.min) / 100)
            if step <= 0 and p.min < p.max:
                c.errors.append(SpecError(c.loc(path + ("step",)), "the slider's step must be positive"))
            kw.update(min=float(p.min), max=float(p.max), step=float(f"{step:.12g}"))  # 0.029, not 0.028999999999999998
        elif kind == "number":
            lo = p.min if p.min is not None else (decl.decl.min if decl else None)
            hi = p.max if p.max is not None else (decl.decl.max if decl else None)
            if lo is not None and hi is not None and lo > hi:
                c.errors.append(SpecError(c.loc(path), f"min ({lo}) is above max ({hi})"))
            kw.update(min=None if lo is None else float(lo), max=None if hi is None else float(hi), step=None if p.step is None else float(p.step))
        elif kind == "dropdown":
            if not p.options:
                c.errors.append(SpecError(c.loc(path + ("options",)), "a dropdown needs at least one option"))
            if vtype in ("float", "int") and any(isinstance(o, (str, bool)) for o in p.options):
                c.errors.append(SpecError(c.loc(path + ("options",)), f"'{var}' is a number, so every option must be a number"))
            if vtype == "str" and any(not isinstance(o, str) for o in p.options):
                c.errors.append(SpecError(c.loc(path + ("options",)), f"'{var}' is text, so every option must be text"))
            kw["options"] = list(p.options)
        kw["where"] = c.where(path)
        cls = {"slider": "E.Slider", "number": "E.Number", "checkbox": "E.Checkbox", "text": "E.Text", "dropdown": "E.Dropdown"}[kind]
        return Call(cls, [], kw, keep=("min", "max", "step"))

    def node3d(self, item: ViewItem) -> Call:
        c = self.c
        self.n += 1
        kind, p, path = item.kind, item.props, item.path
        name = p.name
        if name is None:
            self.auto_counts[kind] = self.auto_counts.get(kind, 0) + 1
            name = f"{kind}{self.auto_counts[kind]}"
            while name in self.scene_names:
                self.auto_counts[kind] += 1
                name = f"{kind}{self.auto_counts[kind]}"
        elif name in self.scene_names:
            c.errors.append(SpecError(c.loc(path + ("name",)), f"the scene already has an object named '{name}'"))
        self.scene_names.add(name)
        kw: dict[str, Any] = {"kind": kind, "name": name}
        props: dict[str, Any] = {}
        for decl in KINDS[kind].props:
            if not decl.is_value:
                continue  # a gizmo's bind and on_change, a group's children: below
            prop = decl.name
            if prop not in p.model_fields_set:
                if not decl.required and decl.default is not None:  # the app's node gets the spec's default
                    value = getattr(p, prop)
                    if isinstance(value, list):
                        value = tuple(value)
                    props[prop] = value
                continue
            value = getattr(p, prop)
            ppath = path + (prop,)
            what = f"the {prop} of {kind} '{name}'"
            if value is None:
                continue
            if kind in MOBILE_MODELS:  # a mobile kind's keys are checked as the drawing panel's (one body serves both)
                handled, compiled = compile_mobile_prop(self, kind, prop, value, ppath, what)
                if handled:
                    props[prop] = compiled
                    continue
            props[prop] = _PROP_COMPILERS[decl.type](self, value, ppath, "", what)
        kw["props"] = props
        placed_by = None if any(d.name == "position" for d in KINDS[kind].props) else p.position  # an ellipse's position is its centre
        if p.transform is not None:
            if placed_by is not None or p.rotation is not None:
                c.errors.append(SpecError(c.loc(path + ("transform",)), "give either 'transform' or 'position'/'rotation', not both"))
            kw["transform"] = self.matrix(p.transform, path + ("transform",), "", f"the transform of '{name}'", (4, 4))
        if placed_by is not None:
            kw["position"] = self.vector(p.position, path + ("position",), "", f"the position of '{name}'", 3)
        if p.rotation is not None:
            kw["rotation"] = self.vector(p.rotation, path + ("rotation",), "", f"the rotation of '{name}'", 3)
        if kind == "gizmo":
            b = self.bind(p.bind, path + ("bind",), "gizmo")
            if b is not None:
                var = p.bind.strip()
                if c.var_shapes.get(var) not in (None, (4, 4)):
                    c.errors.append(SpecError(c.loc(path + ("bind",)), f"a gizmo binds a 4x4 pose variable, but '{var}' has shape {c.var_shapes.get(var)}"))
                kw["bind"] = p.bind
            if p.on_change is not None:
                kw["on_change"] = self.code(f"_gizmo_{_slug(name)}_dragged", p.on_change, path + ("on_change",), f"the on_change of gizmo '{name}'")
        if kind == "view":
            check_view(self, item, name)
        if isinstance(props.get("texture"), str):  # a constant texture the virtual camera cannot draw
            from ejsrl.world.rendering import texture_problem

            bad = texture_problem(props["texture"])
            if bad is not None:
                c.errors.append(SpecError(c.loc(path + ("texture",)), bad[0], bad[1]))
        if "visible" in p.model_fields_set:
            kw["visible"] = self.dynamic(path + ("visible",), "", f"the visibility of '{name}'", p.visible) if isinstance(p.visible, str) else bool(p.visible)
        if p.color is not None:
            kw["color"] = self.color(p.color, path + ("color",), "")
        if "opacity" in p.model_fields_set:
            kw["opacity"] = self.number(p.opacity, path + ("opacity",), "", f"the opacity of '{name}'")
        if p.graspable:
            kw["graspable"] = True
        kw["where"] = c.where(path)
        if item.children:
            kw["children"] = [self.node3d(ch) for ch in item.children]
            return Call("E.Node3D", [], kw, children="children")
        return Call("E.Node3D", [], kw)


#: view element kind -> compiles one element into the lines of its record in ``VIEW``
_ELEMENT_COMPILERS: dict[str, Callable[[ViewCompiler, ViewItem, int], Call | None]] = {
    "folder": ViewCompiler._folder,
    "tabs": ViewCompiler._tabs,
    "markdown": ViewCompiler._markdown,
    "label": ViewCompiler._label,
    "slider": ViewCompiler.control,
    "number": ViewCompiler.control,
    "checkbox": ViewCompiler.control,
    "text": ViewCompiler.control,
    "dropdown": ViewCompiler.control,
    "button": ViewCompiler._button,
    "plot": compile_plot,
    "image": ViewCompiler._image,
    "scene": ViewCompiler._scene,
}

from ejsgen._view_compile_text import compile_console, compile_table  # noqa: E402 - they use ViewCompiler's helpers

_ELEMENT_COMPILERS["table"] = compile_table
_ELEMENT_COMPILERS["console"] = compile_console

from ejsgen._view_compile2d import compile_drawing, compile_keyboard  # noqa: E402 - it uses ViewCompiler's helpers
from ejsgen._view_compile_source import compile_source  # noqa: E402 - a camera's real source
from ejsgen._spec2d_mobile import MOBILE_MODELS, compile_prop as compile_mobile_prop  # noqa: E402 - the mobile kinds' own keys

_ELEMENT_COMPILERS["drawing"] = compile_drawing
_ELEMENT_COMPILERS["keyboard"] = compile_keyboard


def _ints2(vc: ViewCompiler, value: Any, path: Path_, base: str, what: str) -> Any:
    if len(value) != 2 or any(v <= 0 or v > 8192 for v in value):
        vc.c.errors.append(SpecError(vc.c.loc(path), "resolution is [width, height] in pixels (1 to 8192)"))
    return tuple(int(v) for v in value)


#: property type (ejsrl.world.kinds) -> compiles a value the spec gave into the app's props
_PROP_COMPILERS: dict[str, Callable[[ViewCompiler, Any, Path_, str, str], Any]] = {
    "num": lambda vc, v, path, base, what: vc.number(v, path, base, what),
    "vec3": lambda vc, v, path, base, what: vc.vector(v, path, base, what, 3),
    "vec": lambda vc, v, path, base, what: vc.vector(v, path, base, what, None),
    "mat": lambda vc, v, path, base, what: vc.matrix(v, path, base, what, None, cols=3),
    "mat4": lambda vc, v, path, base, what: vc.matrix(v, path, base, what, (4, 4)),
    "mat3": lambda vc, v, path, base, what: vc.matrix(v, path, base, what, (3, 3)),
    "text": lambda vc, v, path, base, what: vc.interpolated(path, v, base, what),
    "expr": lambda vc, v, path, base, what: vc.dynamic(path, base, what, v),
    "file": lambda vc, v, path, base, what: vc.c.asset(v, path, "mesh file"),
    "files": lambda vc, v, path, base, what: [vc.c.asset(f, path + (i,), "mesh file") for i, f in enumerate(v)],
    "ints2": _ints2,
    "int": lambda vc, v, path, base, what: v,
    "name": lambda vc, v, path, base, what: v,
    "bool": lambda vc, v, path, base, what: v,
    "source": lambda vc, v, path, base, what: compile_source(vc, v, path, base, what),
}


def _list_text(value: Any) -> str:
    """A list as the user wrote it: expressions unquoted."""
    if isinstance(value, list):
        return "[" + ", ".join(_list_text(v) for v in value) + "]"
    return str(value)


def _const_index(node: ast.AST) -> tuple[int, ...] | None:
    def one(n: ast.AST) -> int | None:
        if isinstance(n, ast.Constant) and isinstance(n.value, int) and not isinstance(n.value, bool):
            return n.value
        if isinstance(n, ast.UnaryOp) and isinstance(n.op, ast.USub):
            v = one(n.operand)
            return -v if v is not None else None
        return None

    if isinstance(node, ast.Tuple):
        vals = [one(e) for e in node.elts]
        return None if any(v is None for v in vals) else tuple(vals)  # type: ignore[arg-type]
    v = one(node)
    return None if v is None else (v,)
