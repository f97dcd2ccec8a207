"""The 3D element kinds of the language, each declared once.

Every 3D element kind (``box``, ``sphere``, ..., ``gizmo``) is one :class:`Kind`: its
documentation, its own typed properties (:class:`Prop`: name, property type, default,
doc), how the browser view draws it, and what its world node holds besides. Everything
else is derived from :data:`KINDS`:

- the pydantic models of the spec language (``ejsgen.spec.SCENE_ELEMENT_MODELS``), and so
  the JSON Schema and the reference tables of specs/language.md;
- the property types the generator compiles (``ejsgen._view_compile``);
- the default properties of the world's nodes (``ejsrl.world.scene``: ``Node.DEFAULTS``,
  and a plain node class for a kind without geometry of its own);
- the drawing style the browser mirror dispatches on (``ejsrl.view._scene_mirror``).

A new 3D element kind is one more entry here (plus a ``Node`` subclass in
``ejsrl.world.scene`` if it has solid geometry of its own, drawn in the ``mesh`` style).

Property types (``Prop.type``): ``num`` a number or expression; ``vec3`` three of them
(or an expression); ``vec`` any number of them; ``mat`` an N x 3 matrix of points;
``mat4`` / ``mat3`` a 4x4 / 3x3 matrix; ``text`` text with ``{expr}`` interpolated;
``file`` a file relative to the spec, ``files`` a list of them; ``expr`` an expression;
``int`` an integer; ``source`` a camera's real image source (an index, a URL or a file: ``ejsgen._view_compile_source``); ``bool`` true or false; ``flag`` true, false or an expression;
``color`` a colour; ``ints2`` two positive integers; ``name`` an object name; ``bind`` a
bound variable; ``code`` Python code; ``children`` nested 3D elements.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["REQUIRED", "Prop", "Kind", "COMMON", "KINDS", "PROP_TYPES", "DRAW_STYLES"]


class _Required:
    """The default of a property the spec must give."""

    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Required()

#: every property type (see the module's docstring)
PROP_TYPES = frozenset(
    {"num", "vec3", "vec", "mat", "mat4", "mat3", "text", "file", "files", "expr", "int", "bool", "flag", "color", "ints2", "name", "bind", "code", "children", "source"}
)
#: the property types that are not values of the element's props (handled by the element itself)
_NOT_VALUE_TYPES = frozenset({"bind", "code", "children"})

#: how the browser view draws a kind: a viser primitive, or ``mesh`` (the node's ``parts()``),
#: ``gizmo`` (transform controls), ``none`` (nothing but its frame)
DRAW_STYLES = ("box", "sphere", "polyline", "points", "frame", "grid", "label", "camera", "mesh", "gizmo", "none")


@dataclass(frozen=True)
class Prop:
    """One property of a 3D element kind.

    ``type``: a property type (see the module's docstring); ``default``: its value when the
    spec leaves it out (``REQUIRED``: the spec must give it; ``None``: absent);
    ``node_default``: the world node's value before the model gives one, when it differs
    from ``default`` (a required property); ``node``: False if the world node does not
    hold it (a trail's ``point`` is pushed, not held); ``ge``/``le``: bounds of an ``int``.
    """

    name: str
    type: str
    default: Any
    doc: str
    node_default: Any = REQUIRED
    node: bool = True
    ge: int | None = None
    le: int | None = None

    def __post_init__(self) -> None:
        if self.type not in PROP_TYPES:
            raise ValueError(f"property {self.name!r}: unknown property type {self.type!r} (types: {', '.join(sorted(PROP_TYPES))})")

    @property
    def required(self) -> bool:
        """The spec must give this property."""
        return self.default is REQUIRED

    @property
    def is_value(self) -> bool:
        """A value of the element's ``props`` in the generated app (not a bind, code or children)."""
        return self.type not in _NOT_VALUE_TYPES

    @property
    def in_node(self) -> bool:
        """The world node holds this property."""
        return self.node and self.is_value

    def initial(self) -> Any:
        """The world node's value before the model gives one."""
        return self.default if self.node_default is REQUIRED else self.node_default


@dataclass(frozen=True)
class Kind:
    """One 3D element kind.

    ``doc``: what it is (first line in the reference); ``props``: its own properties, in
    order; ``draw``: how the browser view draws it (one of ``DRAW_STYLES``); ``flat``: a
    ``mesh``-drawn kind shaded flat; ``two_sided``: its mesh faces show from both sides
    (meshes from files, whose winding is not known); ``node_extra``: properties its world node holds that
    the spec does not give (state, or values set from code); ``node_module``: the module
    that defines its node class, when not ``ejsrl.world.scene``.
    """

    name: str
    doc: str
    props: tuple[Prop, ...]
    draw: str = "mesh"
    flat: bool = False
    two_sided: bool = False
    node_extra: dict[str, Any] = field(default_factory=dict)
    node_module: str | None = None

    def __post_init__(self) -> None:
        if self.draw not in DRAW_STYLES:
            raise ValueError(f"kind {self.name!r}: unknown drawing style {self.draw!r} (styles: {', '.join(DRAW_STYLES)})")

    def prop(self, name: str) -> Prop:
        """The own property called ``name``."""
        for p in self.props:
            if p.name == name:
                return p
        raise KeyError(f"{self.name} has no property {name!r}")

    def node_defaults(self) -> dict[str, Any]:
        """The world node's properties and their values before the model gives any."""
        out = {p.name: p.initial() for p in self.props if p.in_node}
        out.update(self.node_extra)
        return out


def _no_points() -> Any:
    return np.zeros((0, 3))


#: the properties every 3D element has, in order
COMMON: tuple[Prop, ...] = (
    Prop("name", "name", None, "Name by which code refers to the object (unique in the scene)."),
    Prop("visible", "flag", True, "Shown or hidden."),
    Prop("color", "color", None, "CSS name, '#rrggbb', or an expression giving an RGB triple (0-1 floats)."),
    Prop("opacity", "num", 1.0, "0 transparent to 1 opaque."),
    Prop("graspable", "bool", False, "A robot gripper may pick it up."),
    Prop("position", "vec3", None, "[x, y, z] in metres (in the parent group's frame)."),
    Prop("rotation", "vec3", None, "[roll, pitch, yaw] in radians (ZYX: Rz(yaw) Ry(pitch) Rx(roll))."),
    Prop("transform", "mat4", None, "A 4x4 homogeneous pose (instead of position/rotation)."),
)

#: the virtual camera's texture of a solid element (the browser's 3D view draws a marker too, ejsrl.view._marker_face; a checker plain)
_TEXTURE: tuple[Prop, ...] = (
    Prop("texture", "text", None, "checker: a checkerboard on each face, as the virtual camera sees it (capture); "
         "or a fiducial marker '<dictionary>:<id>' (e.g. 'aruco_4x4_50:7', 'apriltag_36h11:0') on the faces along +z."),
    Prop("texture_size", "num", None, "The checker's squares, or the marker's side, metres along the element's own axes (default 0.05)."),
)

_KINDS: tuple[Kind, ...] = (
    Kind("box", "A box centred on its pose.", (
        Prop("size", "vec3", (1.0, 1.0, 1.0), "Edge lengths [x, y, z]."),
        *_TEXTURE,
    ), draw="box", flat=True),
    Kind("sphere", "A sphere.", (
        Prop("radius", "num", 0.5, "Radius in metres."),
        *_TEXTURE,
    ), draw="sphere"),
    Kind("cylinder", "A cylinder along its local z axis, centred on its pose.", (
        Prop("radius", "num", 0.5, "Radius in metres."),
        Prop("height", "num", 1.0, "Length along local z."),
        *_TEXTURE,
    ), flat=True),
    Kind("arrow", "An arrow.", (
        Prop("start", "vec3", (0.0, 0.0, 0.0), "Tail point [x, y, z]."),
        Prop("vector", "vec3", REQUIRED, "The arrow, tail to head.", node_default=(1.0, 0.0, 0.0)),
        Prop("width", "num", 0.02, "Shaft diameter in metres."),
    ), flat=True),
    Kind("line", "A polyline.", (
        Prop("points", "mat", REQUIRED, "N x 3 points.", node_default=_no_points()),
        Prop("width", "num", 2.0, "Line width in pixels."),
    ), draw="polyline"),
    Kind("trail", "A trace of a moving point.", (
        Prop("point", "vec3", REQUIRED, "The 3-vector traced over time.", node=False),
        Prop("max_points", "int", 1000, "Most points kept.", ge=2, le=1_000_000),
        Prop("width", "num", 2.0, "Line width in pixels."),
    ), draw="polyline", node_extra={"points": _no_points()}),
    Kind("points", "A point cloud.", (
        Prop("points", "mat", REQUIRED, "N x 3 points.", node_default=_no_points()),
        Prop("size", "num", 0.02, "Point size in metres."),
    ), draw="points"),
    Kind("frame", "Coordinate axes.", (
        Prop("size", "num", 0.2, "Axis length."),
    ), draw="frame"),
    Kind("grid", "A grid on the xy plane.", (
        Prop("size", "num", 2.0, "Width of the grid."),
        Prop("cell", "num", 0.1, "Cell size."),
    ), draw="grid"),
    Kind("text3d", "A text label in the scene.", (
        Prop("text", "text", REQUIRED, "The text ({expr} interpolated).", node_default=""),
    ), draw="label"),
    Kind("mesh", "A mesh from a file (OBJ, STL, PLY, GLB/glTF, OFF or VRML97 .wrl).", (
        Prop("file", "file", REQUIRED, "Path relative to the spec.", node_default=""),
        Prop("scale", "num", 1.0, "Uniform scale."),
        *_TEXTURE,
    ), two_sided=True, node_extra={"mesh_parts": ()}),
    Kind("group", "A group whose pose applies to its children.", (
        Prop("children", "children", (), "3D elements inside."),
    ), draw="none"),
    Kind("robot", "An arm drawn from its kinematic model.", (
        Prop("model", "expr", REQUIRED, "Expression giving a runtime Robot."),
        Prop("q", "vec", REQUIRED, "Joint vector."),
        Prop("base", "mat4", None, "Optional 4x4 base pose (e.g. a link frame of another arm)."),
        Prop("meshes", "files", None, "One mesh file per link, each in that link's frame."),
        Prop("show_frames", "bool", False, "Draw each link's frame."),
    ), node_module="ejsrl.world.robot_node"),
    Kind("camera", "A virtual camera (z forward, x right, y down).", (
        Prop("fov", "num", 60.0, "Vertical field of view in degrees."),
        Prop("intrinsics", "mat3", None, "3x3 intrinsic matrix (instead of fov)."),
        Prop("resolution", "ints2", (320, 240), "Image size [width, height] in pixels."),
        Prop("antialias", "int", None, "Supersampling: each pixel is the mean of antialias x antialias samples (1 or left out: off).", ge=1, le=8),
        Prop("shading", "text", None, "flat (left out: one shade per face) or smooth (normals interpolated: curved surfaces look round)."),
        Prop("distortion", "vec", None, "Lens distortion [k1, k2, p1, p2, k3], OpenCV's order, applied by the camera's own model."),
        Prop("blur", "num", None, "Defocus blur: a Gaussian of this standard deviation in pixels (0 or left out: off)."),
        Prop("noise", "num", None, "Gaussian sensor noise: standard deviation in grey levels, 0-255 (0 or left out: off)."),
        Prop("source", "source", None, "A real image source instead of the rendered scene: a camera index (`0`: the camera of "
             "the machine that runs the app), a stream URL (`rtsp://...`, `http://...`), a video file, an image, a folder of "
             "images or a glob pattern (`\"frames/*.png\"`), relative to the spec (copied into the app). `capture(name)` then "
             "gives its frames, resized to `resolution`, through the same pipeline: a file's frame at the simulation's time "
             "(looped), a camera's newest. Each session (browser tab) reads its own. A camera that is missing pauses the "
             "lab with a message saying so."),
    ), draw="camera", node_extra={"near": 0.01, "far": 100.0}),
    Kind("gizmo", "A draggable transform handle bound to a 4x4 pose variable.", (
        Prop("bind", "bind", REQUIRED, "The 4x4 pose variable."),
        Prop("scale", "num", 0.3, "Handle size."),
        Prop("on_change", "code", None, "Code run after a drag (then the fixed relations)."),
    ), draw="gizmo"),
    Kind("view", "The 3D view's camera (not drawn): where it looks from and at, which way is up, how wide it sees.\n\n"
         "At most one per scene; every tab of the simulation (and a tab reloaded later) is shown it. Left out, "
         "`position` stands back along the `preset`'s direction (default `iso`) just far enough to frame the "
         "scene. Code changes it with `set_view()`; the panel's Restore view button puts it back where the spec "
         "has it. Between those the user turns and zooms the view freely.", (
        Prop("target", "vec3", None, "The point looked at, [x, y, z] in metres (left out: the followed object, "
             "else the centre of what the scene shows)."),
        Prop("up", "vec3", None, "The direction shown upwards on screen (left out: the preset's, else [0, 0, 1])."),
        Prop("fov", "num", None, "Vertical field of view in degrees, 1 to 170 (left out: 75)."),
        Prop("preset", "text", None, "A direction to look from, square-on to a plane: front (from -y: the x-z plane, "
             "z up; alias xz), back (from +y), right (from +x: the y-z plane; alias yz), left (from -x), top (from +z: "
             "the x-y plane, y up; alias xy), bottom (from -z), iso (from [1, -1, 0.75], the default). Not with "
             "`position`."),
        Prop("follow", "name", None, "A scene object (or a robot's link, `arm.link3`) the camera tracks every frame: "
             "the target is its position."),
        Prop("follow_offset", "bool", False, "With `follow`: the camera moves along with the object, keeping its "
             "offset from it (false: it stays where it is and turns to watch the object)."),
    ), draw="none", node_extra={"commanded": None}),
)

#: mobile robots (issue #27): drawn on the plane z = 0 of their frame; nodes in ejsrl.mobile._nodes.
#: Their keys are the drawing panel's (ejsgen._spec2d_mobile, whose rules compile them in both): one element body serves both
_MOBILE = "ejsrl.mobile._nodes"
_MOBILE_KINDS: tuple[Kind, ...] = (
    Kind("vehicle", "A mobile robot at a pose [x, y, theta] on the plane: a prism over its footprint (a triangle pointing along its heading by default).", (
        Prop("pose", "vec", REQUIRED, "[x, y, theta] (m, m, rad), or an expression giving them (a vehicle's state).", node_default=(0.0, 0.0, 0.0)),
        Prop("length", "num", 1.0, "Length of the triangle from tail to nose, metres."),
        Prop("breadth", "num", None, "Width of the triangle, metres (default half the length)."),
        Prop("height", "num", 0.3, "Height of the prism, metres."),
        Prop("footprint", "mat", None, "A convex outline N x 2 in the vehicle's frame (x forward), metres, instead of the triangle."),
    ), flat=True, node_module=_MOBILE),
    Kind("laser", "A laser (range) scan: a ray from the sensor's pose to the end of each beam.", (
        Prop("pose", "vec", REQUIRED, "The sensor's pose [x, y, theta] (m, m, rad).", node_default=(0.0, 0.0, 0.0)),
        Prop("ranges", "vec", REQUIRED, "The ranges (n,) in metres, one per beam (e.g. scanner.scan(x)).", node_default=None),
        Prop("angles", "vec", None, "Each beam's angle from the heading (n,), radians (default: evenly over fov)."),
        Prop("fov", "num", float(np.pi), "Field of view in radians, centred on the heading (without angles)."),
        Prop("z", "num", 0.05, "Height of the rays above the plane, metres."),
        Prop("width", "num", 1.0, "Line width in pixels."),
    ), draw="polyline", node_extra={"points": _no_points()}, node_module=_MOBILE),
    Kind("occupancy", "An occupancy grid: its occupied cells as blocks on the plane.", (
        Prop("grid", "expr", REQUIRED, "An ejsrl.mobile BinaryOccupancyGrid or OccupancyGrid, or an H x W array (row 0 at the lowest y; cells >= 0.5 occupied).", node_default=None),
        Prop("cellsize", "num", 1.0, "Cell side in metres (for an array)."),
        Prop("origin", "vec", (0.0, 0.0), "The centre [x, y] of cell [0, 0], metres (for an array)."),
        Prop("height", "num", 0.5, "Height of the blocks, metres."),
    ), flat=True, node_module=_MOBILE),
    Kind("path", "A planned path on the plane: a line through N x 2 points or N x 3 poses.", (
        Prop("points", "mat", REQUIRED, "The way points, N x 2 (or N x 3 poses: x and y drawn), metres.", node_default=_no_points()),
        Prop("z", "num", 0.02, "Height above the plane, metres."),
        Prop("width", "num", 3.0, "Line width in pixels."),
    ), draw="polyline", node_module=_MOBILE),
    Kind("ellipse", "A covariance ellipse on the plane: where a 2-D Gaussian about position holds confidence of its probability.", (
        Prop("position", "vec", REQUIRED, "Its centre [x, y], metres (the estimate): as in the drawing panel, not a placement "
             "of the element (`transform` or a group places its plane).", node_default=(0.0, 0.0)),
        Prop("covariance", "mat", REQUIRED, "The covariance, 2 x 2 (m²) or larger (its top-left 2 x 2).", node_default=None),
        Prop("confidence", "num", 0.95, "The probability it holds, between 0 and 1."),
        Prop("scale", "num", 1.0, "Drawn this many times larger."),
        Prop("z", "num", 0.02, "Height above the plane, metres."),
        Prop("width", "num", 2.0, "Line width in pixels."),
    ), draw="polyline", node_extra={"points": _no_points()}, node_module=_MOBILE),
    Kind("particles", "A particle filter's particles: a point at each row of an N x 2 (positions) or N x 3 (poses) array.", (
        Prop("points", "mat", REQUIRED, "The particles, N x 2 or N x 3 (x and y drawn), metres.", node_default=_no_points()),
        Prop("z", "num", 0.02, "Height above the plane, metres."),
        Prop("size", "num", 0.05, "Point size in metres."),
    ), draw="points", node_module=_MOBILE),
)

#: every 3D element kind by name, in the order of the reference
KINDS: dict[str, Kind] = {k.name: k for k in _KINDS + _MOBILE_KINDS}
