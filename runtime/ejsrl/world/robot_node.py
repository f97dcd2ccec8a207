"""Robots in the scene graph: an arm drawn from its kinematic model and a joint vector.

A :class:`RobotNode` (kind ``"robot"``) is a group whose frame is the robot's mounting
frame in its parent (the ``base`` expression of the spec, or the element's
``position``/``rotation``/``transform``). When it learns its ``model`` (a
``ejsrl.robotics.Robot``) it adds one :class:`LinkNode` child per frame of
``model.fkine_all``: ``"<robot>.link0"`` (the base, fkine_all index 0) to
``"<robot>.link<n>"``. Each link node's ``T_parent_local`` is ``fkine_all(q)[i]`` (so it
includes the model's own ``base``), and its ``parts()`` are the link's geometry in the link
frame: either the mesh file given for that link, the model's own geometry
(``model.visuals``: a URDF's meshes and primitives, see ``ejsrl.robotics.load_urdf``), or
automatic geometry made from the DH parameters (a rod for each of the link's ``d`` and ``a`` offsets, a cylinder for each
joint axis, a base plate and a tool flange), sized from ``model.reach``.

So each frame only the link poses change: the renderer (``World.triangles``), the browser
mirror and the collision checker treat links as ordinary solid nodes. Names of link
nodes contain no ``/`` (the browser mirror uses flat viser paths ``/ejs/<name>``).

World pose of link i = ``T_world(robot node) @ model.fkine_all(q)[i]``.

A model with another number of joints rebuilds the link nodes (objects attached to a link
move to the new link of the same index); another model object with as many joints (the
same arm made again on reset) keeps them, and different DH parameters (or an edit in
place, ``robot.links[1].a = 0.5``) only redraw the automatic geometry.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.world.scene import Frame, Group, MeshNode, Node, Part, World

__all__ = ["RobotNode", "LinkNode", "LinkShape", "link_name", "robot_geometry", "model_visuals", "remove_subtree"]

Array = NDArray[np.float64]

#: colour of the automatic joint housings (RGB in [0, 1])
JOINT_RGB = (0.22, 0.23, 0.26)
#: default colour of a robot drawn with automatic geometry
ROBOT_COLOR = "#e8892c"


def link_name(robot: str, index: int) -> str:
    """The scene name of link ``index`` (0: the base) of the robot element ``robot``."""
    return f"{robot}.link{index}"


class LinkShape:
    """One convex piece of a link for collision checking, in the link frame.

    ``kind``: "capsule" (``p0``, ``p1`` (3,), ``radius``) or "cylinder" (``radius``,
    ``height`` along ``axis`` z of ``T_link_shape``); ``T_link_shape``: (4, 4).
    """

    __slots__ = ("kind", "p0", "p1", "radius", "height", "T_link_shape")

    def __init__(self, kind: str, *, p0: ArrayLike = (0, 0, 0), p1: ArrayLike = (0, 0, 0), radius: float,
                 height: float = 0.0, T_link_shape: ArrayLike | None = None) -> None:
        self.kind = kind
        self.p0 = np.asarray(p0, dtype=float).reshape(3)
        self.p1 = np.asarray(p1, dtype=float).reshape(3)
        self.radius = float(radius)
        self.height = float(height)
        self.T_link_shape = np.eye(4) if T_link_shape is None else np.asarray(T_link_shape, dtype=float)


# -- automatic geometry -----------------------------------------------------------------------
def _sizes(model: Any) -> tuple[float, float, float]:
    """Rod radius, joint housing radius and joint housing length (m), from the arm's reach."""
    reach = float(getattr(model, "reach", 0.0) or 0.0)
    r = 0.022 * reach if reach > 1e-6 else 0.02
    return r, 1.5 * r, 3.6 * r


def robot_geometry(model: Any) -> tuple[list[list[Part]], list[list[LinkShape]]]:
    """Automatic geometry of every link frame 0..n: (parts per link, collision shapes per link).

    Standard DH: link i's body runs from frame i-1's origin along ``d`` on z_{i-1}, then
    ``a`` along x_i; in frame i that is the polyline ``(-a, -d sin(alpha), -d cos(alpha))``,
    ``(-a, 0, 0)``, ``(0, 0, 0)``, rigid in frame i whatever q is. Joint i+1's housing is a
    cylinder on z_i at frame i's origin. Modified DH: the ``d`` rod lies on z_i in frame i,
    the ``a`` rod (``a_{i-1}``) on x_{i-1} in frame i-1, joint i's housing on z_i.
    Prismatic links take their upper limit as ``d`` (a rod that slides through the joint).
    """
    import trimesh

    n = int(model.n)
    r, rj, hj = _sizes(model)
    lengths = np.asarray(model.link_lengths(), dtype=float).reshape(n, 2)
    alphas = [float(link.alpha) for link in model.links]
    prismatic = [bool(link.isprismatic) for link in model.links]
    mdh = bool(model.mdh)
    ets = bool(getattr(model, "ets", False))
    rods: list[list[tuple[Array, Array]]] = [[] for _ in range(n + 1)]
    housings: list[list[tuple[int, bool]]] = [[] for _ in range(n + 1)]  # (joint index, prismatic)
    for i in range(1, n + 1):
        a, d = lengths[i - 1]
        al = alphas[i - 1]
        if ets:  # elementary transforms: a rod from frame i-1 to the joint, then the slide on z_i
            rods[i - 1].append((np.zeros(3), np.array(model.links[i - 1].origin[:3, 3], dtype=float)))
            rods[i].append((np.array([0.0, 0.0, -d]), np.zeros(3)))
            housings[i].append((i, prismatic[i - 1]))
        elif not mdh:
            p_prev = np.array([-a, -d * np.sin(al), -d * np.cos(al)])
            corner = np.array([-a, 0.0, 0.0])
            rods[i].append((p_prev, corner))
            rods[i].append((corner, np.zeros(3)))
            housings[i - 1].append((i, prismatic[i - 1]))
        else:
            rods[i - 1].append((np.zeros(3), np.array([a, 0.0, 0.0])))
            rods[i].append((np.array([0.0, 0.0, -d]), np.zeros(3)))
            housings[i].append((i, prismatic[i - 1]))
    tool = np.asarray(getattr(model, "tool", np.eye(4)), dtype=float)
    if np.linalg.norm(tool[:3, 3]) > 1e-9:
        rods[n].append((np.zeros(3), tool[:3, 3].copy()))

    parts: list[list[Part]] = []
    shapes: list[list[LinkShape]] = []
    for i in range(n + 1):
        body: list[Any] = []
        dark: list[Any] = []
        sh: list[LinkShape] = []
        for p0, p1 in rods[i]:
            length = float(np.linalg.norm(p1 - p0))
            if length < 1e-9:
                continue
            body.append(trimesh.creation.cylinder(radius=r, segment=np.array([p0, p1]), sections=16))
            for p in (p0, p1):
                body.append(trimesh.creation.icosphere(subdivisions=1, radius=r).apply_translation(p))
            sh.append(LinkShape("capsule", p0=p0, p1=p1, radius=r))
        for _joint, is_prismatic in housings[i]:
            # the housing is centred on the joint, except the first one, which stands on the base plate
            T = _tz(r + hj / 2) if i == 0 else np.eye(4)
            if is_prismatic:
                dark.append(trimesh.creation.box(extents=(2 * rj, 2 * rj, hj), transform=T))
            else:
                dark.append(trimesh.creation.cylinder(radius=rj, height=hj, sections=24, transform=T))
            sh.append(LinkShape("cylinder", radius=rj * (np.sqrt(2) if is_prismatic else 1.0), height=hj, T_link_shape=T))
        if i == 0:  # a base plate on frame 0's xy plane
            T = _tz(r / 2)
            dark.append(trimesh.creation.cylinder(radius=2.2 * rj, height=r, sections=32, transform=T))
            sh.append(LinkShape("cylinder", radius=2.2 * rj, height=r, T_link_shape=T))
        if i == n:  # a tool flange on frame n
            T = _tz(r / 2)
            dark.append(trimesh.creation.cylinder(radius=0.9 * rj, height=r, sections=24, transform=T))
            sh.append(LinkShape("cylinder", radius=0.9 * rj, height=r, T_link_shape=T))
        out: list[Part] = []
        if body:
            m = trimesh.util.concatenate(body)
            out.append(Part(m.vertices, m.faces, None))
        if dark:
            m = trimesh.util.concatenate(dark)
            out.append(Part(m.vertices, m.faces, JOINT_RGB))
        parts.append(out)
        shapes.append(sh)
    return parts, shapes


def model_visuals(model: Any) -> tuple[list[list[Part]], list[list[LinkShape]]]:
    """The model's own geometry (``model.visuals``, e.g. a URDF's meshes): parts per link
    frame 0..n, and for collisions one capsule around each piece (along its longest
    principal axis, radius the largest distance of a vertex from that axis)."""
    visuals = model.visuals
    n = int(model.n)
    if len(visuals) != n + 1:
        raise ValueError(f"{getattr(model, 'name', 'robot')}: visuals must list n + 1 = {n + 1} link frames, "
                         f"got {len(visuals)}")
    parts: list[list[Part]] = []
    shapes: list[list[LinkShape]] = []
    for pieces in visuals:
        ps: list[Part] = []
        sh: list[LinkShape] = []
        for vis in pieces:
            rgba = getattr(vis, "rgba", None)
            for m in vis.trimeshes():
                rgb = m.metadata.get("rgb")
                if rgb is None and rgba is not None:
                    rgb = np.asarray(rgba, dtype=float)[:3]
                ps.append(Part(m.vertices, m.faces, rgb))
                cap = _capsule(np.asarray(m.vertices, dtype=float))
                if cap is not None:
                    sh.append(cap)
        parts.append(ps)
        shapes.append(sh)
    return parts, shapes


def _capsule(V: Array) -> LinkShape | None:
    """A capsule that holds the points V (k, 3): its axis is their longest principal axis."""
    if len(V) < 2:
        return None
    c = V.mean(axis=0)
    _, _, Vt = np.linalg.svd(V - c, full_matrices=False)
    u = Vt[0]
    t = (V - c) @ u
    radial = np.linalg.norm((V - c) - np.outer(t, u), axis=1)
    r = float(radial.max())
    # shorten the segment by the radius at each end where the points allow it
    lo, hi = float(t.min()), float(t.max())
    if hi - lo > 2 * r:
        lo, hi = lo + r, hi - r
    else:
        lo = hi = 0.5 * (lo + hi)
    # the capsule must still cover every point: grow the radius to the farthest one
    tc = np.clip(t, lo, hi)
    r = float(np.linalg.norm((V - c) - np.outer(tc, u), axis=1).max())
    return LinkShape("capsule", p0=c + lo * u, p1=c + hi * u, radius=max(r, 1e-6))


def _tz(z: float) -> Array:
    T = np.eye(4)
    T[2, 3] = z
    return T


def _geometry_key(model: Any) -> tuple:
    """What the automatic geometry depends on: the links' parameters and the tool offset."""
    links = model.links
    return (
        len(links),
        tuple((float(k.a), float(k.d), float(k.alpha), bool(k.isprismatic),
               None if k.qlim is None else tuple(np.asarray(k.qlim, dtype=float).tolist()),
               tuple(np.asarray(getattr(k, "origin", np.eye(4)), dtype=float)[:3].round(12).ravel().tolist()))
              for k in links),
        tuple(np.asarray(model.tool, dtype=float)[:3, 3].round(12).tolist()),
        id(getattr(model, "visuals", None)),
    )


# -- the world helpers ----------------------------------------------------------------------------
def remove_subtree(world: World, node: Node) -> None:
    """Take ``node`` and everything below it out of ``world``."""
    world.remove(node.name)


# -- nodes ---------------------------------------------------------------------------------------
class LinkNode(MeshNode):
    """One link frame of a robot (0: the base); its parts are in the link frame.

    It is a mesh node (kind ``"mesh"``) to every consumer of the world; ``robot`` is its
    :class:`RobotNode` and ``index`` its fkine_all index. ``shapes``: its collision pieces.
    """

    def __init__(self, name: str, robot: RobotNode, index: int, parts: Sequence[Part], shapes: list[LinkShape],
                 **common: Any) -> None:
        super().__init__(name, mesh_parts=tuple(parts), **common)
        self.robot = robot
        self.index = index
        self.shapes = shapes


class RobotNode(Group):
    """An arm: ``model`` (a ``Robot``), joint vector ``q`` (n,), optional ``base`` (4, 4).

    Set them with :meth:`set` (as ``SceneSync`` does every frame): ``set(model=robot,
    q=q, base=T, T_parent_local=T_pose)``. The node's frame in its parent is
    ``T_pose @ base``. ``mesh_parts``: optional loaded meshes, one list of parts per link
    (n lists for links 1..n, or n + 1 with the base first); ``meshes`` keeps their file
    names. ``show_frames`` adds coordinate axes ``"<robot>.frame<i>"`` to every link.
    """

    kind = "robot"
    DEFAULTS = {"meshes": (), "show_frames": False}

    def __init__(
        self,
        name: str,
        *,
        model: Any = None,
        q: ArrayLike | None = None,
        base: ArrayLike | None = None,
        mesh_parts: Sequence[Sequence[Part]] | None = None,
        color: Any = ROBOT_COLOR,
        T_parent_local: ArrayLike | None = None,
        **kw: Any,
    ) -> None:
        super().__init__(name, color=color, **kw)
        self.model: Any = None
        self.q: Array | None = None
        self.base: Array | None = None
        self.mesh_parts = [list(p) for p in mesh_parts] if mesh_parts else None
        self.links: list[LinkNode] = []
        #: link frames relative to this node, (n+1, 4, 4): model.fkine_all(q)
        self.frames: Array | None = None
        self._T_pose = np.eye(4) if T_parent_local is None else np.array(T_parent_local, dtype=float)
        self._geom_key: tuple | None = None
        self._pending: dict[str, Any] = {}
        #: called once each after the links are next (re)built (e.g. an attach made in init)
        self.on_links: list[Callable[[], None]] = []
        if base is not None:
            B = np.array(base, dtype=float)
            if B.shape != (4, 4):
                raise ValueError(f"the base of robot '{name}' must be a 4x4 matrix, got shape {B.shape}")
            self.base = B
        if q is not None:
            self.q = np.array(q, dtype=float).reshape(-1)
        if model is not None:
            self._pending["model"] = model
        self._apply_pose()

    # -- properties -------------------------------------------------------------------------------
    def set(self, **values: Any) -> bool:
        """Set ``model``, ``q``, ``base``, ``T_parent_local`` (the element's own pose) and the
        common properties; returns True if anything changed. Raises ValueError for a q of
        the wrong length or a base that is not 4x4 (nothing is changed then)."""
        if self._pending and self.world is not None:
            pending, self._pending = self._pending, {}
            values = {**pending, **values}
        model = values.pop("model", None)
        q = values.pop("q", None)
        base = values.pop("base", None)
        T_pose = values.pop("T_parent_local", None)
        if self.world is None and model is not None:  # not in a world yet: make the links later
            self._pending["model"] = model
        q_arr = None if q is None else np.asarray(q, dtype=float).reshape(-1)
        base_arr = None if base is None else np.asarray(base, dtype=float)
        if base_arr is not None and base_arr.shape != (4, 4):
            raise ValueError(f"the base of robot '{self.name}' must be a 4x4 matrix, got shape {base_arr.shape}")
        new_model = model if model is not None else self.model
        n = getattr(new_model, "n", None)
        if q_arr is not None and n is not None and q_arr.shape != (n,):
            raise ValueError(f"robot '{self.name}' has {n} joints, but q has {q_arr.size} values")
        if model is not None and not (hasattr(model, "fkine_all") and hasattr(model, "links")):
            raise ValueError(f"the model of robot '{self.name}' must be a Robot, got {type(model).__name__}")

        changed = super().set(**values) if values else False
        if changed and ({"color", "opacity"} & set(values)):
            for link in self.links:
                link.set(color=self.color, opacity=self.opacity)
        if T_pose is not None:
            self._T_pose = np.array(T_pose, dtype=float)
        if base_arr is not None:
            self.base = base_arr
        if T_pose is not None or base_arr is not None:
            changed |= self._apply_pose()
        if q_arr is not None and (self.q is None or not np.array_equal(q_arr, self.q)):
            self.q = q_arr
            changed = True
        if self.world is not None and new_model is not None:
            if model is not None and len(self.links) != model.n + 1:
                self._rebuild(model)
                changed = True
            swapped = model is not None and model is not self.model
            if swapped:
                self.model = model  # same number of links (e.g. the same arm made again on reset): keep the nodes
                changed = True
            if _geometry_key(self.model) != self._geom_key:
                self._regeometry()
            changed |= self._pose_links(force=swapped)
        return changed

    def _apply_pose(self) -> bool:
        T = self._T_pose if self.base is None else self._T_pose @ self.base
        if np.array_equal(T, self.T_parent_local):
            return False
        self.T_parent_local = np.array(T)
        self.rev += 1
        return True

    # -- links ------------------------------------------------------------------------------------
    def link(self, index: int | None = None) -> LinkNode:
        """Link node ``index`` (0: the base, n: the last link; None: the last; negative from the end)."""
        if not self.links:
            raise RuntimeError(f"robot '{self.name}' has no links yet (its model has not been evaluated)")
        n = len(self.links) - 1
        i = n if index is None else int(index)
        if i < 0:
            i += n + 1
        if not 0 <= i <= n:
            raise IndexError(f"robot '{self.name}' has links 0 (the base) to {n}, not {index}")
        return self.links[i]

    def _link_geometry(self, model: Any) -> tuple[list[list[Part]], list[list[LinkShape]]]:
        n = int(model.n)
        if self.mesh_parts is None and getattr(model, "visuals", None):
            return model_visuals(model)
        auto_parts, auto_shapes = robot_geometry(model)
        if self.mesh_parts is None:
            return auto_parts, auto_shapes
        meshes = self.mesh_parts
        if len(meshes) == n:
            meshes = [[]] + meshes
        if len(meshes) != n + 1:
            raise ValueError(
                f"robot '{self.name}' has {n} links, but {len(self.mesh_parts)} mesh files were given "
                f"(give {n}, one per link, or {n + 1} with the base first)"
            )
        parts = [list(p) if p else (auto_parts[0] if i == 0 else []) for i, p in enumerate(meshes)]
        return parts, auto_shapes

    def _rebuild(self, model: Any) -> None:
        world = self.world
        assert world is not None
        parts, shapes = self._link_geometry(model)
        guests: list[tuple[int, Node, Array]] = []  # attached objects: link index, node, T_link_object
        for link in self.links:
            for child in list(link.children):
                if not _owned(child):
                    guests.append((link.index, child, child.T_parent_local.copy()))
                    world.reparent(child.name, None, keep_world_pose=True)
            remove_subtree(world, link)
        revs = {link.name: (link.rev, link.geom_rev) for link in self.links}
        self.model = model
        self.links = []
        frame_size = 0.12 * max(float(getattr(model, "reach", 1.0) or 1.0), 0.1)
        for i in range(int(model.n) + 1):
            link = LinkNode(link_name(self.name, i), self, i, parts[i], shapes[i], color=self.color, opacity=self.opacity)
            if link.name in revs:  # a viewer that keys nodes by name must see a new shape
                link.rev, link.geom_rev = revs[link.name][0] + 1, revs[link.name][1] + 1
            world.add(link, self)
            self.links.append(link)
            if self.props["show_frames"]:
                world.add(Frame(f"{self.name}.frame{i}", size=frame_size), link)
        self._geom_key = _geometry_key(model)
        self.frames = None
        self._pose_links(force=True)
        for index, child, T_link_child in guests:  # they keep their pose relative to the link
            if index < len(self.links):
                world.reparent(child.name, self.links[index], keep_world_pose=False)
                child.set(T_parent_local=T_link_child)
        callbacks, self.on_links = self.on_links, []
        for fn in callbacks:
            fn()

    def _regeometry(self) -> None:
        """New DH parameters: redraw the automatic geometry (meshes stay) and the collision shapes."""
        parts, shapes = self._link_geometry(self.model)
        for link, p, s in zip(self.links, parts, shapes):
            if self.mesh_parts is None:
                link.set(mesh_parts=tuple(p))
            link.shapes = s
        self._geom_key = _geometry_key(self.model)

    def _pose_links(self, force: bool = False) -> bool:
        """Place the links at ``model.fkine_all(q)``; True if any moved."""
        if self.model is None or not self.links:
            return False
        q = self.q
        if q is None:
            q = np.zeros(self.model.n)
        F = np.asarray(self.model.fkine_all(q), dtype=float)
        if not force and self.frames is not None and np.array_equal(F, self.frames):
            return False
        self.frames = F
        for link, T in zip(self.links, F):
            if force or not np.array_equal(link.T_parent_local, T):
                link.T_parent_local = np.array(T)
                link.rev += 1
        return True


def _owned(node: Node) -> bool:
    """True for the nodes a robot makes itself (links, link frames), False for attached objects."""
    return isinstance(node, LinkNode) or (isinstance(node, Frame) and ".frame" in node.name and node.parent is not None
                                          and isinstance(node.parent, LinkNode))
