"""The ``.ejs.yaml`` language, version 1, as pydantic models.

Every model forbids unknown keys and documents every field (the docstrings become the
JSON Schema's descriptions, ``ejsgen schema``). Values that may be constants or
expressions are typed as unions with ``str`` (a string is an expression); the compiler
checks the expressions.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Union

from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, model_validator

from ejsrl.sim.ode import METHODS

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
    "VIEW_KINDS",
    "GUI_ELEMENT_MODELS",
    "SCENE_ELEMENT_MODELS",
    "ODE_METHODS",
]

ODE_METHODS = METHODS  # the runtime's solvers are the language's methods


class Strict(BaseModel):
    """Base: unknown keys are errors; attribute docstrings document the fields."""

    model_config = ConfigDict(extra="forbid", use_attribute_docstrings=True, populate_by_name=True)


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
    """One curve of a plot."""

    y: NumOrExpr
    """Expression giving the y value."""
    label: str | None = None
    """Legend text (default: the expression); {expr} and {expr:fmt} are interpolated."""
    color: str | None = None
    """CSS colour of the line."""


class PlotEl(Strict):
    """A line plot against a numeric x, one point per frame."""

    title: str = ""
    """The plot's title; {expr} and {expr:fmt} are interpolated."""
    x: NumOrExpr = "t"
    """Expression giving the x value (default t)."""
    series: list[SeriesEl]
    """The curves."""
    window: float | None = Field(default=None, gt=0)
    """The x-span kept (older points scroll out)."""
    max_points: int = Field(default=2000, ge=2, le=100000)
    """Most points kept per curve."""
    y_range: list[Number] | None = None
    """Fixed [ymin, ymax] (default: automatic)."""
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

# -- view: 3D elements ------------------------------------------------------------------------


class _Node(Strict):
    name: str | None = None
    """Name by which code refers to the object (unique in the scene)."""
    visible: BoolOrExpr = True
    """Shown or hidden."""
    color: ColorValue | None = None
    """CSS name, '#rrggbb', or an expression giving an RGB triple (0-1 floats)."""
    opacity: NumOrExpr = 1.0
    """0 transparent to 1 opaque."""
    graspable: bool = False
    """A robot gripper may pick it up."""
    position: VecOrExpr | None = None
    """[x, y, z] in metres (in the parent group's frame)."""
    rotation: VecOrExpr | None = None
    """[roll, pitch, yaw] in radians (ZYX: Rz(yaw) Ry(pitch) Rx(roll))."""
    transform: MatOrExpr | None = None
    """A 4x4 homogeneous pose (instead of position/rotation)."""


class BoxEl(_Node):
    """A box centred on its pose."""

    size: VecOrExpr = Field(default_factory=lambda: [1.0, 1.0, 1.0])
    """Edge lengths [x, y, z]."""


class SphereEl(_Node):
    """A sphere."""

    radius: NumOrExpr = 0.5
    """Radius in metres."""


class CylinderEl(_Node):
    """A cylinder along its local z axis, centred on its pose."""

    radius: NumOrExpr = 0.5
    """Radius in metres."""
    height: NumOrExpr = 1.0
    """Length along local z."""


class ArrowEl(_Node):
    """An arrow."""

    start: VecOrExpr = Field(default_factory=lambda: [0.0, 0.0, 0.0])
    """Tail point [x, y, z]."""
    vector: VecOrExpr
    """The arrow, tail to head."""
    width: NumOrExpr = 0.02
    """Shaft diameter in metres."""


class LineEl(_Node):
    """A polyline."""

    points: MatOrExpr
    """N x 3 points."""
    width: NumOrExpr = 2.0
    """Line width in pixels."""


class TrailEl(_Node):
    """A trace of a moving point."""

    point: VecOrExpr
    """The 3-vector traced over time."""
    max_points: int = Field(default=1000, ge=2, le=1_000_000)
    """Most points kept."""
    width: NumOrExpr = 2.0
    """Line width in pixels."""


class PointsEl(_Node):
    """A point cloud."""

    points: MatOrExpr
    """N x 3 points."""
    size: NumOrExpr = 0.02
    """Point size in metres."""


class FrameEl(_Node):
    """Coordinate axes."""

    size: NumOrExpr = 0.2
    """Axis length."""


class GridEl(_Node):
    """A grid on the xy plane."""

    size: NumOrExpr = 2.0
    """Width of the grid."""
    cell: NumOrExpr = 0.1
    """Cell size."""


class Text3dEl(_Node):
    """A text label in the scene."""

    text: str
    """The text ({expr} interpolated)."""


class MeshEl(_Node):
    """A mesh from a file (OBJ, STL, PLY, GLB/glTF, OFF or VRML97 .wrl)."""

    file: str
    """Path relative to the spec."""
    scale: NumOrExpr = 1.0
    """Uniform scale."""


class GroupEl(_Node):
    """A group whose pose applies to its children."""

    children: list[Any] = Field(default_factory=list)
    """3D elements inside."""


class RobotEl(_Node):
    """An arm drawn from its kinematic model."""

    model: Expr
    """Expression giving a runtime Robot."""
    q: VecOrExpr
    """Joint vector."""
    base: MatOrExpr | None = None
    """Optional 4x4 base pose (e.g. a link frame of another arm)."""
    meshes: list[str] | None = None
    """One mesh file per link, each in that link's frame."""
    show_frames: bool = False
    """Draw each link's frame."""


class CameraEl(_Node):
    """A virtual camera (z forward, x right, y down)."""

    fov: NumOrExpr = 60.0
    """Vertical field of view in degrees."""
    intrinsics: MatOrExpr | None = None
    """3x3 intrinsic matrix (instead of fov)."""
    resolution: list[int] = Field(default_factory=lambda: [320, 240])
    """Image size [width, height] in pixels."""


class GizmoEl(_Node):
    """A draggable transform handle bound to a 4x4 pose variable."""

    bind: str
    """The 4x4 pose variable."""
    scale: NumOrExpr = 0.3
    """Handle size."""
    on_change: Code | None = None
    """Code run after a drag (then the fixed relations)."""


SCENE_ELEMENT_MODELS: dict[str, type[Strict]] = {
    "box": BoxEl,
    "sphere": SphereEl,
    "cylinder": CylinderEl,
    "arrow": ArrowEl,
    "line": LineEl,
    "trail": TrailEl,
    "points": PointsEl,
    "frame": FrameEl,
    "grid": GridEl,
    "text3d": Text3dEl,
    "mesh": MeshEl,
    "group": GroupEl,
    "robot": RobotEl,
    "camera": CameraEl,
    "gizmo": GizmoEl,
}

VIEW_KINDS = tuple(GUI_ELEMENT_MODELS) + ("scene",)


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
