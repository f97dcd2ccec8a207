"""Mirror an ``ejsrl.world.World`` into a viser scene, sending only what changed.

Every world node becomes one viser node named ``/ejs/<name>`` placed at the node's
*world* pose (flat names, so reparenting in the world, e.g. a gripper picking up a part,
never needs a rebuild). Its geometry hangs below it as ``/ejs/<name>/g<i>`` children in
the node frame. Each frame :meth:`SceneMirror.sync` compares, per node:

- the world pose (4, 4) with the last one sent: a changed pose sends ``position`` and
  ``wxyz`` (quaternion w, x, y, z) of the node handle only;
- ``geom_rev``: a changed shape updates primitive sizes in place or rebuilds the geometry;
- ``rev``: any other change (colour, opacity, points of a line, text) updates those props;
- the visibility of the node and its ancestors.

Lines are moved by poses wherever their shape allows, so that they are drawn in the same
browser frame as the solids beside them (``ejsrl.view._lines``).

Everything is sent inside one ``server.atomic()`` block by the caller.
Gizmo nodes become transform controls; a drag calls ``on_gizmo(name, T_world (4, 4))``.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ejsrl.robotics.transforms import q2r, r2q
from ejsrl.view._lines import LineDraw, PointsDraw
from ejsrl.view._marker_face import add_marker_face, marker_face_key
from ejsrl.view._wire import set_position, set_wxyz
from ejsrl.world.kinds import KINDS

__all__ = ["SceneMirror", "ROOT"]

#: the viser scene path under which every world node is placed
ROOT = "/ejs"

GizmoCallback = Callable[[str, np.ndarray], None]


def _rgb255(rgb: Any) -> tuple[int, int, int]:
    key = rgb if isinstance(rgb, tuple) else None
    if key is not None and key in _RGB255:
        return _RGB255[key]
    c = np.clip(np.asarray(rgb, dtype=float).reshape(3) * 255.0 + 0.5, 0, 255).astype(int)
    out = (int(c[0]), int(c[1]), int(c[2]))
    if key is not None and len(_RGB255) < 4096:
        _RGB255[key] = out
    return out


#: colours seen (a node's colour is a tuple): most frames send the colour of the frame before
_RGB255: dict[tuple[Any, ...], tuple[int, int, int]] = {}


def _opacity(x: float) -> float | None:
    return None if x >= 1.0 else max(0.0, float(x))


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """``np.array_equal`` for two small float arrays of one shape, at a fraction of its cost."""
    return a.shape == b.shape and a.tolist() == b.tolist()


def _snapshot(node: Any) -> tuple:
    """A comparable record of the node's non-pose state (colour, opacity, own props)."""
    items = []
    for k, v in sorted(node.props.items()):
        if isinstance(v, np.ndarray):
            items.append((k, v.shape, v.tobytes()))
        elif isinstance(v, (list, tuple)) and v and not isinstance(v[0], (int, float, str)):
            items.append((k, id(v), len(v)))
        else:
            try:
                hash(v)
                items.append((k, v))
            except TypeError:
                items.append((k, repr(v)))
    return (tuple(node.color), node.opacity, tuple(items))


class _Mirror:
    """What has been sent for one world node."""

    __slots__ = ("kind", "style", "frame", "geoms", "T", "rev", "geom_rev", "visible", "state", "mesh_parts_rgb", "part_keys", "part_handles", "parts_ref", "line", "marker")

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self.style = _style(kind)
        self.frame: Any = None  # the node handle (a frame, or transform controls)
        self.geoms: list[Any] = []  # geometry handles below it
        self.T: np.ndarray | None = None
        self.rev = -1
        self.geom_rev = -1
        self.visible: bool | None = None
        self.state: tuple | None = None
        #: for meshes: per geometry handle, True if it takes the node colour
        self.mesh_parts_rgb: list[bool] = []
        #: for meshes: what identifies each part's shape, and its handles
        self.part_keys: list[tuple] | None = None
        self.part_handles: list[list[Any]] = []
        self.parts_ref: list[Any] = []  # keeps the keyed arrays alive, so their ids stay unique
        #: for lines, trails and point clouds: how they are drawn (ejsrl.view._lines)
        self.line: LineDraw | PointsDraw | None = None
        #: for solids with a marker texture: what its picture was made for, and its image handle
        self.marker: tuple[tuple, Any] | None = None


class SceneMirror:
    """Keeps a viser scene in step with a world.

    ``scene``: ``server.scene``; ``on_gizmo(name, T_world)``: called (from a viser thread)
    when the user drags a gizmo; ``clock()``: monotonic seconds, for how long a dragged
    gizmo is left to the user (the real clock by default). ``counters`` counts the updates sent, by kind, for tests
    and benchmarks.
    """

    def __init__(
        self, scene: Any, *, on_gizmo: GizmoCallback | None = None, clock: Callable[[], float] = time.monotonic
    ) -> None:
        self.scene = scene
        self.on_gizmo = on_gizmo
        self.clock = clock
        self._nodes: dict[str, _Mirror] = {}
        self._dragging: dict[str, float] = {}
        self._gizmo_lock = threading.Lock()
        self.counters: dict[str, int] = {"create": 0, "pose": 0, "geometry": 0, "props": 0, "visible": 0, "remove": 0, "part_poses": 0}

    # -- the per-frame entry point ------------------------------------------------------
    def sync(self, world: Any) -> None:
        """Send what changed in ``world`` since the last call (caller holds the model lock)."""
        seen: set[str] = set()
        T_of: dict[str, np.ndarray] = {}
        vis_of: dict[str, bool] = {}
        for node in world.walk():
            parent = node.parent
            if parent is None:
                T = node.T_parent_local
                vis = node.visible
            else:
                T = T_of[parent.name] @ node.T_parent_local
                vis = vis_of[parent.name] and node.visible
            T_of[node.name] = T
            vis_of[node.name] = vis
            seen.add(node.name)
            self._sync_node(node, T, vis)
        for name in [n for n in self._nodes if n not in seen]:
            self._remove(name)

    def clear(self) -> None:
        """Remove every mirrored node (the next ``sync`` rebuilds them)."""
        for name in list(self._nodes):
            self._remove(name)

    # -- one node -----------------------------------------------------------------------
    def _sync_node(self, node: Any, T: np.ndarray, visible: bool) -> None:
        m = self._nodes.get(node.name)
        if m is None or m.kind != node.kind:
            if m is not None:
                self._remove(node.name)
            m = self._create(node, T, visible)
            self._nodes[node.name] = m
            return
        if m.style == "gizmo" and self._is_dragging(node.name):
            m.T = None  # the user moves it; send the model's pose again once the drag is over
        elif m.T is None or not _same(m.T, T):
            # only the part that moved: a body that translates (a pendulum's bob) sends no rotation
            if m.T is None or not _same(m.T[:3, 3], T[:3, 3]):
                set_position(m.frame, T[:3, 3])
            if m.T is None or not _same(m.T[:3, :3], T[:3, :3]):
                set_wxyz(m.frame, r2q(T))
            self.counters["pose"] += 1
            m.T = np.array(T)
        if visible != m.visible:
            m.frame.visible = visible
            m.visible = visible
            self.counters["visible"] += 1
        if node.rev != m.rev:
            m.rev = node.rev
            state = _snapshot(node)
            if node.geom_rev != m.geom_rev:
                m.geom_rev = node.geom_rev
                m.state = state
                self._update_geometry(node, m)
            elif state != m.state:
                m.state = state
                self._update_props(node, m)
            self._sync_marker(node, m)

    def _path(self, name: str) -> str:
        return f"{ROOT}/{name}"

    def _create(self, node: Any, T: np.ndarray, visible: bool) -> _Mirror:
        m = _Mirror(node.kind)
        path = self._path(node.name)
        pos, wxyz = T[:3, 3], r2q(T)
        if m.style == "gizmo":
            m.frame = self.scene.add_transform_controls(
                path, scale=float(node.props.get("scale", 0.3)), position=pos, wxyz=wxyz, visible=visible
            )
            self._attach_gizmo(node.name, m.frame)
        else:
            m.frame = self.scene.add_frame(path, show_axes=False, position=pos, wxyz=wxyz, visible=visible)
        m.T = np.array(T)
        m.visible = visible
        m.rev = node.rev
        m.geom_rev = node.geom_rev
        m.state = _snapshot(node)
        self._build_geometry(node, m)
        self._sync_marker(node, m)
        self.counters["create"] += 1
        return m

    def _sync_marker(self, node: Any, m: _Mirror) -> None:
        """The picture of a marker texture on the node's +z face (ejsrl.view._marker_face), made
        again when what it shows changed (texture, size, height, colour), removed when it has none."""
        if m.style not in ("box", "sphere", "mesh") and m.marker is None:
            return
        key = marker_face_key(node, _rgb255(node.color)) if node.props.get("texture") else None
        if (m.marker[0] if m.marker is not None else None) == key:
            return
        if m.marker is not None:
            _safe_remove(m.marker[1])
        m.marker = None if key is None else (key, add_marker_face(self.scene, f"{self._path(node.name)}/marker", key))

    def _remove(self, name: str) -> None:
        m = self._nodes.pop(name, None)
        if m is None:
            return
        for h in m.geoms:
            _safe_remove(h)
        if m.marker is not None:
            _safe_remove(m.marker[1])
        _safe_remove(m.frame)
        self.counters["remove"] += 1

    # -- geometry -----------------------------------------------------------------------
    def _build_geometry(self, node: Any, m: _Mirror) -> None:
        """Create the geometry handles of ``node`` below its frame."""
        base = self._path(node.name)
        color = _rgb255(node.color)
        opacity = _opacity(node.opacity)
        m.geoms = []
        m.line = None
        m.mesh_parts_rgb = []
        _BUILDERS[_style(node.kind)](self, node, m, base, color, opacity)

    def _build_mesh(self, node: Any, m: _Mirror, base: str, color: tuple[int, int, int], opacity: float | None) -> None:
        """Any solid node: its ``parts()`` as meshes, one per part and colour.

        Each mesh is placed at its part's ``T_node_part``, so a node whose parts only move
        (a robot's links) is updated by poses alone.
        """
        try:
            parts = node.parts()
        except Exception:
            parts = []
        decl = KINDS.get(node.kind)
        flat = decl is not None and decl.flat
        side = "double" if decl is not None and decl.two_sided else "front"
        m.part_keys = []
        m.part_handles = []
        m.parts_ref = list(parts)
        i = 0
        for part in parts:
            v = np.asarray(part.vertices, dtype=np.float64)
            faces = np.asarray(part.faces, dtype=np.int64)
            T = np.eye(4) if part.T_node_part is None else np.asarray(part.T_node_part, dtype=float)
            m.part_keys.append(_part_key(part))
            handles: list[Any] = []
            m.part_handles.append(handles)
            if len(faces) == 0:
                continue
            if part.face_rgb is not None:
                groups = _faces_by_colour(np.asarray(part.face_rgb))
            else:
                groups = [(None, np.arange(len(faces)))]
            for rgb, idx in groups:
                verts, fcs = _compact(v, faces[idx])
                own = rgb if rgb is not None else part.rgb
                c = color if own is None else _rgb255(own)
                h = self.scene.add_mesh_simple(
                    f"{base}/g{i}",
                    vertices=verts.astype(np.float32),
                    faces=fcs.astype(np.uint32),
                    color=c,
                    opacity=opacity,
                    flat_shading=flat,
                    side=side,
                    position=T[:3, 3],
                    wxyz=r2q(T),
                )
                m.geoms.append(h)
                handles.append(h)
                m.mesh_parts_rgb.append(own is None)
                i += 1

    def _move_parts(self, node: Any, m: _Mirror) -> bool:
        """If only the parts' poses changed, send those; False if the shapes changed."""
        if m.part_keys is None:
            return False
        try:
            parts = node.parts()
        except Exception:
            return False
        if len(parts) != len(m.part_keys) or any(_part_key(p) != k for p, k in zip(parts, m.part_keys)):
            return False
        m.parts_ref = list(parts)
        for part, handles in zip(parts, m.part_handles):
            T = np.eye(4) if part.T_node_part is None else np.asarray(part.T_node_part, dtype=float)
            for h in handles:
                set_position(h, T[:3, 3])
                set_wxyz(h, r2q(T))
        self.counters["part_poses"] += 1
        return True

    def _update_geometry(self, node: Any, m: _Mirror) -> None:
        """The shape changed: update sizes in place where viser can, else rebuild."""
        self.counters["geometry"] += 1
        resize = _RESIZERS.get(_style(node.kind))
        if resize is not None and m.geoms:
            resize(m.geoms[0], node.props)
            self._update_props(node, m, count=False)
            return
        if self._move_parts(node, m):
            self.counters["geometry"] -= 1
            self._update_props(node, m, count=False)
            return
        for h in m.geoms:
            _safe_remove(h)
        self._build_geometry(node, m)

    def _update_props(self, node: Any, m: _Mirror, *, count: bool = True) -> None:
        """Colour, opacity and the kinds' own non-shape props, in place."""
        if count:
            self.counters["props"] += 1
        color = _rgb255(node.color)
        opacity = _opacity(node.opacity)
        style = _style(node.kind)
        if not m.geoms:
            if style == "gizmo":
                m.frame.scale = float(node.props.get("scale", 0.3))
            return
        _PROP_UPDATERS[style](self, node, m, color, opacity)

    # -- gizmos ---------------------------------------------------------------------------
    def _attach_gizmo(self, name: str, handle: Any) -> None:
        @handle.on_update
        def _(event: Any) -> None:
            phase = getattr(event, "phase", "update")
            with self._gizmo_lock:
                # while the user drags (and briefly after, for frames already in flight) the
                # server's poses must not snap the gizmo back; a drag whose end never comes
                # (a closed tab) stops counting a second after its last move
                self._dragging[name] = self.clock() + (0.3 if phase == "end" else 1.0)
            T = np.eye(4)
            T[:3, :3] = q2r(np.asarray(handle.wxyz, dtype=float))
            T[:3, 3] = np.asarray(handle.position, dtype=float)
            if np.all(np.isfinite(T)) and self.on_gizmo is not None:
                self.on_gizmo(name, T)

    def _is_dragging(self, name: str) -> bool:
        with self._gizmo_lock:
            until = self._dragging.get(name)
            if until is None:
                return False
            if self.clock() < until:
                return True
            del self._dragging[name]
            return False


def _camera_fov_aspect(props: dict[str, Any]) -> tuple[float, float]:
    """Vertical field of view (radians) and aspect ratio (w / h) of a camera node."""
    w, h = (float(v) for v in props.get("resolution", (320, 240)))
    K = props.get("intrinsics")
    if K is not None:
        K = np.asarray(K, dtype=float)
        fov = 2.0 * float(np.arctan2(h / 2.0, K[1, 1]))
    else:
        fov = float(np.radians(float(props.get("fov", 60.0))))
    return fov, (w / h if h > 0 else 4.0 / 3.0)


# -- what each drawing style sends (ejsrl.world.kinds: ``Kind.draw``) ---------------------------


def _style(kind: str) -> str:
    """How a node kind is drawn: its declared style, or its ``parts()`` as meshes."""
    decl = KINDS.get(kind)
    return decl.draw if decl is not None else "mesh"


Color = tuple[int, int, int]


def _build_box(mirror: SceneMirror, node: Any, m: _Mirror, base: str, color: Color, opacity: float | None) -> None:
    size = tuple(float(v) for v in np.asarray(node.props["size"], dtype=float).reshape(3))
    m.geoms.append(mirror.scene.add_box(f"{base}/g0", dimensions=size, color=color, opacity=opacity))


def _build_sphere(mirror: SceneMirror, node: Any, m: _Mirror, base: str, color: Color, opacity: float | None) -> None:
    m.geoms.append(
        mirror.scene.add_icosphere(f"{base}/g0", radius=float(node.props["radius"]), color=color, opacity=opacity, subdivisions=3)
    )


def _build_polyline(mirror: SceneMirror, node: Any, m: _Mirror, base: str, color: Color, opacity: float | None) -> None:
    m.line = LineDraw.build(mirror.scene, node, base, color)
    m.geoms.extend(m.line.geoms)


def _build_points(mirror: SceneMirror, node: Any, m: _Mirror, base: str, color: Color, opacity: float | None) -> None:
    m.line = PointsDraw.build(mirror.scene, node, base, color)
    m.geoms.extend(m.line.geoms)


def _build_frame(mirror: SceneMirror, node: Any, m: _Mirror, base: str, color: Color, opacity: float | None) -> None:
    size = float(node.props["size"])
    m.geoms.append(mirror.scene.add_frame(f"{base}/g0", axes_length=size, axes_radius=max(size * 0.04, 1e-4)))


def _build_grid(mirror: SceneMirror, node: Any, m: _Mirror, base: str, color: Color, opacity: float | None) -> None:
    size, cell = float(node.props["size"]), float(node.props["cell"])
    m.geoms.append(
        mirror.scene.add_grid(
            f"{base}/g0",
            width=size,
            height=size,
            plane="xy",
            cell_size=cell,
            section_size=cell * 10,
            cell_color=color,
            section_color=tuple(max(0, c - 60) for c in color),
        )
    )


def _build_label(mirror: SceneMirror, node: Any, m: _Mirror, base: str, color: Color, opacity: float | None) -> None:
    m.geoms.append(mirror.scene.add_label(f"{base}/g0", str(node.props["text"])))


def _build_camera(mirror: SceneMirror, node: Any, m: _Mirror, base: str, color: Color, opacity: float | None) -> None:
    fov, aspect = _camera_fov_aspect(node.props)
    m.geoms.append(mirror.scene.add_camera_frustum(f"{base}/g0", fov=fov, aspect=aspect, scale=0.1, color=color))


def _build_nothing(mirror: SceneMirror, node: Any, m: _Mirror, base: str, color: Color, opacity: float | None) -> None:
    """A group or a gizmo: only its frame (or its transform controls)."""


def _build_mesh(mirror: SceneMirror, node: Any, m: _Mirror, base: str, color: Color, opacity: float | None) -> None:
    mirror._build_mesh(node, m, base, color, opacity)


#: drawing style -> creates the geometry handles below the node's frame
_BUILDERS: dict[str, Callable[[SceneMirror, Any, _Mirror, str, Color, float | None], None]] = {
    "box": _build_box,
    "sphere": _build_sphere,
    "polyline": _build_polyline,
    "points": _build_points,
    "frame": _build_frame,
    "grid": _build_grid,
    "label": _build_label,
    "camera": _build_camera,
    "mesh": _build_mesh,
    "gizmo": _build_nothing,
    "none": _build_nothing,
}


def _resize_box(g: Any, props: dict[str, Any]) -> None:
    g.dimensions = tuple(float(v) for v in np.asarray(props["size"], dtype=float).reshape(3))


def _resize_sphere(g: Any, props: dict[str, Any]) -> None:
    g.radius = float(props["radius"])


#: drawing style -> changes the shape of its primitive in place (other styles are rebuilt,
#: or for meshes whose parts only moved, moved)
_RESIZERS: dict[str, Callable[[Any, dict[str, Any]], None]] = {"box": _resize_box, "sphere": _resize_sphere}


def _props_solid(mirror: SceneMirror, node: Any, m: _Mirror, color: Color, opacity: float | None) -> None:
    g = m.geoms[0]
    g.color = color
    g.opacity = opacity


def _props_polyline(mirror: SceneMirror, node: Any, m: _Mirror, color: Color, opacity: float | None) -> None:
    """A line, a trail or a point cloud: what changed, or drawn anew another way (a line whose
    shape changed: as pieces; two points became three hundred: one segment set)."""
    if m.line is not None and m.line.update(node, color):
        return
    draw = PointsDraw if _style(node.kind) == "points" else LineDraw
    changing = m.line is not None and m.line.changing
    for h in m.geoms:
        _safe_remove(h)
    m.line = draw.build(mirror.scene, node, mirror._path(node.name), color, changing=changing)
    m.geoms = list(m.line.geoms)


def _props_frame(mirror: SceneMirror, node: Any, m: _Mirror, color: Color, opacity: float | None) -> None:
    g = m.geoms[0]
    size = float(node.props["size"])
    g.axes_length = size
    g.axes_radius = max(size * 0.04, 1e-4)


def _props_label(mirror: SceneMirror, node: Any, m: _Mirror, color: Color, opacity: float | None) -> None:
    m.geoms[0].text = str(node.props["text"])


def _props_camera(mirror: SceneMirror, node: Any, m: _Mirror, color: Color, opacity: float | None) -> None:
    g = m.geoms[0]
    fov, aspect = _camera_fov_aspect(node.props)
    g.fov = fov
    g.aspect = aspect
    g.color = color


def _props_rebuild(mirror: SceneMirror, node: Any, m: _Mirror, color: Color, opacity: float | None) -> None:
    for h in m.geoms:
        _safe_remove(h)
    mirror._build_geometry(node, m)


def _props_nothing(mirror: SceneMirror, node: Any, m: _Mirror, color: Color, opacity: float | None) -> None:
    """A group or a gizmo has no geometry to update."""


def _props_mesh(mirror: SceneMirror, node: Any, m: _Mirror, color: Color, opacity: float | None) -> None:
    for h, takes_node_colour in zip(m.geoms, m.mesh_parts_rgb):
        if takes_node_colour:
            h.color = color
        h.opacity = opacity


#: drawing style -> updates colour, opacity and the non-shape props of its handles in place
_PROP_UPDATERS: dict[str, Callable[[SceneMirror, Any, _Mirror, Color, float | None], None]] = {
    "box": _props_solid,
    "sphere": _props_solid,
    "polyline": _props_polyline,
    "points": _props_polyline,
    "frame": _props_frame,
    "label": _props_label,
    "camera": _props_camera,
    "grid": _props_rebuild,
    "mesh": _props_mesh,
    "gizmo": _props_nothing,
    "none": _props_nothing,
}


def _faces_by_colour(face_rgb: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Face indices grouped by their (quantised) colour."""
    q = np.clip(np.round(face_rgb * 255), 0, 255).astype(np.int64)
    key = (q[:, 0] << 16) | (q[:, 1] << 8) | q[:, 2]
    out = []
    for k in np.unique(key):
        idx = np.nonzero(key == k)[0]
        out.append((np.array([(k >> 16) & 255, (k >> 8) & 255, k & 255], dtype=float) / 255.0, idx))
    return out


def _part_key(part: Any) -> tuple:
    """What identifies a part's shape: its arrays (by identity, or by content when small) and colours."""

    def arr(a: Any) -> Any:
        if a is None:
            return None
        a = np.asarray(a)
        return (a.shape, a.tobytes()) if a.size <= 3 * 4096 else (a.shape, id(a))

    rgb = None if part.rgb is None else tuple(np.asarray(part.rgb, dtype=float).round(4))
    return (arr(part.vertices), arr(part.faces), rgb, arr(part.face_rgb))


def _compact(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Only the vertices ``faces`` use, with the faces renumbered."""
    used, inverse = np.unique(faces.reshape(-1), return_inverse=True)
    return vertices[used], inverse.reshape(-1, 3)


def _safe_remove(handle: Any) -> None:
    try:
        handle.remove()
    except Exception:
        pass

