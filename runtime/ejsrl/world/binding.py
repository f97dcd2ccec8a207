"""Keep the runtime's ``World`` in step with the model, from the view's ``Scene`` description.

``SceneSync`` builds one world node per ``Node3D`` element, then on every frame evaluates
each element's dynamic properties against the model and writes them into its node
(nodes count their own changes, so the browser view can send only what changed). It runs
with or without a browser, so ``capture()`` sees the same world in headless runs.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ejsrl.robotics.transforms import rpy2r
from ejsrl.view.elements import Dynamic, Folder, Node3D, Scene, Tabs, is_dynamic
from ejsrl.world.kinds import KINDS
from ejsrl.world.scene import NODE_KINDS, Node, Trail, World

__all__ = ["SceneSync", "pose_from", "scene_elements"]

Evaluate = Callable[[Any, str], Any]


def pose_from(position: Any, rotation: Any, transform: Any) -> np.ndarray:
    """A (4, 4) pose from a ``transform`` or from ``position`` (3,) and ``rotation`` (roll, pitch, yaw)."""
    if transform is not None:
        T = np.asarray(transform, dtype=float)
        if T.shape != (4, 4):
            raise ValueError(f"a transform must be a 4x4 matrix, got shape {T.shape}")
        return T
    T = np.eye(4)
    if position is not None:
        p = np.asarray(position, dtype=float).reshape(-1)
        if p.shape != (3,):
            raise ValueError(f"a position needs 3 numbers, got {p.size}")
        T[:3, 3] = p
    if rotation is not None:
        r = np.asarray(rotation, dtype=float).reshape(-1)
        if r.shape != (3,):
            raise ValueError(f"a rotation needs 3 angles (roll, pitch, yaw), got {r.size}")
        T[:3, :3] = rpy2r(r)
    return T


def scene_elements(view: list[Any]) -> list[Node3D]:
    """The top-level 3D elements of every ``Scene`` in a view (inside folders and tabs too)."""
    out: list[Node3D] = []
    for element in view:
        if isinstance(element, Scene):
            out.extend(element.children)
        elif isinstance(element, Folder):
            out.extend(scene_elements(element.children))
        elif isinstance(element, Tabs):
            for _, children in element.tabs:
                out.extend(scene_elements(children))
    return out


class _Binding:
    """One element and its node, with the lists of constant and dynamic properties."""

    __slots__ = ("element", "node", "dynamic_props", "dynamic_pose", "dynamic_common", "trail_point")

    def __init__(self, element: Node3D, node: Node) -> None:
        self.element = element
        self.node = node
        props = dict(element.props)
        self.trail_point = props.pop("point", None) if element.kind == "trail" else None
        self.dynamic_props = {k: v for k, v in props.items() if is_dynamic(v)}
        self.dynamic_pose = any(is_dynamic(p) for p in (element.position, element.rotation, element.transform))
        self.dynamic_common = {
            k: v for k, v in (("visible", element.visible), ("color", element.color), ("opacity", element.opacity)) if is_dynamic(v)
        }


class SceneSync:
    """Builds the world from the scene elements and refreshes it from the model.

    ``base_dir`` resolves mesh files; ``node_factories`` may add node kinds (robots).
    """

    def __init__(self, elements: list[Node3D], *, base_dir: Path | str = ".", world: World | None = None) -> None:
        self.world = world if world is not None else World()
        self.base_dir = Path(base_dir)
        self.bindings: list[_Binding] = []
        #: names of objects that model code placed (move_object, attach): their spec pose no
        #: longer applies until a reset
        self.placed: set[str] = set()
        #: the model of the last update (world functions use it to bring robots up to date)
        self.model: Any = None
        self._home: dict[str, Node | None] = {}
        for element in elements:
            self._build(element, None)

    def where_of(self, name: str) -> str:
        """The spec location of the element that made node ``name`` ("" if none did)."""
        return next((b.element.where for b in self.bindings if b.node.name == name), "")

    # -- building ---------------------------------------------------------------------------
    def _build(self, element: Node3D, parent: Node | None) -> None:
        node = self._make_node(element)
        self.world.add(node, parent)
        self.bindings.append(_Binding(element, node))
        self._home[node.name] = parent
        if not any(is_dynamic(p) for p in (element.position, element.rotation, element.transform)):
            try:  # constant poses hold from the start (for object_pose() in init)
                node.set(T_parent_local=pose_from(element.position, element.rotation, element.transform))
            except ValueError:
                pass  # reported by the first update
        for child in element.children:
            self._build(child, node)

    def _make_node(self, element: Node3D) -> Node:
        common: dict[str, Any] = {"graspable": bool(element.graspable)}
        for key in ("visible", "color", "opacity"):
            value = getattr(element, key)
            if value is not None and not is_dynamic(value):
                common[key] = value
        factory = _FACTORIES.get(element.kind)
        if factory is not None:
            return factory(self, element, common)
        cls = NODE_KINDS.get(element.kind)
        if cls is None:
            raise ValueError(f"unknown 3D element kind {element.kind!r}")
        decl = KINDS.get(element.kind)
        state = decl.node_extra if decl is not None else {}  # what the node keeps itself (a trail's points)
        own = {k: v for k, v in element.props.items() if k in cls.DEFAULTS and k not in state and not is_dynamic(v)}
        return cls(element.name, **own, **common)

    # -- every frame ----------------------------------------------------------------------------
    def reset(self) -> None:
        """Clear what accumulates over time (trails); put objects that model code moved,
        attached or released back where the spec has them."""
        for b in self.bindings:
            if isinstance(b.node, Trail):
                b.node.clear()
        for b in self.bindings:
            node = b.node
            home = self._home.get(node.name)
            if node.parent is not home:
                self.world.reparent(node.name, home, keep_world_pose=False)
            if node.name in self.placed and not b.dynamic_pose:
                e = b.element
                try:
                    node.set(T_parent_local=pose_from(e.position, e.rotation, e.transform))
                except ValueError:
                    pass
        self.placed.clear()

    def update(self, model: Any, evaluate: Evaluate | None = None, *, first: bool = False) -> None:
        """Evaluate every dynamic property against ``model`` and write it into the world.

        ``evaluate(prop, where)`` reads a property under the app's error guard (it returns
        None after an error, and the property is then left as it was); ``first`` also
        applies constant poses (done once).
        """
        ev = evaluate or (lambda prop, where: prop(model) if isinstance(prop, Dynamic) else prop)
        self.model = model
        for b in self.bindings:
            e = b.element
            values: dict[str, Any] = {}
            for key, prop in b.dynamic_props.items():
                v = ev(prop, e.where)
                if v is not None:
                    values[key] = v
            for key, prop in b.dynamic_common.items():
                v = ev(prop, e.where)
                if v is not None:
                    values[key] = v
            if (b.dynamic_pose or first) and b.node.name not in self.placed:
                parts = [ev(p, e.where) if is_dynamic(p) else p for p in (e.position, e.rotation, e.transform)]
                if not any(is_dynamic(p) and v is None for p, v in zip((e.position, e.rotation, e.transform), parts)):
                    try:
                        values["T_parent_local"] = pose_from(*parts)
                    except ValueError as exc:
                        ev(Dynamic(_raiser(exc), ""), e.where)
            if "scale" in values and b.node.kind == "mesh":
                values["scale"] = float(np.asarray(values["scale"], dtype=float).reshape(-1)[0]) if np.ndim(values["scale"]) else values["scale"]
            if values:
                try:
                    b.node.set(**values)
                except (ValueError, TypeError) as exc:
                    ev(Dynamic(_raiser(exc), ""), e.where)
            if b.trail_point is not None:
                p = ev(b.trail_point, e.where) if is_dynamic(b.trail_point) else b.trail_point
                if p is not None:
                    b.node.push(p)  # type: ignore[attr-defined]

    def refresh_poses(self, model: Any) -> None:
        """Bring poses up to date with ``model`` now (robots, and elements whose pose is an
        expression), for world functions called between frames. Errors propagate to the
        caller (the user code that called the world function)."""
        self.model = model
        for b in self.bindings:
            e = b.element
            values: dict[str, Any] = {}
            if e.kind == "robot":
                for key in ("model", "q", "base"):
                    prop = b.dynamic_props.get(key)
                    if prop is not None:
                        values[key] = prop(model)
            if b.dynamic_pose and b.node.name not in self.placed:
                values["T_parent_local"] = pose_from(*(p(model) if is_dynamic(p) else p for p in (e.position, e.rotation, e.transform)))
            if values:
                b.node.set(**values)


def _robot_node(sync: SceneSync, element: Node3D, common: dict[str, Any]) -> Node:
    from ejsrl.world.mesh import load_mesh
    from ejsrl.world.robot_node import RobotNode

    props = element.props
    meshes = [str(f) for f in (props.get("meshes") or ())]
    const = {k: props[k] for k in ("q", "base") if props.get(k) is not None and not is_dynamic(props[k])}
    return RobotNode(
        element.name,
        mesh_parts=[load_mesh(sync.base_dir / f) for f in meshes] or None,
        meshes=tuple(meshes),
        show_frames=bool(props.get("show_frames", False)),
        **const,
        **common,
    )


def _mesh_node(sync: SceneSync, element: Node3D, common: dict[str, Any]) -> Node:
    from ejsrl.world.mesh import load_mesh

    file = element.props.get("file", "")
    parts = load_mesh(sync.base_dir / str(file))
    scale = element.props.get("scale", 1.0)
    return NODE_KINDS["mesh"](element.name, mesh_parts=tuple(parts), scale=1.0 if is_dynamic(scale) else scale, file=str(file), **common)


def _module_node(sync: SceneSync, element: Node3D, common: dict[str, Any]) -> Node:
    """A node whose class lives in its kind's ``node_module`` (the mobile robots' kinds:
    ``ejsrl.mobile._nodes``), made from the element's constant properties."""
    import importlib

    decl = KINDS[element.kind]
    module = importlib.import_module(str(decl.node_module))
    cls = next(c for c in vars(module).values() if isinstance(c, type) and issubclass(c, Node) and c.__dict__.get("kind") == element.kind)
    own = {k: v for k, v in element.props.items() if k in cls.DEFAULTS and k not in decl.node_extra and not is_dynamic(v)}
    return cls(element.name, **own, **common)


#: kinds whose nodes need more than their constant properties (files to load); every other
#: kind's node is its ``NODE_KINDS`` class made from the element's constant properties
_FACTORIES: dict[str, Callable[[SceneSync, Node3D, dict[str, Any]], Node]] = {"robot": _robot_node, "mesh": _mesh_node}
_FACTORIES.update({name: _module_node for name, k in KINDS.items() if k.node_module is not None and name not in _FACTORIES})


def _raiser(exc: Exception) -> Callable[[Any], Any]:
    def fn(_model: Any) -> Any:
        raise exc

    return fn
