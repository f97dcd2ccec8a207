"""The scene graph of a simulation: named nodes with poses, shapes and colours.

The runtime owns the world; the viser view only mirrors it, and the virtual camera
renders it on the server. Every node keeps ``T_parent_local``, the (4, 4) pose of its
local frame in its parent's frame (the world for root nodes); units are metres, z up.

Each node counts its changes in ``rev`` (any property) and ``geom_rev`` (its shape), so a
view can send only what changed since it last looked.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Iterator, Sequence
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.robotics.transforms import trinv
from ejsrl.world.colors import to_rgb
from ejsrl.world.kinds import KINDS

__all__ = [
    "Node",
    "Box",
    "Sphere",
    "Cylinder",
    "Arrow",
    "Line",
    "Trail",
    "Points",
    "Frame",
    "Grid",
    "Text3D",
    "MeshNode",
    "Group",
    "CameraNode",
    "GizmoNode",
    "Part",
    "World",
    "NODE_KINDS",
]

Array = NDArray[np.float64]


class Part:
    """One solid piece of a node's geometry in the node's local frame.

    ``vertices``: (V, 3) float64 in the part frame; ``faces``: (F, 3) int32 vertex indices
    (counter-clockwise seen from outside); ``rgb``: (3,) floats in [0, 1], or ``face_rgb``
    (F, 3) per face; ``T_node_part``: (4, 4) pose of the part in the node frame.
    """

    __slots__ = ("vertices", "faces", "rgb", "face_rgb", "T_node_part")

    def __init__(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        rgb: Sequence[float] | None = None,
        *,
        face_rgb: ArrayLike | None = None,
        T_node_part: ArrayLike | None = None,
    ) -> None:
        self.vertices = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
        self.faces = np.ascontiguousarray(faces, dtype=np.int32).reshape(-1, 3)
        self.rgb = None if rgb is None else np.asarray(rgb, dtype=np.float64).reshape(3)
        self.face_rgb = None if face_rgb is None else np.asarray(face_rgb, dtype=np.float64).reshape(-1, 3)
        self.T_node_part = None if T_node_part is None else np.asarray(T_node_part, dtype=np.float64)


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a_arr, b_arr = np.asarray(a), np.asarray(b)
        return a_arr.shape == b_arr.shape and bool(np.array_equal(a_arr, b_arr))
    return bool(a == b)


class Node:
    """Base of every scene node.

    ``name``: unique in its world; ``T_parent_local``: (4, 4); ``color``: RGB floats in [0, 1];
    ``opacity`` in [0, 1]; ``graspable``: a robot gripper may pick it up.
    """

    kind: ClassVar[str] = "node"
    #: the properties that change the node's shape (and so its triangles)
    GEOMETRY_PROPS: ClassVar[tuple[str, ...]] = ()
    #: default values of the node's own properties (for a declared kind: from its declaration
    #: in ejsrl.world.kinds, unless the class gives its own)
    DEFAULTS: ClassVar[dict[str, Any]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        decl = KINDS.get(cls.__dict__.get("kind", ""))
        if decl is not None and "DEFAULTS" not in cls.__dict__:
            cls.DEFAULTS = decl.node_defaults()

    def __init__(
        self,
        name: str,
        *,
        T_parent_local: ArrayLike | None = None,
        visible: bool = True,
        color: Any = "lightgray",
        opacity: float = 1.0,
        graspable: bool = False,
        **props: Any,
    ) -> None:
        self.name = name
        self.parent: Node | None = None
        self.children: list[Node] = []
        self.world: World | None = None
        self.T_parent_local = np.eye(4) if T_parent_local is None else np.array(T_parent_local, dtype=float)
        self.visible = bool(visible)
        self.color = to_rgb(color)
        self.opacity = float(opacity)
        self.graspable = bool(graspable)
        self.props: dict[str, Any] = dict(self.DEFAULTS)
        unknown = set(props) - set(self.DEFAULTS)
        if unknown:
            raise TypeError(f"{self.kind} has no properties {sorted(unknown)}")
        self.props.update(props)
        self.rev = 0
        self.geom_rev = 0
        self._parts: list[Part] | None = None

    # -- properties -------------------------------------------------------------------
    def __getattr__(self, key: str) -> Any:
        props = self.__dict__.get("props")
        if props is not None and key in props:
            return props[key]
        raise AttributeError(f"{type(self).__name__!s} has no attribute {key!r}")

    def set(self, **values: Any) -> bool:
        """Set properties (own ones, or ``visible``, ``color``, ``opacity``, ``T_parent_local``).

        Returns True if anything changed; bumps ``rev`` (and ``geom_rev`` for shape changes).
        """
        changed = False
        for key, value in values.items():
            if key == "T_parent_local":
                value = np.asarray(value, dtype=float)
                if not np.array_equal(value, self.T_parent_local):
                    self.T_parent_local = np.array(value)
                    changed = True
                continue
            if key == "color":
                value = to_rgb(value)
            elif key in ("visible", "graspable"):
                value = bool(value)
            elif key == "opacity":
                value = float(value)
            if key in ("color", "visible", "opacity", "graspable"):
                if getattr(self, key) != value:
                    setattr(self, key, value)
                    changed = True
                continue
            if key not in self.props:
                raise TypeError(f"{self.kind} has no property {key!r}")
            if not _same(self.props[key], value):
                self.props[key] = value
                changed = True
                if key in self.GEOMETRY_PROPS:
                    self.geom_rev += 1
                    self._parts = None
        if changed:
            self.rev += 1
        return changed

    # -- poses ------------------------------------------------------------------------
    def T_world(self) -> Array:
        """Pose (4, 4) of this node's frame in the world."""
        T = self.T_parent_local
        node = self.parent
        while node is not None:
            T = node.T_parent_local @ T
            node = node.parent
        return T

    # -- geometry ---------------------------------------------------------------------
    def parts(self) -> list[Part]:
        """Solid geometry in the node frame (empty for non-solid nodes); cached per shape."""
        if self._parts is None:
            self._parts = self._make_parts()
        return self._parts

    def _make_parts(self) -> list[Part]:
        return []

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}>"


def _trimesh_part(mesh: Any, rgb: Sequence[float] | None = None) -> Part:
    return Part(np.asarray(mesh.vertices), np.asarray(mesh.faces), rgb)


class Box(Node):
    """Axis-aligned box centred on the node frame; ``size`` = [x, y, z] edge lengths."""

    kind = "box"
    GEOMETRY_PROPS = ("size",)

    def _make_parts(self) -> list[Part]:
        sx, sy, sz = (float(v) for v in np.asarray(self.props["size"], dtype=float).reshape(3))
        v = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
        v *= (sx, sy, sz)
        f = np.array(
            [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
             [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
        )
        return [Part(v, f, None)]


class Sphere(Node):
    """Sphere of ``radius`` centred on the node frame."""

    kind = "sphere"
    GEOMETRY_PROPS = ("radius",)

    def _make_parts(self) -> list[Part]:
        import trimesh

        return [_trimesh_part(trimesh.creation.icosphere(subdivisions=2, radius=float(self.props["radius"])))]


class Cylinder(Node):
    """Cylinder of ``radius`` and ``height`` along the local z axis, centred on the frame."""

    kind = "cylinder"
    GEOMETRY_PROPS = ("radius", "height")

    def _make_parts(self) -> list[Part]:
        import trimesh

        m = trimesh.creation.cylinder(radius=float(self.props["radius"]), height=float(self.props["height"]), sections=24)
        return [_trimesh_part(m)]


class Arrow(Node):
    """Arrow from ``start`` along ``vector`` (both (3,), in the node frame).

    Its parts are a head (a cone ``min(0.3 * length, 6 * width)`` long) and a shaft of two
    overlapping cylinders of one fixed length ``h``, from the tail and from the head's base
    (``ejsrl.world._pieces``): while the shaft's length stays within ``[h, 2h]`` and the head's
    does not change (arrows at least 20 widths long) a change of the arrow moves its parts but not
    their vertices, so the browser's view moves it by poses, in the frame of the bodies beside it.
    A translucent arrow's shaft is one cylinder (overlapping pieces would show darker).
    """

    kind = "arrow"
    GEOMETRY_PROPS = ("start", "vector", "width")

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name, **kwargs)
        #: the shaft pieces' length (metres; 0: none yet), the shaft lengths seen, and whether
        #: the parts were made for a translucent arrow
        self._piece = 0.0
        self._seen = (math.inf, 0.0)
        self._made_translucent = False

    def parts(self) -> list[Part]:
        if self._parts is not None and self._made_translucent != (self.opacity < 1.0):
            self._parts = None
        return super().parts()

    def _make_parts(self) -> list[Part]:
        import trimesh

        from ejsrl.world._pieces import PIECE_RATIO, refit_piece

        start = np.asarray(self.props["start"], dtype=float).reshape(3)
        vec = np.asarray(self.props["vector"], dtype=float).reshape(3)
        length = float(np.linalg.norm(vec))
        self._made_translucent = self.opacity < 1.0
        if not (length >= 1e-12 and math.isfinite(length)):
            return []
        r = float(self.props["width"]) / 2
        head = min(0.3 * length, 6 * r)
        shaft = length - head
        z = vec / length
        helper = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
        x = np.cross(helper, z)
        x /= np.linalg.norm(x)
        R = np.column_stack([x, np.cross(z, x), z])

        def at(along: float) -> Array:
            T = np.eye(4)
            T[:3, :3] = R
            T[:3, 3] = start + along * z
            return T

        cone = trimesh.creation.cone(radius=2.5 * r, height=head, sections=12)
        parts = [Part(cone.vertices, cone.faces, None, T_node_part=at(shaft))]
        if self._made_translucent:
            pieces = [(shaft, 0.0)]
        else:
            new, self._seen = refit_piece(self._piece, shaft, self._seen)
            if new is not None:
                self._piece = new if self._piece > 0.0 else shaft / PIECE_RATIO
            pieces = [(self._piece, 0.0), (self._piece, shaft - self._piece)]
        for h, along in pieces:
            cyl = trimesh.creation.cylinder(radius=r, height=h, sections=12)
            cyl.apply_translation((0, 0, h / 2))
            parts.append(Part(cyl.vertices, cyl.faces, None, T_node_part=at(along)))
        return parts


class Line(Node):
    """Polyline through ``points`` (N, 3); ``width`` in pixels. Not solid."""

    kind = "line"


class Trail(Node):
    """A polyline that grows with ``point`` over time, keeping ``max_points``."""

    kind = "trail"

    def push(self, point: ArrayLike) -> None:
        """Append a point (3,), dropping the oldest beyond ``max_points``."""
        p = np.asarray(point, dtype=float).reshape(1, 3)
        pts = self.props["points"]
        if len(pts) and np.array_equal(pts[-1], p[0]):
            return
        pts = np.concatenate([pts, p])[-int(self.props["max_points"]) :]
        self.props["points"] = pts
        self.rev += 1

    def clear(self) -> None:
        """Forget every point (on reset)."""
        if len(self.props["points"]):
            self.props["points"] = np.zeros((0, 3))
            self.rev += 1


class Points(Node):
    """Point cloud ``points`` (N, 3) with a point ``size`` in metres. Not solid."""

    kind = "points"


class Frame(Node):
    """Coordinate axes (x red, y green, z blue) of length ``size``."""

    kind = "frame"


class Grid(Node):
    """Square grid on the local xy plane: ``size`` wide, cells of ``cell``."""

    kind = "grid"


class Text3D(Node):
    """A text label anchored at the node frame."""

    kind = "text3d"


class MeshNode(Node):
    """A triangle mesh: ``parts`` given directly (already loaded), scaled by ``scale``."""

    kind = "mesh"
    GEOMETRY_PROPS = ("mesh_parts", "scale")

    def _make_parts(self) -> list[Part]:
        scale = np.asarray(self.props["scale"], dtype=float)
        if np.all(scale == 1.0):
            return list(self.props["mesh_parts"])
        out = []
        for p in self.props["mesh_parts"]:
            scaled = copy.copy(p)  # keeps a MeshPart's opacity and name
            scaled.vertices = p.vertices * scale
            if p.T_node_part is not None:
                scaled.T_node_part = p.T_node_part.copy()
                scaled.T_node_part[:3, 3] *= scale
            out.append(scaled)
        return out


class Group(Node):
    """A node with no geometry whose pose applies to its children."""

    kind = "group"


class CameraNode(Node):
    """A virtual camera: frame z forward, x right, y down.

    ``fov``: vertical field of view in degrees (used when ``intrinsics`` is None);
    ``intrinsics``: (3, 3) matrix K; ``resolution``: (width, height) in pixels.
    """

    kind = "camera"


class GizmoNode(Node):
    """A draggable transform handle; its pose is the bound 4x4 variable."""

    kind = "gizmo"


def _node_classes() -> dict[str, type[Node]]:
    """A node class for every declared kind whose node this module makes: the class above
    that names the kind, or a plain ``Node`` holding the declared properties."""
    defined = {cls.kind: cls for cls in Node.__subclasses__() if cls.__module__ == __name__}
    out: dict[str, type[Node]] = {}
    for name, decl in KINDS.items():
        if decl.node_module is None:
            out[name] = defined.get(name) or type(name.capitalize(), (Node,), {"kind": name, "__doc__": decl.doc, "__module__": __name__})
    return out


#: kind -> node class, for every declared kind except those whose node is made elsewhere
#: (``Kind.node_module``: a robot's node is ``ejsrl.world.robot_node.RobotNode``)
NODE_KINDS: dict[str, type[Node]] = _node_classes()


class World:
    """A tree of named nodes.

    ``add`` registers a node (unique name) under a parent or at the root; ``triangles``
    gives all visible solid geometry in world coordinates for the renderer.
    """

    def __init__(self) -> None:
        self.nodes: dict[str, Node] = {}
        self.roots: list[Node] = []
        self._tri_cache: dict[str, tuple[tuple[int, int, bytes], NDArray[np.float64], NDArray[np.float64]]] = {}

    # -- building -----------------------------------------------------------------------
    def add(self, node: Node, parent: Node | str | None = None) -> Node:
        """Add ``node`` (its name must be new) under ``parent`` (a node, a name, or the root)."""
        if node.name in self.nodes:
            raise ValueError(f"the world already has an object named {node.name!r}")
        parent_node = self[parent] if isinstance(parent, str) else parent
        node.world = self
        node.parent = parent_node
        if parent_node is None:
            self.roots.append(node)
        else:
            parent_node.children.append(node)
        self.nodes[node.name] = node
        return node

    def remove(self, name: str) -> None:
        """Take the named object and everything below it out of the world."""
        node = self[name]
        if node.parent is None:
            if node in self.roots:
                self.roots.remove(node)
        elif node in node.parent.children:
            node.parent.children.remove(node)
        stack = [node]
        while stack:
            n = stack.pop()
            stack.extend(n.children)
            self.nodes.pop(n.name, None)
            self._tri_cache.pop(n.name, None)
            n.world = None
        node.parent = None

    def unique_name(self, base: str) -> str:
        """A name not yet used, ``base`` or ``base_2``, ``base_3``, ..."""
        if base not in self.nodes:
            return base
        i = 2
        while f"{base}_{i}" in self.nodes:
            i += 1
        return f"{base}_{i}"

    def __getitem__(self, name: str) -> Node:
        try:
            return self.nodes[name]
        except KeyError:
            import difflib

            close = difflib.get_close_matches(name, list(self.nodes), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise KeyError(f"no object named {name!r} in the scene{hint}") from None

    def __contains__(self, name: object) -> bool:
        return name in self.nodes

    def walk(self) -> Iterator[Node]:
        """All nodes, parents before children."""
        stack = list(reversed(self.roots))
        while stack:
            node = stack.pop()
            yield node
            stack.extend(reversed(node.children))

    # -- poses --------------------------------------------------------------------------
    def T_world(self, name: str) -> Array:
        """Pose (4, 4) of the named object in the world."""
        return self[name].T_world()

    def set_world_pose(self, name: str, T_world_obj: ArrayLike) -> None:
        """Place the named object so its world pose is ``T_world_obj`` (4, 4)."""
        node = self[name]
        T = np.asarray(T_world_obj, dtype=float)
        if node.parent is not None:
            T = trinv(node.parent.T_world()) @ T
        node.set(T_parent_local=T)

    def reparent(self, name: str, new_parent: Node | str | None, *, keep_world_pose: bool = True) -> None:
        """Move the named object under ``new_parent`` (None: the root), by default in place."""
        node = self[name]
        parent = self[new_parent] if isinstance(new_parent, str) else new_parent
        p = parent
        while p is not None:
            if p is node:
                raise ValueError(f"cannot put {name!r} under its own descendant")
            p = p.parent
        T_world = node.T_world()
        if node.parent is None:
            self.roots.remove(node)
        else:
            node.parent.children.remove(node)
        node.parent = parent
        if parent is None:
            self.roots.append(node)
        else:
            parent.children.append(node)
        if keep_world_pose:
            T_local = T_world if parent is None else trinv(parent.T_world()) @ T_world
            node.T_parent_local = T_local
        node.rev += 1

    # -- geometry for the renderer --------------------------------------------------------
    def is_visible(self, node: Node) -> bool:
        """A node shows only if it and all its ancestors are visible."""
        n: Node | None = node
        while n is not None:
            if not n.visible:
                return False
            n = n.parent
        return True

    def triangles(self, exclude: Sequence[str] = ()) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Every visible solid triangle in world coordinates.

        Returns ``tris`` (F, 3, 3): the three vertices of each face, world frame, metres;
        and ``rgb`` (F, 3): its colour in [0, 1]. Cached per node while its pose and shape
        do not change.
        """
        tris_all = []
        rgb_all = []
        skip = set(exclude)
        for node in self.walk():
            if node.name in skip or not self.is_visible(node) or node.opacity <= 0.0:
                continue
            parts = node.parts()
            if not parts:
                continue
            T = node.T_world()
            key = (node.geom_rev, id(parts), T.tobytes() + np.asarray(node.color).tobytes())
            cached = self._tri_cache.get(node.name)
            if cached is None or cached[0] != key:
                tris, rgb = _world_triangles(parts, T, node.color)
                self._tri_cache[node.name] = (key, tris, rgb)
            else:
                tris, rgb = cached[1], cached[2]
            tris_all.append(tris)
            rgb_all.append(rgb)
        if not tris_all:
            return np.zeros((0, 3, 3)), np.zeros((0, 3))
        return np.concatenate(tris_all), np.concatenate(rgb_all)


def _world_triangles(parts: list[Part], T_world_node: Array, color: Sequence[float]) -> tuple[Array, Array]:
    tris = []
    rgbs = []
    for part in parts:
        T = T_world_node if part.T_node_part is None else T_world_node @ part.T_node_part
        v = part.vertices @ T[:3, :3].T + T[:3, 3]
        tris.append(v[part.faces])
        if part.face_rgb is not None:
            rgbs.append(part.face_rgb)
        else:
            rgb = np.asarray(color if part.rgb is None else part.rgb, dtype=float)
            rgbs.append(np.broadcast_to(rgb, (len(part.faces), 3)))
    return np.concatenate(tris), np.concatenate(rgbs)
