"""Descriptions of view elements, as a generated app declares them.

The generator turns each element of a spec's ``view`` into one of these plain records.
A *dynamic* property is a function of the model (``Callable[[model], value]``), made from
a spec expression compiled into a method of the generated ``Model`` class; a constant
property is the value itself. :func:`value_of` reads either kind.

``where`` is the element's location in the spec (``"lab.ejs.yaml:12:5"``), shown with any
error its expressions raise.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "Dynamic",
    "is_dynamic",
    "value_of",
    "format_value",
    "escape_markdown",
    "escaped",
    "keep_spaces",
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
]


class Dynamic:
    """A property computed from the model: ``fn(model) -> value``.

    ``source`` is the spec expression it came from (shown in error messages and tooltips).
    ``fn`` may also be a bind path (``Dynamic("t")``, ``Dynamic("q[2]")``): the value of
    that variable or element, read by :func:`ejsrl.sim.paths.getter`.
    """

    __slots__ = ("fn", "source")

    def __init__(self, fn: Callable[[Any], Any] | str, source: str = "") -> None:
        if isinstance(fn, str):
            from ejsrl.sim.paths import getter

            fn, source = getter(fn), source or fn
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


# -- text shown in labels --------------------------------------------------------------


def format_value(value: Any, spec: str = "") -> str:
    """``format(value, spec)``, as ``{value:spec}`` in an f-string, extended to arrays.

    An array (or a list of numbers) is formatted element by element with ``spec``: a
    vector as ``[a b c]``, a matrix as one row per line with its columns aligned
    (right-justified), so that ``{T:+.3f}`` shows a 4x4 pose as a readable block.
    """
    if isinstance(value, (list, tuple)) and spec:
        try:
            value = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            return format(value, spec)
    if isinstance(value, np.ndarray) and value.ndim in (1, 2) and value.dtype.kind in "biuf":
        if not spec:
            spec = "g" if value.dtype.kind == "f" else "d"
        cells = [[_format_number(x.item(), spec) for x in row] for row in np.atleast_2d(value)]
        width = max((len(c) for row in cells for c in row), default=0)
        rows = ["[" + " ".join(c.rjust(width) for c in row) + "]" for row in cells]
        if value.ndim == 1:
            return rows[0]
        return "\n".join(rows)
    return _format_number(value, spec)


def _format_number(value: Any, spec: str) -> str:
    """``format(value, spec)``, but a float that rounds to zero reads 0, never -0 ("-0.000" -> "0.000", "+0.000")."""
    text = format(value, spec)
    if isinstance(value, (float, np.floating)) and "-" in text and math.isfinite(value):
        mantissa = text.lower().partition("e")[0]
        if not any(c in "123456789" for c in mantissa):
            text = format(0.0 * abs(float(value)), spec)  # +0.0 written the same way
    return text


_MD_SPECIAL = re.compile(r"[^\w\s\u00a0-\uffff]|_", re.ASCII)


def escape_markdown(text: str) -> str:
    """``text`` made inert for the Markdown (and raw HTML) renderer of the control panel.

    Every ASCII character other than letters, digits and whitespace becomes a numeric
    character reference (``<`` -> ``&#60;``), so no tag, entity, emphasis, link, image,
    list, heading or code span can start inside it; the renderer shows the characters
    themselves. Spaces and line breaks are left for :func:`keep_spaces`.
    """
    return _MD_SPECIAL.sub(lambda m: f"&#{ord(m.group())};", text)


#: a matrix value is shown as one block: its rows one under the other, columns aligned
_BLOCK = '<span style="display:inline-block;vertical-align:middle;font-family:monospace;white-space:pre">'


def escaped(value: Any, spec: str = "") -> str:
    """A value interpolated into a label: formatted (:func:`format_value`), then escaped.

    The generated code wraps every ``{expr}`` of a ``label`` in this, so that a value --
    text a user typed into a field, say -- is shown as text to every client, never run
    as HTML. A value of several lines (a matrix) is shown as one aligned block.
    """
    text = escape_markdown(format_value(value, spec))
    if "\n" in text:
        return _BLOCK + text.replace(" ", "&#32;").replace("\n", "<br>") + "</span>"
    return text


_RUN = re.compile(r" {2,}")
#: the delimiter row under a Markdown table's header: | --- | :-: | ---: |
_TABLE_RULE = re.compile(r"^\s*\|?\s*:?-+:?\s*(\|\s*:?-+:?\s*)*\|?\s*$")


def _spaced(line: str) -> str:
    body = line.lstrip(" ")
    lead = "&nbsp;" * (len(line) - len(body))
    return lead + _RUN.sub(lambda m: " " + "&nbsp;" * (len(m.group()) - 1), body)


def _is_table_start(lines: list[str], i: int) -> bool:
    """Whether a Markdown table (a header row, then its delimiter row) starts at line ``i``."""
    return i + 1 < len(lines) and "|" in lines[i] and "|" in lines[i + 1] and bool(_TABLE_RULE.match(lines[i + 1]))


def keep_spaces(text: str) -> str:
    """Markdown that shows ``text``'s spaces and line breaks as written, and its tables as tables.

    Runs of spaces and the spaces that start a line become non-breaking spaces (the
    renderer would collapse them, and would show a line indented by four as a code
    box); a line break becomes ``<br>``. A Markdown table (a header row with ``|``, a
    delimiter row such as ``|---|--:|``, then rows with ``|``) is kept as lines of its
    own, a block apart from the text around it, so the renderer draws it as a table.
    A value interpolated into a cell (``E.escaped``) cannot end it or add a cell: its
    ``|`` and line breaks arrive as character references and ``<br>``.
    """
    lines = text.replace("\t", "    ").split("\n")
    blocks: list[str] = []
    para: list[str] = []
    i = 0
    while i < len(lines):
        if not _is_table_start(lines, i):
            para.append(lines[i])
            i += 1
            continue
        if para and not para[-1].strip():
            para.pop()  # the blank line before the table: the block break stands for it
        if para:
            blocks.append("<br>".join(_spaced(line) for line in para))
        para = []
        end = i + 2
        while end < len(lines) and "|" in lines[end] and lines[end].strip():
            end += 1
        blocks.append("\n".join(line.strip() for line in lines[i:end]))
        i = end
        if i < len(lines) and not lines[i].strip():
            i += 1  # the blank line after it, likewise
    if para or not blocks:
        blocks.append("<br>".join(_spaced(line) for line in para))
    return "\n\n".join(blocks)


@dataclass
class Element:
    """Base of every view element; ``where`` is its spec location."""

    where: str = field(default="", kw_only=True)


# -- containers and static text -------------------------------------------------------


@dataclass
class Folder(Element):
    """A collapsible group of GUI elements; ``label`` is text or a ``Dynamic`` giving text."""

    label: Any
    children: list[Element]
    expanded: bool = True


@dataclass
class Tabs(Element):
    """Tabs: ``tabs`` is a list of ``(tab label, children)``; a label may be a ``Dynamic``."""

    tabs: list[tuple[Any, list[Element]]]


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
    ``set(model, value)`` writes it (made from ``bind`` by :mod:`ejsrl.sim.paths` when not given); ``on_change(model)`` runs after a change made in the UI
    (then the app runs the fixed relations). ``vtype`` is the variable's value type:
    ``"float"``, ``"int"``, ``"bool"`` or ``"str"``. ``label``: text or a ``Dynamic``.
    """

    bind: str
    get: Callable[[Any], Any] = None  # type: ignore[assignment]
    set: Callable[[Any, Any], None] = None  # type: ignore[assignment]
    label: Any = ""
    on_change: Callable[[Any], None] | None = None
    vtype: str = "float"

    def __post_init__(self) -> None:
        from ejsrl.sim.paths import getter, setter

        if self.get is None:
            self.get = getter(self.bind)
        if self.set is None:
            self.set = setter(self.bind)

    @property
    def title(self) -> str:
        """What messages call the control: its label when that is constant text, else its ``bind``."""
        return self.label if isinstance(self.label, str) and self.label else self.bind


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
    """A button running ``action(model)`` (then the fixed relations); ``label`` may be a ``Dynamic``."""

    label: Any
    action: Callable[[Any], None]


# -- plots and images -----------------------------------------------------------------------


@dataclass
class Series(Element):
    """One series of a plot.

    ``y``: a ``Dynamic`` giving a number (a point per frame) or a 1-D array (a curve
    redrawn every frame); ``x``: the series' own x (None: the plot's), a number (an x-y
    history of its own, ``max_points`` long) or an array as long as ``y``; ``kind``:
    ``"line"``, ``"scatter"`` or ``"histogram"`` (bars counting the values of ``x``, a
    number's history or an array, in ``bins`` bins over ``bin_range`` or their extent);
    ``marker``/``size``: marker shape and size (px); ``width``: line width (px).
    """

    y: Any = None
    label: Any = ""
    color: Any = None
    x: Any = None
    kind: str = "line"
    marker: str | None = None
    size: float = 6.0
    width: float = 2.0
    max_points: int | None = None
    bins: int = 20
    bin_range: tuple[float, float] | None = None


@dataclass
class Plot(Element):
    """A plot of ``series`` (EjsS's plotting panel), drawn by the 2D panel.

    ``x``: the x (a ``Dynamic`` or constant) of the series without one of their own: a
    number (their points, one a frame, form a strip chart) or a 1-D array; ``window``: the
    x-span kept (None keeps everything up to ``max_points``); ``x_range``/``y_range``:
    fixed ``(lo, hi)`` or None for automatic; ``x_log``/``y_log``: logarithmic axes;
    ``legend``: draw the labels in the plot (None: when there are two series or more);
    ``height``: pixels (None: the panel's choice). ``title`` and each series' ``label``
    are constant text or a ``Dynamic`` (a text with ``{expr}``).
    """

    title: Any
    x: Any
    series: list[Series]
    window: float | None = None
    max_points: int = 2000
    y_range: tuple[float, float] | None = None
    #: axis titles ("t (s)"); empty: the x expression, and no y title
    x_label: str = ""
    y_label: str = ""
    x_range: tuple[float, float] | None = None
    x_log: bool = False
    y_log: bool = False
    legend: bool | None = None
    grid: bool = True
    height: int | None = None


@dataclass
class Image(Element):
    """An image: ``source`` gives an (H, W) or (H, W, 3) uint8 array; ``points`` (N, 2) (x, y)."""

    source: Any
    label: Any = ""
    points: Any = None


# -- the 3D scene ---------------------------------------------------------------------------


@dataclass
class Node3D(Element):
    """One 3D element of the scene.

    ``kind``: the spec's element kind (``box``, ``sphere``, ..., ``group``, ``robot``,
    ``camera``, ``gizmo``), declared with its properties in ``ejsrl.world.kinds.KINDS``;
    ``name``: unique in the scene (the generator makes one up for unnamed elements);
    ``props``: the kind's own properties (its declared value properties), constant or ``Dynamic``;
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
    #: for ``gizmo``: the bound (4, 4) pose variable; gives ``transform`` and ``set`` when they are not given
    bind: str | None = None

    def __post_init__(self) -> None:
        from difflib import get_close_matches

        if self.bind is not None:
            from ejsrl.sim.paths import setter

            if self.transform is None:
                self.transform = Dynamic(self.bind)
            if self.set is None:
                self.set = setter(self.bind)

        from ejsrl.world.kinds import KINDS  # imported here: the world package imports this module

        decl = KINDS.get(self.kind)
        at = f"{self.where}: " if self.where else ""
        if decl is None:
            close = get_close_matches(self.kind, list(KINDS), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else f" (kinds: {', '.join(KINDS)})"
            raise ValueError(f"{at}unknown 3D element kind {self.kind!r}{hint}")
        known = [p.name for p in decl.props if p.is_value]
        for key in self.props:
            if key not in known:
                close = get_close_matches(key, known, n=1)
                hint = f"; did you mean {close[0]!r}?" if close else f" (it has: {', '.join(known) or 'none'})"
                raise ValueError(f"{at}a {self.kind} has no property {key!r}{hint}")


@dataclass
class Scene(Element):
    """The 3D world: a list of ``Node3D``."""

    children: list[Node3D]


# the 2D drawing panel's records (ejsrl.view.elements2d), re-exported for generated apps (E.Drawing, ...)
from ejsrl.view.elements2d import Drag2D, Drawing, SceneKeys, Shape2D  # noqa: E402

__all__ += ["Drawing", "Shape2D", "Drag2D", "SceneKeys"]


# the data and text elements' records (ejsrl.view.elements_text), re-exported for generated apps (E.Table, ...)
from ejsrl.view.elements_text import Console, Table, TableRow  # noqa: E402

__all__ += ["Table", "TableRow", "Console"]
