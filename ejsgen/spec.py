"""The ``.ejs.yaml`` language, version 1, as pydantic models.

Every model forbids unknown keys and documents every field (the docstrings become the
JSON Schema's descriptions, ``ejsgen schema``). Values that may be constants or
expressions are typed as unions with ``str`` (a string is an expression); the compiler
checks the expressions.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Union

from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, create_model, model_validator

from ejsrl.sim.ode import METHODS
from ejsrl.world.kinds import COMMON, KINDS, Prop

__all__ = [
    "Spec",
    "Model",
    "Variable",
    "CodePage",
    "Code",
    "OdeEvent",
    "Ode",
    "OdePage",
    "CodeEvolutionPage",
    "Program",
    "Simulation",
    "Fmu",
    "GUI_ELEMENT_MODELS",
    "SCENE_ELEMENT_MODELS",
    "ODE_METHODS",
]

ODE_METHODS = METHODS  # the runtime's solvers are the language's methods


class Strict(BaseModel):
    """Base: unknown keys are errors; attribute docstrings document the fields."""

    model_config = ConfigDict(extra="forbid", use_attribute_docstrings=True, populate_by_name=True)


class Derived(Strict):
    """Base of the models made by ``create_model`` (3D kinds, view lists): their fields carry
    their descriptions already, so pydantic need not search source code for attribute
    docstrings (that search cost over half a second of every ``ejsgen`` command's start)."""

    model_config = ConfigDict(use_attribute_docstrings=False)


Expr = str
Number = Union[float, int]
NumOrExpr = Union[float, int, str]
"""A number, or a string holding a Python expression."""
BoolOrExpr = Union[bool, str]
VecOrExpr = Union[str, list[Union[float, int, str]]]
"""A list of numbers/expressions, or one expression giving an array."""
MatOrExpr = Union[str, list[list[Union[float, int, str]]], list[Union[float, int, str]]]
ColorValue = Union[str, list[Union[float, int, str]]]
"""A CSS colour name, '#rrggbb', or an expression giving an RGB triple."""


# -- model ---------------------------------------------------------------------------------


class Variable(Strict):
    """A variable in long form: exactly one of ``value`` or ``expr``."""

    value: Any = None
    """Initial value: a number, boolean, string, or (nested) list of numbers."""
    expr: str | None = None
    """A Python expression evaluated once, in declaration order, giving the initial value."""
    doc: str | None = None
    """What the variable means (shown as a tooltip)."""
    unit: str | None = None
    """Its unit, e.g. 'm' or 'rad' (SI units and radians inside)."""
    min: float | None = None
    """Lowest value a control bound to it may set."""
    max: float | None = None
    """Highest value a control bound to it may set."""

    @model_validator(mode="after")
    def _one_of(self) -> Variable:
        has_value = "value" in self.model_fields_set
        has_expr = self.expr is not None
        if has_value == has_expr:
            raise ValueError("a variable needs exactly one of 'value' or 'expr'")
        return self


class CodePage(Strict):
    """One page of a code block; pages run in order."""

    name: str = ""
    """A title for the page."""
    code: str
    """Python code."""
    enabled: bool = True
    """A disabled page does not run."""


Code = Union[str, list[CodePage]]
"""Python code: a string, or a list of pages."""


class OdeEvent(Strict):
    """An event: fires when ``when`` crosses zero in the given direction during a step."""

    name: str = ""
    """A name, used in messages."""
    when: Expr
    """An expression of the state; the event fires when it crosses zero."""
    direction: Literal["up", "down", "both"] = "both"
    """Which crossings count: up (- to +), down (+ to -) or both."""
    action: Code = ""
    """Code run at the event's time, with the state set to its value then."""
    stop: bool = False
    """Pause the simulation after the action."""


class Ode(Strict):
    """Ordinary differential equations advanced by ``step`` each simulation step."""

    independent: str = "t"
    """The independent variable (time)."""
    step: NumOrExpr = "dt"
    """How much the independent variable advances each step (an expression)."""
    method: Literal[METHODS] = "rk4"  # type: ignore[valid-type]
    """The solver: explicit fixed-step, explicit adaptive, or implicit (radau, bdf) for stiff models."""
    tolerance: float = Field(default=1e-6, gt=0)
    """Absolute and relative tolerance of adaptive and implicit methods."""
    max_step: float | None = Field(default=None, gt=0)
    """Largest internal step of adaptive and implicit methods."""
    equations: dict[str, NumOrExpr]
    """Ordered mapping state_variable: rate expression."""
    preliminary: Code | None = None
    """Code run before each evaluation of the rates."""
    events: list[OdeEvent] = Field(default_factory=list)
    """Events located in time during a step."""


class OdePage(Strict):
    """An evolution page holding ODEs."""

    ode: Ode
    """The equations."""
    name: str = ""
    """A title for the page."""
    enabled: bool = True
    """A disabled page does not run."""


class CodeEvolutionPage(Strict):
    """An evolution page of code run once per step."""

    code: str
    """Python code."""
    name: str = ""
    """A title for the page."""
    enabled: bool = True
    """A disabled page does not run."""


def _evolution_tag(v: Any) -> str | None:
    if isinstance(v, dict):
        if "ode" in v:
            return "ode"
        if "code" in v:
            return "code"
        return None
    return getattr(v, "__class__", type(None)).__name__ == "OdePage" and "ode" or "code"


EvolutionPage = Annotated[
    Union[Annotated[OdePage, Tag("ode")], Annotated[CodeEvolutionPage, Tag("code")]],
    Discriminator(_evolution_tag, custom_error_type="evolution_page", custom_error_message="an evolution page needs 'code' or 'ode'"),
]


class Program(Strict):
    """A robot program running alongside the simulation in simulated time."""

    robot: str
    """The Robot variable it moves."""
    q: str
    """The joint-vector variable it drives."""
    gripper: str | None = None
    """Optional number variable, 0 closed to 1 open."""
    autostart: bool = False
    """Start when the simulation starts."""
    code: Code
    """The program: Python with move_j, move_l, wait, wait_until, open_gripper, close_gripper."""


class Model(Strict):
    """Variables, initialization, evolution, fixed relations, custom methods and programs."""

    variables: dict[str, Any] = Field(default_factory=dict)
    """Variables in declaration order: a plain value, or a long form {value|expr, doc, unit, min, max}."""
    init: Code | None = None
    """Runs at start and on reset(), after the variables take their initial values."""
    evolution: list[EvolutionPage] = Field(default_factory=list)
    """Pages run in order once per simulation step."""
    fixed_relations: Code | None = None
    """Runs after init, after every step, and after every change made from the view."""
    custom: Code | None = None
    """Function definitions callable from all code, actions and expressions."""
    programs: dict[str, Program] = Field(default_factory=dict)
    """Robot programs by name."""


# -- view: GUI elements ------------------------------------------------------------------------


class _Bound(Strict):
    bind: str
    """The model variable (or array element, 'q[2]') this control shows and edits."""
    label: str | None = None
    """Text beside the control (default: the bind target); {expr} and {expr:fmt} are interpolated."""
    on_change: Code | None = None
    """Code run after the user changes the value (then the fixed relations)."""


class FolderEl(Strict):
    """A collapsible group of elements."""

    label: str = ""
    """The folder's title; {expr} and {expr:fmt} are interpolated."""
    expanded: bool = True
    """Open at start."""
    children: list[Any] = Field(default_factory=list)
    """The elements inside."""


class TabsEl(Strict):
    """Tabs, each a list of elements."""

    tabs: dict[str, list[Any]]
    """Tab label (with {expr} interpolated): list of elements."""


class MarkdownEl(Strict):
    """Static Markdown text."""

    text: str
    """The Markdown."""


class LabelEl(Strict):
    """A line of text with {expr} / {expr:fmt} interpolated every frame."""

    text: str
    """The text: Markdown written in the spec, with each {expr} / {expr:fmt} value shown as plain text."""


class SliderEl(_Bound):
    """A slider."""

    min: Number
    """Lowest value."""
    max: Number
    """Highest value."""
    step: Number | None = None
    """Increment (default: a hundredth of the range)."""


class NumberEl(_Bound):
    """A number field."""

    min: Number | None = None
    """Lowest value (values below are clamped)."""
    max: Number | None = None
    """Highest value (values above are clamped)."""
    step: Number | None = None
    """Increment of the arrows."""


class CheckboxEl(_Bound):
    """A checkbox bound to a boolean variable."""


class TextEl(_Bound):
    """A text field bound to a string variable."""


class DropdownEl(_Bound):
    """A choice among fixed options."""

    options: list[Union[str, float, int, bool]]
    """The values the variable may take."""


class ButtonEl(Strict):
    """A button that runs code."""

    label: str
    """The button's text; {expr} and {expr:fmt} are interpolated."""
    action: Code
    """Code run when pressed (then the fixed relations)."""


class SeriesEl(Strict):
    """One series of a plot: a history (one point per frame), a curve of arrays redrawn every frame, or a histogram."""

    y: NumOrExpr | None = None
    """Expression giving the y value: a number (a point per frame) or a 1-D array (a curve, with x an array as long)."""
    x: NumOrExpr | None = None
    """The series' own x (default: the plot's x). Numbers: an x-y history (a phase orbit, kept whole, max_points long); 1-D arrays as long as y: a curve redrawn every frame. A histogram counts the values of x: a number (its history) or an array."""
    label: str | None = None
    """Legend text (default: the expression); {expr} and {expr:fmt} are interpolated."""
    color: str | None = None
    """CSS colour of the line, markers or bars."""
    type: Literal["line", "scatter", "histogram"] = "line"
    """line (points joined), scatter (markers only) or histogram (bars counting the values of x in bins)."""
    marker: Literal["circle", "square", "cross", "triangle"] | None = None
    """Marker shape: of a scatter series (default circle), or drawn on every point of a line."""
    size: float = Field(default=6.0, gt=0, le=100)
    """Marker size in pixels."""
    width: float = Field(default=2.0, gt=0, le=50)
    """Line width in pixels."""
    max_points: int | None = Field(default=None, ge=2, le=100000)
    """Points kept by a series with its own x, or values kept by a histogram of a number (default: the plot's max_points)."""
    bins: int | None = Field(default=None, ge=1, le=10000)
    """A histogram's number of bins (default 20)."""
    bin_range: list[Number] | None = None
    """A histogram's [lo, hi] (default: the values' extent); values outside are not counted."""


class PlotEl(Strict):
    """A plot (EjsS's plotting panel): histories against time, x-y orbits, curves of arrays, scatter and histograms."""

    title: str = ""
    """The plot's title; {expr} and {expr:fmt} are interpolated."""
    x: NumOrExpr = "t"
    """Expression giving the x value of the series that have no x of their own (default t)."""
    series: list[SeriesEl]
    """The series, drawn in order."""
    window: float | None = Field(default=None, gt=0)
    """The x-span kept (older points scroll out)."""
    max_points: int = Field(default=2000, ge=2, le=100000)
    """Most points kept per curve."""
    y_range: list[Number] | None = None
    """Fixed [ymin, ymax] (default: automatic)."""
    x_range: list[Number] | None = None
    """Fixed [xmin, xmax] (default: automatic: the window, or the data's extent)."""
    x_log: bool = False
    """A logarithmic x axis (values <= 0 are not drawn)."""
    y_log: bool = False
    """A logarithmic y axis (values <= 0 are not drawn)."""
    legend: bool | None = None
    """Show the series' labels in the plot (default: when it has two series or more)."""
    grid: bool = True
    """Grid lines at the ticks."""
    height: int | None = Field(default=None, ge=80, le=2000)
    """The plot's height in pixels (default 240; 300 in a lab without a 3D scene)."""
    x_label: str | None = None
    """Title of the x axis (default: the x expression and its variable's unit, 't (s)')."""
    y_label: str | None = None
    """Title of the y axis (default: the unit the series' variables share, if any)."""


class ImageEl(Strict):
    """An image from an expression, with optional points drawn over it."""

    source: Expr
    """Expression giving an HxW or HxWx3 uint8 array, e.g. capture("eih")."""
    label: str | None = None
    """Caption; {expr} and {expr:fmt} are interpolated."""
    points: Expr | None = None
    """Expression giving Nx2 pixel coordinates (x, y) = (column, row)."""


class SceneEl(Strict):
    """Placeholder: a scene is a list of 3D elements (validated item by item)."""


GUI_ELEMENT_MODELS: dict[str, type[Strict]] = {
    "folder": FolderEl,
    "tabs": TabsEl,
    "markdown": MarkdownEl,
    "label": LabelEl,
    "slider": SliderEl,
    "number": NumberEl,
    "checkbox": CheckboxEl,
    "text": TextEl,
    "dropdown": DropdownEl,
    "button": ButtonEl,
    "plot": PlotEl,
    "image": ImageEl,
}

from ejsgen._spec_text import ConsoleEl, TableEl  # noqa: E402 - they build on Strict

GUI_ELEMENT_MODELS["table"] = TableEl
GUI_ELEMENT_MODELS["console"] = ConsoleEl

from ejsgen._spec2d import DrawingEl, KeyboardEl  # noqa: E402 - it builds on the types above

GUI_ELEMENT_MODELS["drawing"] = DrawingEl
GUI_ELEMENT_MODELS["keyboard"] = KeyboardEl

# -- view: 3D elements ------------------------------------------------------------------------
# Derived from the kinds' declarations (ejsrl.world.kinds): one model per kind, named
# ``<Kind>El``, with the common properties first.

#: property type (ejsrl.world.kinds) -> the values the spec may give, written as in a class body
#: (postponed annotations, resolved in this module; the docs tables read them as written)
_ANNOTATIONS: dict[str, str] = {
    "num": "NumOrExpr",
    "vec3": "VecOrExpr",
    "vec": "VecOrExpr",
    "mat": "MatOrExpr",
    "mat4": "MatOrExpr",
    "mat3": "MatOrExpr",
    "text": "str",
    "file": "str",
    "expr": "Expr",
    "name": "str",
    "bind": "str",
    "int": "int",
    "bool": "bool",
    "flag": "BoolOrExpr",
    "color": "ColorValue",
    "files": "list[str]",
    "ints2": "list[int]",
    "code": "Code",
    "children": "list[Any]",
    "source": "Union[int, str]",
}


def _field(prop: Prop) -> tuple[str, Any]:
    """The pydantic field (annotation, FieldInfo) of a declared property."""
    annotation = _ANNOTATIONS[prop.type]
    bounds = {k: v for k, v in (("ge", prop.ge), ("le", prop.le)) if v is not None}
    if prop.required:
        return annotation, Field(description=prop.doc, **bounds)
    if prop.default is None:
        return f"{annotation} | None", Field(default=None, description=prop.doc, **bounds)
    if isinstance(prop.default, tuple):
        items = prop.default
        return annotation, Field(default_factory=lambda: list(items), description=prop.doc, **bounds)
    return annotation, Field(default=prop.default, description=prop.doc, **bounds)


def _scene_models() -> dict[str, type[Strict]]:
    """One model per declared 3D element kind, ``<Kind>El``, the common properties first."""
    base = create_model("_Node", __base__=Derived, **{p.name: _field(p) for p in COMMON})  # type: ignore[call-overload]
    return {
        name: create_model(f"{name.capitalize()}El", __base__=base, __doc__=kind.doc, **{p.name: _field(p) for p in kind.props})  # type: ignore[call-overload]
        for name, kind in KINDS.items()
    }


SCENE_ELEMENT_MODELS: dict[str, type[Strict]] = _scene_models()


class Simulation(Strict):
    """How the simulation runs and is displayed."""

    fps: float = Field(default=30, gt=0, le=240)
    """Display frames per second."""
    steps_per_display: int = Field(default=1, ge=1, le=100000)
    """Simulation steps per display frame."""
    autoplay: bool = False
    """Start playing when the app starts."""
    realtime: bool = False
    """Pace the independent variable to the wall clock."""
    controls: bool = True
    """Show the play/pause/step/reset bar."""
    panel_width: int | None = Field(default=None, ge=200, le=1200)
    """Width of the control panel in pixels (default: the browser's choice, about 320)."""


class Fmu(Strict):
    """A Functional Mock-up Unit (FMI 2.0 or 3.0, e.g. exported from Simulink) computing part of the model."""

    file: str
    """The FMU, relative to the spec: an .fmu file, or a folder holding an unpacked FMU whose sources/ the build compiles."""
    kind: Literal["co_simulation", "model_exchange"] | None = None
    """co_simulation (the FMU steps itself, doStep) or model_exchange (an ODE page integrates its states); default: co_simulation if the FMU has it."""
    step: NumOrExpr | None = None
    """Co-simulation: the communication step (an expression); default: one doStep per model step."""
    ode: str | int | None = None
    """Model exchange: the ODE page integrating its states (the page's name or its index in evolution); default: the first ODE page."""
    method: Literal[METHODS] = "dopri5"  # type: ignore[valid-type]
    """Model exchange in a model without ODE pages: the solver of the FMU's own states, advanced to the model's time after each step."""
    tolerance: float = Field(default=1e-6, gt=0)
    """Model exchange with its own solver: the adaptive or implicit method's absolute and relative tolerance."""
    inputs: dict[str, NumOrExpr] = Field(default_factory=dict)
    """FMU input variable: expression giving its value (sent at every communication point, or every evaluation of the rates)."""
    outputs: dict[str, str] = Field(default_factory=dict)
    """FMU output variable: the model variable (or array element, 'tau[0]') that receives its value."""
    parameters: dict[str, Union[bool, float, int, str]] = Field(default_factory=dict)
    """FMU parameter: expression giving its value when the FMU is instantiated (at start and reset); tunable ones are sent again when it changes."""
    start: dict[str, Union[bool, float, int]] = Field(default_factory=dict)
    """FMU variable: constant start value (e.g. of a state)."""


from ejsgen._spec_plant import Plant  # noqa: E402 - it builds on Strict


class Spec(Strict):
    """A whole ``.ejs.yaml`` file."""

    ejs: Literal[1]
    """Format version (1)."""
    title: str
    """The app's title."""
    description: str = ""
    """Markdown shown in the app's About panel."""
    author: str = ""
    """Who wrote it."""
    imports: list[str] = Field(default_factory=list)
    """Extra import lines, visible to all code."""
    assets: list[str] = Field(default_factory=list)
    """Files relative to the spec, copied into the app."""
    model: Model = Field(default_factory=Model)
    """The model."""
    view: list[dict[str, Any]] = Field(default_factory=list)
    """The view: a list of one-key mappings kind: {properties}."""
    simulation: Simulation = Field(default_factory=Simulation)
    """Simulation settings."""
    metrics: dict[str, Expr] = Field(default_factory=dict)
    """Per-run results of a sweep (ejsgen sweep): name: expression, evaluated on the state at the end of each run; each is a column of the sweep's summary."""
    fmus: dict[str, Fmu] = Field(default_factory=dict)
    """Functional Mock-up Units by name, co-simulated with the model (FMPy: pip install 'ejsgen[fmu]')."""
    plant: Plant | None = None
    """A real plant the lab drives in its Real plant mode (a remote laboratory: MQTT through paho-mqtt, pip install 'ejsgen[plant]')."""
