"""Records of the 2D drawing panel (``drawing``) and its elements, as a generated app declares them.

A property is a constant or a :class:`~ejsrl.view.elements.Dynamic` (a function of the
model), as for the other elements; ``where`` is the spec location shown with errors.
:mod:`ejsrl.view._drawing` turns them into frames of the 2D panel every display frame.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ejsrl.view._drawing_mobile import MOBILE_SHAPE_KINDS
from ejsrl.view.elements import Element

__all__ = ["Drawing", "Shape2D", "Drag2D", "SHAPE_KINDS", "SceneKeys"]

#: the 2D element kinds and the properties each takes (besides name, visible, color, drag)
SHAPE_KINDS: dict[str, tuple[str, ...]] = {
    "point": ("position", "size", "shape"),
    "particle": ("position", "radius", "stroke"),
    "circle": ("position", "radius", "fill", "width"),
    "segment": ("start", "end", "width"),
    "arrow": ("position", "vector", "width", "head"),
    "spring": ("start", "end", "coils", "radius", "width"),
    "polygon": ("points", "fill", "width"),
    "polyline": ("points", "width"),
    "trace": ("point", "max_points", "width"),
    "text": ("position", "text", "size", "align"),
    "image": ("source", "file", "position", "size"),
    "axes": ("width",),
    "grid": ("spacing", "width"),
}
SHAPE_KINDS.update(MOBILE_SHAPE_KINDS)  # vehicle, laser, occupancy, path, ellipse, particles (issue #27)


@dataclass
class Drag2D:
    """How an element is dragged.

    ``bind``: the spec's targets, one (``"x"``; for a set, an (N, 2) array variable) or two
    (``("x0", "y0")``); ``set_x``/``set_y``: write a coordinate (``set(model, value)``),
    None for a coordinate not bound; ``set_row(model, i, (x, y))``: for a set bound to one
    (N, 2) array; ``along``: ``free``, ``x``, ``y``, ``curve`` or ``region``; ``curve(model,
    x, y) -> (x, y)``; ``region``: ``(xmin, xmax, ymin, ymax)``, constants or Dynamic;
    ``handle``: ``start`` or ``end`` (segments, arrows, springs); ``on_drag(model)``,
    ``on_release(model)``: code run after a move / the release (then the fixed relations);
    ``limits``: per bound target, the ``(min, max)`` its variable declares (None: none),
    applied after the constraint; ``ints``: per bound target, True for an integer variable
    (the value is rounded).
    """

    bind: tuple[str, ...]
    along: str = "free"
    curve: Callable[[Any, float, float], Any] | None = None
    region: Any = None
    handle: str = "start"
    on_drag: Callable[[Any], None] | None = None
    on_release: Callable[[Any], None] | None = None
    limits: tuple[tuple[float | None, float | None], ...] = ()
    ints: tuple[bool, ...] = ()
    set_x: Callable[[Any, Any], None] | None = field(default=None, repr=False)
    set_y: Callable[[Any, Any], None] | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        from ejsrl.sim.paths import setter

        targets = tuple(self.bind) if not isinstance(self.bind, str) else (self.bind,)
        self.bind = targets
        if len(targets) == 2:
            self.set_x = self.set_x or setter(targets[0])
            self.set_y = self.set_y or setter(targets[1])
        elif self.along == "y":
            self.set_y = self.set_y or setter(targets[0])
        elif self.along == "x":
            self.set_x = self.set_x or setter(targets[0])


@dataclass
class Shape2D(Element):
    """One 2D element of a drawing panel.

    ``kind``: one of :data:`SHAPE_KINDS`; ``name``: unique in its panel (drag events carry
    it); ``props``: the kind's properties, constant or ``Dynamic`` (positions [x, y] or
    (N, 2) arrays in world units, sizes and widths in pixels unless the kind says world
    units); ``visible``, ``color`` (a CSS colour, or an RGB triple 0-1), ``drag``.
    """

    kind: str
    name: str
    props: dict[str, Any] = field(default_factory=dict)
    visible: Any = True
    color: Any = None
    drag: Drag2D | None = None

    def __post_init__(self) -> None:
        from difflib import get_close_matches

        at = f"{self.where}: " if self.where else ""
        if self.kind not in SHAPE_KINDS:
            close = get_close_matches(self.kind, list(SHAPE_KINDS), n=1)
            raise ValueError(f"{at}unknown 2D element kind {self.kind!r}" + (f"; did you mean {close[0]!r}?" if close else ""))
        for key in self.props:
            if key not in SHAPE_KINDS[self.kind]:
                raise ValueError(f"{at}a 2D {self.kind} has no property {key!r}")


@dataclass
class Drawing(Element):
    """A 2D drawing panel (EjsS's DrawingPanel).

    ``title``: text or ``Dynamic``; ``x_range``/``y_range``: ``(min, max)`` world window,
    constant or ``Dynamic``; ``aspect``: ``equal`` or ``free``; ``height``: pixels (None:
    with ``equal``, as high as the ranges need at the panel's width, within the window; with
    ``free``, 300);
    ``axes``/``grid``: a frame with ticks / grid lines; ``x_label``/``y_label``: axis
    titles; ``background``: CSS colour; ``keys``: key name (``"ArrowUp"``, ``"a"``,
    ``"Space"``, ...) -> ``action(model)`` run on key-down while the panel has the focus
    (then the fixed relations); ``children``: the :class:`Shape2D` drawn in order.
    """

    children: list[Shape2D] = field(default_factory=list)
    title: Any = ""
    x_range: Any = (-1.0, 1.0)
    y_range: Any = (-1.0, 1.0)
    aspect: str = "equal"
    height: int | None = None
    axes: bool = False
    grid: bool = False
    x_label: str = ""
    y_label: str = ""
    background: str = "white"
    keys: dict[str, Callable[[Any], None]] = field(default_factory=dict)


@dataclass
class SceneKeys(Element):
    """Keys of the 3D view: key name -> ``action(model)``, run on key-down while the 3D view
    has the focus (the user clicked it last), then the fixed relations."""

    keys: dict[str, Callable[[Any], None]] = field(default_factory=dict)
