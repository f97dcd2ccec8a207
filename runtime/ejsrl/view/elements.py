"""Descriptions of view elements, as a generated app declares them.

The generator turns each element of a spec's ``view`` into one of these plain records.
A *dynamic* property is a function of the model (``Callable[[model], value]``), made from
a spec expression compiled into a method of the generated ``Model`` class; a constant
property is the value itself. :func:`value_of` reads either kind.

``where`` is the element's location in the spec (``"lab.ejs.yaml:12:5"``), shown with any
error its expressions raise.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

__all__ = [
    "Dynamic",
    "is_dynamic",
    "value_of",
    "Element",
    "Folder",
    "Tabs",
    "Markdown",
    "Label",
    "Control",
    "Slider",
    "Number",
    "Checkbox",
    "Text",
    "Dropdown",
    "Button",
    "Series",
    "Plot",
    "Image",
    "Scene",
    "Node3D",
    "GUI_KINDS",
]


class Dynamic:
    """A property computed from the model: ``fn(model) -> value``.

    ``source`` is the spec expression it came from (shown in error messages and tooltips).
    """

    __slots__ = ("fn", "source")

    def __init__(self, fn: Callable[[Any], Any], source: str = "") -> None:
        self.fn = fn
        self.source = source

    def __call__(self, model: Any) -> Any:
        return self.fn(model)

    def __repr__(self) -> str:
        return f"Dynamic({self.source!r})"


def is_dynamic(prop: Any) -> bool:
    """True if ``prop`` must be evaluated against the model each frame."""
    return isinstance(prop, Dynamic)


def value_of(prop: Any, model: Any) -> Any:
    """The current value of a constant or dynamic property."""
    return prop(model) if isinstance(prop, Dynamic) else prop


@dataclass
class Element:
    """Base of every view element; ``where`` is its spec location."""

    where: str = field(default="", kw_only=True)


# -- containers and static text -------------------------------------------------------


@dataclass
class Folder(Element):
    """A collapsible group of GUI elements."""

    label: str
    children: list[Element]
    expanded: bool = True


@dataclass
class Tabs(Element):
    """Tabs: ``tabs`` is a list of ``(tab label, children)``."""

    tabs: list[tuple[str, list[Element]]]


@dataclass
class Markdown(Element):
    """Static Markdown text."""

    text: str


@dataclass
class Label(Element):
    """A line of text updated every frame; ``text`` is a constant or ``Dynamic`` giving str."""

    text: Any


# -- controls bound to model variables ---------------------------------------------------


@dataclass
class Control(Element):
    """Base of the controls that show and edit one model variable (or array element).

    ``bind``: the spec's target text (``"L"`` or ``"q[2]"``); ``get(model)`` reads it and
    ``set(model, value)`` writes it; ``on_change(model)`` runs after a change made in the UI
    (then the app runs the fixed relations). ``vtype`` is the variable's value type:
    ``"float"``, ``"int"``, ``"bool"`` or ``"str"``.
    """

    bind: str
    get: Callable[[Any], Any]
    set: Callable[[Any, Any], None]
    label: str = ""
    on_change: Callable[[Any], None] | None = None
    vtype: str = "float"


@dataclass
class Slider(Control):
    """A slider over ``[min, max]`` with ``step``."""

    min: float = 0.0
    max: float = 1.0
    step: float | None = None


@dataclass
class Number(Control):
    """A number field, clamped to ``[min, max]`` when given."""

    min: float | None = None
    max: float | None = None
    step: float | None = None


@dataclass
class Checkbox(Control):
    """A checkbox bound to a boolean variable."""


@dataclass
class Text(Control):
    """A text field bound to a string variable."""


@dataclass
class Dropdown(Control):
    """A choice among ``options`` (the values the variable may take)."""

    options: Sequence[Any] = ()


@dataclass
class Button(Element):
    """A button running ``action(model)`` (then the fixed relations)."""

    label: str
    action: Callable[[Any], None]


# -- plots and images -----------------------------------------------------------------------


@dataclass
class Series(Element):
    """One curve of a plot: ``y`` is a ``Dynamic`` giving a number."""

    y: Any
    label: str = ""
    color: Any = None


@dataclass
class Plot(Element):
    """A line plot of ``series`` against the numeric ``x`` (a ``Dynamic``), one point a frame.

    ``window``: the x-span kept (None keeps everything up to ``max_points``);
    ``y_range``: fixed ``(ymin, ymax)`` or None for automatic.
    """

    title: str
    x: Any
    series: list[Series]
    window: float | None = None
    max_points: int = 2000
    y_range: tuple[float, float] | None = None


@dataclass
class Image(Element):
    """An image: ``source`` gives an (H, W) or (H, W, 3) uint8 array; ``points`` (N, 2) (x, y)."""

    source: Any
    label: str = ""
    points: Any = None


# -- the 3D scene ---------------------------------------------------------------------------


@dataclass
class Node3D(Element):
    """One 3D element of the scene.

    ``kind``: the spec's element kind (``box``, ``sphere``, ..., ``group``, ``robot``,
    ``camera``, ``gizmo``); ``name``: unique in the scene (the generator makes one up for
    unnamed elements); ``props``: the kind's own properties, constant or ``Dynamic``;
    the pose is ``transform`` (a (4, 4) constant or ``Dynamic``) or ``position`` (3,) with
    optional ``rotation`` (roll, pitch, yaw, radians); ``children`` for groups.
    Common properties ``visible``, ``color``, ``opacity``, ``graspable`` may be dynamic too.
    """

    kind: str
    name: str
    props: dict[str, Any] = field(default_factory=dict)
    position: Any = None
    rotation: Any = None
    transform: Any = None
    visible: Any = True
    color: Any = None
    opacity: Any = 1.0
    graspable: bool = False
    children: list[Node3D] = field(default_factory=list)
    #: for ``gizmo``: writes the dragged (4, 4) pose into the bound variable
    set: Callable[[Any, Any], None] | None = None
    on_change: Callable[[Any], None] | None = None


@dataclass
class Scene(Element):
    """The 3D world: a list of ``Node3D``."""

    children: list[Node3D]


GUI_KINDS = ("folder", "tabs", "markdown", "label", "slider", "number", "checkbox", "text", "dropdown", "button", "plot", "image", "scene")
