"""The ``drawing`` view element (EjsS's DrawingPanel) and its 2D children, as pydantic models.

A drawing panel shows 2D elements in world coordinates (equal aspect by default): points,
particles, circles, segments, arrows, springs, polygons, polylines, traces, text, images,
axes and grids. A child whose position expression gives an (N, 2) array draws N of them (a
*set*). A child may be dragged (``drag:``) within a constraint, writing bound variables;
the panel may map keys to code (``keys:``) while it has the keyboard focus.

The panel's ``children`` are validated here, kind by kind, when the view is compiled
(:func:`child_models`), so that every mistake is reported at its FILE:LINE:COL with the
wording of the other elements; the JSON Schema lists them for editor completion.
"""

from __future__ import annotations

from typing import Any, Literal, Union

from pydantic import Field

from ejsgen.spec import BoolOrExpr, Code, ColorValue, Expr, NumOrExpr, Strict, VecOrExpr

__all__ = ["DrawingEl", "KeyboardEl", "DragEl", "CHILD_MODELS", "KEY_NAMES", "KEY_ALIASES", "key_schema_note"]

#: the keys a panel may map (as the browser names them; "Space" stands for " ")
KEY_NAMES: tuple[str, ...] = (
    tuple(chr(c) for c in range(ord("a"), ord("z") + 1))
    + tuple(chr(c) for c in range(ord("A"), ord("Z") + 1))
    + tuple(str(d) for d in range(10))
    + ("ArrowUp", "ArrowDown", "ArrowLeft", "ArrowRight", "Space", "Enter", "Escape", "+", "-")
)
#: names authors write for keys -> the key's name in ``keys:``
KEY_ALIASES: dict[str, str] = {
    "Up": "ArrowUp", "Down": "ArrowDown", "Left": "ArrowLeft", "Right": "ArrowRight", " ": "Space",
    "space": "Space", "Return": "Enter", "enter": "Enter", "Esc": "Escape", "escape": "Escape",
    "plus": "+", "minus": "-", "up": "ArrowUp", "down": "ArrowDown", "left": "ArrowLeft", "right": "ArrowRight",
}


def key_schema_note() -> str:
    return "letters a-z and A-Z, digits, ArrowUp, ArrowDown, ArrowLeft, ArrowRight, Space, Enter, Escape, + and -"


class DragEl(Strict):
    """How a 2D element is dragged with the mouse: the variables it writes and its constraint."""

    bind: Union[str, list[str]]
    """The variables the dragged point writes: [x_var, y_var] (variables or array elements, 'p[0]'); one variable with along: x or y; for a set, one (N, 2) array variable whose row the dragged item is. Each is kept within its variable's min and max."""
    along: Literal["free", "x", "y", "curve", "region"] = "free"
    """The constraint: free, along x (y stays), along y, on a curve (curve:), or inside a region (region:)."""
    curve: str | None = None
    """For along: curve, the point of the curve for the pointer at (x, y): the name of a custom function f(x, y) -> [x, y], or a lambda, 'lambda px, py: [px, 0.1*px**2]'."""
    region: list[NumOrExpr] | None = None
    """[xmin, xmax, ymin, ymax]: the point is kept inside (any constraint; needed by along: region)."""
    handle: Literal["start", "end"] = "start"
    """For a segment, arrow or spring: the end that is dragged (an arrow's tip is its end)."""
    on_drag: Code | None = None
    """Code run after each move of the point (then the fixed relations)."""
    on_release: Code | None = None
    """Code run when the mouse is released (then the fixed relations)."""


class _Shape(Strict):
    name: str | None = None
    """A name for the element (drag events and error messages use it; default: kind and number)."""
    visible: BoolOrExpr = True
    """Whether it is drawn (an expression may hide it)."""
    color: ColorValue | None = None
    """Its colour: a CSS name, '#rrggbb' or an expression giving an RGB triple (0-1)."""
    drag: DragEl | None = None
    """Make it draggable: the variables it writes and the constraint."""


class PointEl(_Shape):
    """A point (marker) of a fixed size in pixels; a set if position gives N x 2."""

    position: VecOrExpr
    """[x, y] in world units, or an expression giving [x, y] or an N x 2 array (N points)."""
    size: NumOrExpr = 8
    """Diameter in pixels."""
    shape: Literal["circle", "square", "cross", "triangle"] = "circle"
    """The marker's shape."""


class ParticleEl(_Shape):
    """A filled disc of a radius in world units (a ball, a particle); a set if position gives N x 2."""

    position: VecOrExpr
    """Its centre [x, y], or an expression giving an N x 2 array (N particles)."""
    radius: NumOrExpr = 0.1
    """Radius in world units (all particles of a set alike)."""
    stroke: ColorValue | None = None
    """Outline colour (default: none)."""


class CircleEl(_Shape):
    """A circle (outline, optionally filled) of a radius in world units; a set if position gives N x 2."""

    position: VecOrExpr
    """Its centre [x, y], or an expression giving an N x 2 array."""
    radius: NumOrExpr
    """Radius in world units."""
    fill: ColorValue | None = None
    """Fill colour (default: none)."""
    width: NumOrExpr = 1.5
    """Line width in pixels."""


class SegmentEl(_Shape):
    """A line segment from start to end; a set if they give N x 2 arrays."""

    start: VecOrExpr
    """One end [x, y] (or N x 2)."""
    end: VecOrExpr
    """The other end [x, y] (or N x 2)."""
    width: NumOrExpr = 1.5
    """Line width in pixels."""


class ArrowEl(_Shape):
    """An arrow (a vector) drawn from position along vector; a field of arrows if they give N x 2."""

    position: VecOrExpr
    """Where it starts [x, y] (or N x 2: a field)."""
    vector: VecOrExpr
    """Its components [dx, dy] in world units (or N x 2, one per arrow)."""
    width: NumOrExpr = 1.5
    """Line width in pixels."""
    head: NumOrExpr = 8
    """Length of the head in pixels."""


class SpringEl(_Shape):
    """A spring: a zig-zag between start and end (EjsS's spring)."""

    start: VecOrExpr
    """One end [x, y]."""
    end: VecOrExpr
    """The other end [x, y]."""
    coils: int = Field(default=8, ge=1, le=200)
    """Number of coils."""
    radius: NumOrExpr = 0.1
    """Half the width of the zig-zag, in world units."""
    width: NumOrExpr = 1.5
    """Line width in pixels."""


class PolygonEl(_Shape):
    """A closed polygon through points, optionally filled."""

    points: Union[str, list[list[Union[float, int, str]]]]
    """Its vertices: a list of [x, y], or an expression giving an N x 2 array."""
    fill: ColorValue | None = None
    """Fill colour (default: none)."""
    width: NumOrExpr = 1.5
    """Line width in pixels."""


class PolylineEl(_Shape):
    """An open line through points (a NaN row breaks it): a function curve, a path."""

    points: Union[str, list[list[Union[float, int, str]]]]
    """Its points: a list of [x, y], or an expression giving an N x 2 array."""
    width: NumOrExpr = 1.5
    """Line width in pixels."""


class TraceEl(_Shape):
    """The path a point leaves behind (EjsS's trace): one point recorded per display frame."""

    point: VecOrExpr
    """The traced point [x, y]."""
    max_points: int = Field(default=1000, ge=2, le=100000)
    """Most points kept (older ones drop off)."""
    width: NumOrExpr = 1.5
    """Line width in pixels."""


class Text2DEl(_Shape):
    """Text at a point of the panel (drawn as text, never as markup)."""

    position: VecOrExpr
    """Where [x, y] (the text's anchor, see align)."""
    text: str
    """The text; {expr} and {expr:fmt} are interpolated."""
    size: NumOrExpr = 14
    """Font size in pixels."""
    align: Literal["left", "center", "right"] = "center"
    """Which side of the text the position is."""


class Image2DEl(_Shape):
    """An image placed in world coordinates: an array expression or an image file."""

    source: Expr | None = None
    """Expression giving an HxW or HxWx3 uint8 array (or floats 0-1)."""
    file: str | None = None
    """An image file (PNG, JPEG) relative to the spec (instead of source)."""
    position: VecOrExpr = Field(default_factory=lambda: [0.0, 0.0])
    """Its centre [x, y]."""
    size: VecOrExpr = Field(default_factory=lambda: [1.0, 1.0])
    """[width, height] in world units."""


class Axes2DEl(_Shape):
    """The coordinate axes: lines through the origin across the panel, with arrow heads."""

    width: NumOrExpr = 1.0
    """Line width in pixels."""


class Grid2DEl(_Shape):
    """Grid lines across the panel every spacing world units."""

    spacing: NumOrExpr = 1.0
    """Distance between lines in world units."""
    width: NumOrExpr = 1.0
    """Line width in pixels."""


#: child kind -> model (``particle`` is a point of a radius in world units)
CHILD_MODELS: dict[str, type[Strict]] = {
    "point": PointEl,
    "particle": ParticleEl,
    "circle": CircleEl,
    "segment": SegmentEl,
    "arrow": ArrowEl,
    "spring": SpringEl,
    "polygon": PolygonEl,
    "polyline": PolylineEl,
    "trace": TraceEl,
    "text": Text2DEl,
    "image": Image2DEl,
    "axes": Axes2DEl,
    "grid": Grid2DEl,
}

from ejsgen._spec2d_mobile import MOBILE_MODELS  # noqa: E402 - they extend _Shape, defined above

CHILD_MODELS.update(MOBILE_MODELS)  # vehicle, laser, occupancy, path, ellipse, particles (issue #27)


def _inline(node: Any, defs: dict[str, Any]) -> Any:
    """``node`` with every ``{"$ref": "#/$defs/X"}`` replaced by X's schema (the 2D models have no cycles)."""
    if isinstance(node, dict):
        ref = node.get("$ref")
        if isinstance(ref, str) and ref.startswith("#/$defs/"):
            return _inline(defs[ref.removeprefix("#/$defs/")], defs)
        return {k: _inline(v, defs) for k, v in node.items()}
    if isinstance(node, list):
        return [_inline(v, defs) for v in node]
    return node


def _children_schema(schema: dict[str, Any]) -> None:
    """The JSON Schema of ``children``: one-key objects of the 2D kinds, their schemas inline."""
    items = []
    for kind, model in CHILD_MODELS.items():
        sub = model.model_json_schema()
        defs = sub.pop("$defs", {})
        items.append({"type": "object", "description": model.__doc__ or kind, "properties": {kind: _inline(sub, defs)},
                      "required": [kind], "additionalProperties": False})
    schema["properties"]["children"]["items"] = {"oneOf": items}


class DrawingEl(Strict):
    """A 2D drawing panel (EjsS's DrawingPanel): 2D elements in world coordinates, draggable, with keys."""

    model_config = Strict.model_config | {"json_schema_extra": _children_schema}

    title: str = ""
    """Text above the panel; {expr} and {expr:fmt} are interpolated."""
    x_range: VecOrExpr = Field(default_factory=lambda: [-1.0, 1.0])
    """[xmin, xmax] of the world shown (numbers or expressions: a window that follows an object)."""
    y_range: VecOrExpr = Field(default_factory=lambda: [-1.0, 1.0])
    """[ymin, ymax] of the world shown."""
    aspect: Literal["equal", "free"] = "equal"
    """equal: a unit is as long on x as on y (the ranges grow to fill the panel, centred); free: each range fills the panel."""
    height: int | None = Field(default=None, ge=60, le=2000)
    """Height of the panel in pixels (it is as wide as the control panel). Left out: with aspect: equal, as high as the ranges need at the panel's width, so that they fill it (at most the window's height less 100 px, at least 120 px: beyond those the other range grows); with aspect: free, 300."""
    axes: bool = False
    """Draw a frame with ticks and numbers along x and y."""
    grid: bool = False
    """Draw grid lines at the ticks."""
    x_label: str = ""
    """Title of the x axis (with axes: true)."""
    y_label: str = ""
    """Title of the y axis (with axes: true)."""
    background: str = "white"
    """Background colour (a CSS name or '#rrggbb')."""
    keys: dict[str, Code] = Field(default_factory=dict)
    """Key: code run when the key is pressed while the panel has the keyboard focus (click it), then the fixed relations. Keys: letters, digits, ArrowUp, ArrowDown, ArrowLeft, ArrowRight, Space, Enter, Escape, + and -."""
    children: list[Any] = Field(default_factory=list)
    """The 2D elements, drawn in order: point, particle, circle, segment, arrow, spring, polygon, polyline, trace, text, image, axes, grid; for mobile robots vehicle, laser, occupancy, path, ellipse, particles."""


class KeyboardEl(Strict):
    """Keys of the 3D view: code run when a key is pressed while the 3D view has the keyboard focus (it was clicked last)."""

    keys: dict[str, Code]
    """Key: code run when it is pressed, then the fixed relations. Keys: letters, digits, ArrowUp, ArrowDown, ArrowLeft, ArrowRight, Space, Enter, Escape, + and - (a drawing panel takes its own keys:)."""


# -- the reference's generated tables (ejsgen._docs: sections drawing-elements, drawing-properties, drag) --


def docs_kinds() -> str:
    """The table of the 2D kinds, each linked to its properties."""
    rows = ["| kind | what it is |", "|---|---|"]
    for kind, cls in CHILD_MODELS.items():
        rows.append(f"| [`{kind}`](#2d-{kind}) | {(cls.__doc__ or '').strip()} |")
    return "\n".join(rows) + "\n"


def docs_properties() -> str:
    """Each 2D kind's own properties (those every 2D element has come first, once)."""
    from ejsgen._docs import field_table

    common = list(_Shape.model_fields)
    out = ["Every 2D element takes\n", field_table(PointEl, common)]
    for kind, cls in CHILD_MODELS.items():
        own = [f for f in cls.model_fields if f not in common]
        out.append(f"#### 2D `{kind}`\n\n{(cls.__doc__ or '').strip()}\n")
        out.append(field_table(cls, own) if own else "No properties of its own.\n")
    return "\n".join(out)


def docs_drag() -> str:
    """The table of ``drag:``."""
    from ejsgen._docs import field_table

    return field_table(DragEl)
