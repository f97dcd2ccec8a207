"""Compile a ``plot`` element into its ``E.Plot`` record, checking its series' shapes.

What a series draws follows from the shapes of its expressions: numbers make a history
(one point per frame), 1-D arrays of one length a curve redrawn every frame; a histogram
counts the values of its ``x``. When the shapes are known at build time (numbers, literal
lists, array variables declared as lists, ``np.linspace(a, b, 50)``, slices of them,
elementwise arithmetic) a mismatch is a build error at the expression; otherwise the app
checks every frame and pauses with the same message.
"""

from __future__ import annotations

import ast
from typing import TYPE_CHECKING, Any

from ejsgen._shapes import infer_shape
from ejsgen.errors import SpecError
from ejsgen.plan import Call
from ejsgen.validate import ViewItem
from ejsgen.yamlload import Path_

if TYPE_CHECKING:
    from ejsgen._view_compile import ViewCompiler

__all__ = ["compile_plot", "expr_shape"]

Shape = tuple[int, ...]

#: NumPy functions that keep the shape of their (first) argument
_ELEMENTWISE = {
    "sin", "cos", "tan", "arcsin", "arccos", "arctan", "sinh", "cosh", "tanh", "exp", "expm1", "log", "log10", "log2",
    "log1p", "sqrt", "abs", "absolute", "sign", "floor", "ceil", "round", "square", "degrees", "radians", "deg2rad", "rad2deg",
    "asarray", "copy", "cumsum", "real", "imag", "nan_to_num", "clip",
}


def _const_int(node: ast.AST) -> int | None:
    if isinstance(node, ast.Constant) and isinstance(node.value, int) and not isinstance(node.value, bool):
        return node.value
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        v = _const_int(node.operand)
        return None if v is None else -v
    return None


def _index_shape(shape: Shape, index: ast.AST) -> Shape | None:
    """The shape of ``a[index]`` for ``a`` of ``shape`` when ``index`` is made of constant ints and slices."""
    parts = list(index.elts) if isinstance(index, ast.Tuple) else [index]
    if len(parts) > len(shape):
        return None
    out: list[int] = []
    for dim, part in zip(shape, parts):
        if isinstance(part, ast.Slice):
            bounds = [None if b is None else _const_int(b) for b in (part.lower, part.upper, part.step)]
            if any(b is None and raw is not None for b, raw in zip(bounds, (part.lower, part.upper, part.step))):
                return None
            out.append(len(range(dim)[slice(*bounds)]))
        elif _const_int(part) is not None:
            i = _const_int(part)
            if not -dim <= i < dim:  # type: ignore[operator]
                return None
        else:
            return None
    return tuple(out) + shape[len(parts) :]


def _np_call(node: ast.Call) -> str | None:
    f = node.func
    if isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) and f.value.id == "np":
        return f.attr
    return None


def expr_shape(node: ast.AST, var_shapes: dict[str, Shape | None]) -> Shape | None:
    """The shape of a rewritten expression when it is certain at build time, else None.

    Extends :func:`ejsgen._shapes.infer_shape` with constant slices of arrays of known
    shape (``data[:, 0]``), ``np.linspace``/``np.arange``/``np.zeros``/``np.ones`` with
    constant sizes, and NumPy's elementwise functions. A variable declared as an empty
    list is taken as unknown (it is usually filled later).
    """
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "self":
        shape = var_shapes.get(node.attr)
        return None if shape is not None and 0 in shape else shape
    if isinstance(node, ast.Subscript):
        base = expr_shape(node.value, var_shapes)
        return None if base is None or base == () else _index_shape(base, node.slice)
    if isinstance(node, ast.UnaryOp):
        return expr_shape(node.operand, var_shapes)
    if isinstance(node, ast.BinOp) and not isinstance(node.op, ast.MatMult):
        if isinstance(node.left, (ast.List, ast.Tuple)) or isinstance(node.right, (ast.List, ast.Tuple)):
            return None
        a, b = expr_shape(node.left, var_shapes), expr_shape(node.right, var_shapes)
        if a is None or b is None:
            return None
        if a == ():
            return b
        if b == () or a == b:
            return a
        return None
    if isinstance(node, ast.Call):
        name = _np_call(node)
        args = node.args
        if name == "linspace" and len(args) >= 2:
            num = next((kw.value for kw in node.keywords if kw.arg == "num"), args[2] if len(args) > 2 else None)
            n = 50 if num is None else _const_int(num)
            return None if n is None else (n,)
        if name == "arange" and args and not node.keywords:
            ints = [_const_int(a) for a in args]
            if any(v is None for v in ints) or len(ints) > 3:
                return None
            return (len(range(*ints)),)  # type: ignore[arg-type]
        if name in ("zeros", "ones", "empty") and len(args) == 1:
            a = args[0]
            dims = [_const_int(e) for e in a.elts] if isinstance(a, (ast.Tuple, ast.List)) else [_const_int(a)]
            return None if any(d is None for d in dims) else tuple(dims)  # type: ignore[arg-type]
        if name in _ELEMENTWISE and args:
            return expr_shape(args[0], var_shapes)
    return infer_shape(node, var_shapes)


def _describe(shape: Shape) -> str:
    if shape == ():
        return "a number"
    if len(shape) == 1:
        return f"an array of {shape[0]} values"
    return f"an array of shape {shape}"


class _PlotCompiler:
    """One plot: its series' records, the shapes it knows, and the errors it finds."""

    def __init__(self, vc: ViewCompiler, item: ViewItem) -> None:
        self.vc = vc
        self.c = vc.c
        self.p = item.props
        self.path = item.path

    def err(self, path: Path_, message: str, hint: str = "") -> None:
        self.c.errors.append(SpecError(self.c.loc(path), message, hint))

    def value(self, value: Any, path: Path_, what: str) -> tuple[Any, Shape | None]:
        """A number or expression: its compiled value, and its shape when known."""
        if not isinstance(value, str):
            return value, ()
        before = len(self.c.errors)
        dyn = self.vc.number(value, path, "", what)
        if dyn is None or len(self.c.errors) > before:
            return dyn, None
        res = self.c.expr_source(path, what, text=value)
        return dyn, (None if res is None else expr_shape(res[1], self.c.var_shapes))

    def range_(self, key: str, log: bool) -> tuple[float, float] | None:
        value = getattr(self.p, key)
        if value is None:
            return None
        axis = key[0]
        if len(value) != 2 or value[0] >= value[1]:
            self.err(self.path + (key,), f"{key} is [{axis}min, {axis}max] with {axis}min < {axis}max")
            return None
        if log and value[0] <= 0:
            self.err(self.path + (key,), f"a logarithmic {axis} axis shows only positive values, but {key} starts at {value[0]}", f"give {key} a positive start, e.g. [{value[1] / 1000:g}, {value[1]:g}]")
            return None
        return (float(value[0]), float(value[1]))

    def series(self, i: int, s: Any, plot_x_shape: Shape | None) -> Call | None:
        spath = self.path + ("series", i)
        name = f"series {i + 1} of the plot"
        kind = s.type
        if kind == "histogram":
            if s.x is None:
                self.err(spath, f"{name} is a histogram: it counts the values of its own x", "give it x: the quantity (a number, whose history it counts) or an array")
                return None
            if s.y is not None:
                self.err(spath + ("y",), f"{name} is a histogram: its bars count the values of x, so it takes no y", "remove y (the bars' heights are the counts)")
            if s.marker is not None:
                self.err(spath + ("marker",), f"{name} is a histogram: it draws bars, not markers")
        else:
            if s.y is None:
                self.err(spath, f"{name} needs y", "e.g. {y: omega}" if s.x is not None else "e.g. {y: theta, label: angle}")
                return None
            for key in ("bins", "bin_range"):
                if getattr(s, key) is not None:
                    self.err(spath + (key,), f"'{key}' is for a histogram, but {name} is a {kind}", "add 'type: histogram'")
        kw: dict[str, Any] = {}
        x_shape: Shape | None = plot_x_shape
        if s.x is not None:
            kw["x"], x_shape = self.value(s.x, spath + ("x",), f"the x of {name}")
        y_shape: Shape | None = None
        if s.y is not None:
            kw["y"], y_shape = self.value(s.y, spath + ("y",), f"the y of {name}")
        self.check_shapes(spath, name, s, kind, x_shape, y_shape)
        if s.label is not None:
            kw["label"] = self.vc.interpolated(spath + ("label",), s.label, "", f"the label of series {i + 1}")
        else:
            kw["label"] = str(s.y if s.y is not None else s.x)
        if s.color is not None:
            self.vc.color(s.color, spath + ("color",), "")
            kw["color"] = s.color
        if kind != "line":
            kw["kind"] = kind
        for key, default in (("marker", None), ("size", 6.0), ("width", 2.0), ("max_points", None)):
            if getattr(s, key) != default:
                kw[key] = getattr(s, key)
        if kind == "histogram":
            if s.bins is not None:
                kw["bins"] = s.bins
            if s.bin_range is not None:
                br = s.bin_range
                if len(br) != 2 or br[0] >= br[1]:
                    self.err(spath + ("bin_range",), "bin_range is [lo, hi] with lo < hi")
                else:
                    kw["bin_range"] = (float(br[0]), float(br[1]))
        kw["where"] = self.c.where(spath)
        return Call("E.Series", [], kw)

    def check_shapes(self, spath: Path_, name: str, s: Any, kind: str, x_shape: Shape | None, y_shape: Shape | None) -> None:
        """Build errors for shapes that cannot be drawn (only what is certain now)."""
        x_where = spath + ("x",) if s.x is not None else self.path + ("x",)
        x_text = f"its x '{s.x}'" if s.x is not None else f"the plot's x '{self.p.x}'"
        for shape, where, text, expr, col in ((x_shape, x_where, x_text, s.x if s.x is not None else self.p.x, 0), (y_shape, spath + ("y",), f"its y '{s.y}'", s.y, 1)):
            if shape is not None and len(shape) > 1:
                hint = f"pick one column, e.g. {str(expr).strip()}[:, {col}]" if len(shape) == 2 else "flatten it, or pick a 1-D slice"
                self.err(where, f"{name} needs numbers or 1-D arrays, but {text} is {_describe(shape)}", hint)
                return
        if kind == "histogram" or x_shape is None or y_shape is None:
            return
        if x_shape == () and y_shape != ():
            if s.x is None:
                self.err(spath + ("y",), f"{name}'s y '{s.y}' is {_describe(y_shape)} but the plot's x '{self.p.x}' is a number", f"give the series an x of its own with as many values, e.g. x: \"np.arange(len({str(s.y).strip()}))\"")
            else:
                self.err(spath + ("y",), f"{name}'s y '{s.y}' is {_describe(y_shape)} but its x '{s.x}' is a number", "give both as numbers (a history) or both as arrays of one length (a curve)")
        elif x_shape != () and y_shape == ():
            self.err(spath + ("y",), f"{name}'s y '{s.y}' is a number but {x_text} is {_describe(x_shape)}", "give both as numbers (a history) or both as arrays of one length (a curve)")
        elif x_shape != y_shape:
            self.err(spath + ("y",), f"{name}'s x and y must have as many values, but {x_text} is {_describe(x_shape)} and its y '{s.y}' is {_describe(y_shape)}")

    def uses_plot_x(self) -> bool:
        """Whether a series draws against the plot's ``x`` (one that is not a histogram and has no x of its own)."""
        return any(s.x is None and s.type != "histogram" for s in self.p.series)

    def plot_x(self) -> tuple[Any, Shape | None]:
        """The plot's compiled x and its shape; None (not compiled) when no series needs it.

        The default ``x: t`` in a model without ``t`` is an error at the plot, naming the series that need an x.
        """
        p, path = self.p, self.path
        if not self.uses_plot_x():
            return None, None
        if "x" not in p.model_fields_set and "t" not in self.c.var_decls:
            need = [str(i + 1) for i, s in enumerate(p.series) if s.x is None and s.type != "histogram"]
            which = f"series {need[0]} has" if len(need) == 1 else f"series {', '.join(need[:-1])} and {need[-1]} have"
            self.c.errors.append(SpecError(self.c.doc.key_loc(path), f"the plot draws against its x, t by default, but this model has no variable t ({which} no x of its own)", "give the plot an x, or each series its own x"))
            return None, None
        return self.value(p.x, path + ("x",), "the plot's x")

    def compile(self) -> Call:
        p, path, c = self.p, self.path, self.c
        x, x_shape = self.plot_x()
        series = [call for call in (self.series(i, s, x_shape) for i, s in enumerate(p.series)) if call is not None]
        y_range = self.range_("y_range", p.y_log)
        x_range = self.range_("x_range", p.x_log)
        title = self.vc.interpolated(path + ("title",), p.title, "", "the plot's title")
        kw: dict[str, Any] = {"title": title, "x": x, "series": series, "window": p.window, "max_points": p.max_points, "y_range": y_range}
        x_label = p.x_label if p.x_label is not None else self.x_title()
        y_label = p.y_label if p.y_label is not None else self.y_title()
        if x_label:
            kw["x_label"] = x_label
        if y_label:
            kw["y_label"] = y_label
        for key, default in (("x_range", None), ("x_log", False), ("y_log", False), ("legend", None), ("grid", True), ("height", None)):
            value = x_range if key == "x_range" else getattr(p, key)
            if value != default:
                kw[key] = value
        kw["where"] = c.where(path)
        return Call("E.Plot", [], kw)

    def x_title(self) -> str:
        """The x axis' title, with its unit: the plot's x when a series draws against it; else
        the x every series has of its own (a histogram's values) when they are one variable
        (``th1`` and ``[th1]`` alike); none when they differ."""
        series = self.p.series
        if series and not self.uses_plot_x():
            return self._shared_title([s.x for s in series if s.x is not None])
        return self.vc._axis_title(self.p.x)

    def y_title(self) -> str:
        """The y axis' title: "count" for histograms alone; the y and its unit when every series
        is x-y with one variable as y (``w1`` and ``[w1]``); else the unit the series' y share, if any."""
        series = self.p.series
        if series and all(s.type == "histogram" for s in series):
            return "count"
        ys = [s for s in series if s.y is not None]
        if ys and all(s.x is not None for s in ys):
            title = self._shared_title([s.y for s in ys])
            if title:
                return title
        units = {self.vc._unit_of(_plain(s.y)) for s in ys}
        return (units.pop() or "") if len(units) == 1 else ""

    def _shared_title(self, exprs: list[Any]) -> str:
        """The axis title of ``exprs`` when they are all one expression or one variable, else ""."""
        keys = {_plain(e) for e in exprs}
        return self.vc._axis_title(keys.pop()) if len(keys) == 1 else ""


#: calls that wrap a value without changing what it is: np.array([th1]) is th1
_WRAPPERS = {"array", "asarray", "atleast_1d", "ravel", "float", "list"}


def _plain(expr: Any) -> Any:
    """The variable an expression shows (``"[th1]"``, ``"np.array([th1])"`` -> ``"th1"``), or
    the expression's own text (stripped); non-text as it is."""
    if not isinstance(expr, str):
        return expr
    try:
        node = ast.parse(expr.strip(), mode="eval").body
    except SyntaxError:
        return expr.strip()
    while True:
        if isinstance(node, (ast.List, ast.Tuple)) and len(node.elts) == 1:
            node = node.elts[0]
        elif isinstance(node, ast.Call) and len(node.args) == 1 and not node.keywords and (
            (isinstance(node.func, ast.Attribute) and isinstance(node.func.value, ast.Name) and node.func.value.id == "np" and node.func.attr in _WRAPPERS)
            or (isinstance(node.func, ast.Name) and node.func.id in _WRAPPERS)
        ):
            node = node.args[0]
        else:
            break
    return node.id if isinstance(node, ast.Name) else expr.strip()


def compile_plot(vc: ViewCompiler, item: ViewItem, n: int) -> Call:
    """The ``E.Plot`` record of a ``plot`` element (registered in ``_ELEMENT_COMPILERS``)."""
    return _PlotCompiler(vc, item).compile()
