"""The prelude's world functions: what model code calls to move, grasp and check objects.

``object_pose(name)``, ``move_object(name, pose)``, ``attach(name, robot, link=None)``,
``release(name)`` and ``collisions()`` in a spec's code end up in :class:`WorldFunctions`,
which works on the ``SceneSync`` of the app (its ``world`` and its element bindings).

Rules (what a student sees):

- Every call first brings robots and expression-bound poses up to date with the model,
  so the world matches the variables even between display frames (in headless runs too).
- ``move_object`` and ``attach`` work on objects whose pose in the spec is constant (or
  absent). An object whose ``position``/``rotation``/``transform`` is an expression is
  placed by that expression every frame, so moving it from code is an error that says so.
  Robots and their links are moved by their joints and ``base``, never by these functions.
- An object that code moved, attached or released stays where code put it (its constant
  spec pose no longer applies) until the simulation is reset, which puts every object back
  where the spec has it.
- ``attach`` keeps the object's pose relative to the link at the moment of attaching (it
  becomes a child of the link node); ``release`` leaves it where it is, in the world frame.
  Attaching in ``init``, before the robot is first drawn, takes effect when it is drawn.
- ``collisions()`` lists the pairs of visible solid objects and robot links that touch,
  each ``(a, b)`` with ``a < b``, sorted. Robot links are named ``"<robot>.link<i>"``
  (``i`` = 0 for the base, as ``fkine_all``). A robot's neighbouring links (and links that
  already touch in the robot's zero pose, such as the parts of a spherical wrist) are never
  reported against each other, nor is a grasped object against its link, that link's
  neighbours and the links it touched when it was grasped, nor an object against the group
  that holds it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.world.collision import CollisionShape, CollisionWorld, intersects, shape_from_node
from ejsrl.world.robot_node import LinkNode, LinkShape, RobotNode
from ejsrl.world.scene import Node

__all__ = ["WorldFunctions", "RobotCollider"]

Array = NDArray[np.float64]

_PRIMITIVES = ("box", "sphere", "cylinder")


class WorldFunctions:
    """World functions over a ``SceneSync`` (``scene``).

    ``model``: the model whose variables the scene shows (an object, or a callable that
    returns it); by default the model of the scene's last update.
    """

    def __init__(self, scene: Any, model: Any = None) -> None:
        self.scene = scene
        self._model = model
        self.collider = RobotCollider()
        self._pending: dict[str, tuple[RobotNode, int | None]] = {}  # attach before the robot is drawn

    # -- helpers ------------------------------------------------------------------------------------
    @property
    def world(self) -> Any:
        return self.scene.world

    def _current_model(self) -> Any:
        m = self._model() if callable(self._model) else self._model
        return m if m is not None else getattr(self.scene, "model", None)

    def refresh(self) -> None:
        """Bring robots and expression-bound poses up to date with the model."""
        model = self._current_model()
        if model is not None:
            self.scene.refresh_poses(model)
        self._attach_pending()

    def _attach_pending(self) -> None:
        for name, (robot, link) in list(self._pending.items()):
            if robot.links:
                del self._pending[name]
                self._attach_now(self.world[name], robot, link)

    def _binding(self, name: str) -> Any:
        for b in self.scene.bindings:
            if b.node.name == name:
                return b
        return None

    def _movable(self, name: str, what: str) -> Node:
        """The node ``name`` if code may move it; else a ValueError that says why."""
        node = self.world[name]
        if isinstance(node, RobotNode):
            raise ValueError(f"cannot {what} '{name}': it is a robot; it moves with its joints q and its base")
        if isinstance(node, LinkNode):
            raise ValueError(f"cannot {what} '{name}': it is a link of robot '{node.robot.name}'; it moves with the robot's joints")
        b = self._binding(name)
        if b is None:
            raise ValueError(f"cannot {what} '{name}': it belongs to another object of the scene")
        if b.dynamic_pose:
            e = b.element
            src = next((p.source for p in (e.transform, e.position, e.rotation) if hasattr(p, "source")), "")
            raise ValueError(
                f"cannot {what} '{name}': its pose is the expression '{src}' in the spec, which places it "
                "every frame; change the variables of that expression instead, or give the object a constant position"
            )
        return node

    # -- the prelude's functions ---------------------------------------------------------------------
    def object_pose(self, name: str) -> Array:
        """The (4, 4) pose of the scene object ``name`` in the world (a copy)."""
        self.refresh()
        if name not in self.world:
            for node in self.world.walk():
                if isinstance(node, RobotNode) and not node.links and name.startswith(node.name + ".link"):
                    raise RuntimeError(
                        f"the links of robot '{node.name}' are not drawn yet: robots are first drawn right after the "
                        "model starts, so the first run of init and the fixed relations cannot see their links"
                    )
        return np.array(self.world.T_world(name))

    def move_object(self, name: str, pose: ArrayLike) -> None:
        """Place ``name`` at a world pose: a (4, 4) matrix, or an [x, y, z] position (the
        orientation stays). An attached object stays attached (at its new place on the link)."""
        node = self._movable(name, "move")
        self.refresh()
        P = np.asarray(pose, dtype=float)
        if P.shape == (3,):
            T = np.array(node.T_world())
            T[:3, 3] = P
        elif P.shape == (4, 4):
            T = P
        else:
            raise ValueError(f"move_object('{name}', pose): pose must be a 4x4 matrix or [x, y, z], got shape {P.shape}")
        if not np.all(np.isfinite(T)):
            raise ValueError(f"move_object('{name}', pose): the pose has non-finite numbers")
        self.world.set_world_pose(name, T)
        self.scene.placed.add(name)

    def attach(self, name: str, robot: str, link: int | None = None) -> None:
        """Attach ``name`` to link ``link`` of robot ``robot`` (None: the last link; 0: the base),
        keeping its pose relative to the link from now on."""
        node = self._movable(name, "attach")
        rnode = self.world[robot]
        if not isinstance(rnode, RobotNode):
            raise ValueError(f"attach('{name}', '{robot}'): '{robot}' is a {rnode.kind}, not a robot")
        if link is not None and not isinstance(link, (int, np.integer)):
            raise ValueError(f"attach('{name}', '{robot}', link): link must be a whole number, got {link!r}")
        self.refresh()
        self.scene.placed.add(name)
        if not rnode.links:  # init, before the robot is drawn: attach when it is
            self._pending[name] = (rnode, None if link is None else int(link))
            rnode.on_links.append(self._attach_pending)
            return
        self._attach_now(node, rnode, None if link is None else int(link))

    def _attach_now(self, node: Node, robot: RobotNode, link: int | None) -> None:
        target = robot.link(link)
        self.world.reparent(node.name, target, keep_world_pose=True)
        # the links it touches as it is grasped (the fingers, the wrist) may go on touching it
        self.collider.touch[node.name] = set()
        robot_links = {ln.name for ln in robot.links}
        self.collider.touch[node.name] = {
            b if a == node.name else a for a, b in self.collider.pairs(self.world) if node.name in (a, b) and ({a, b} & robot_links)
        }
        self.collider.invalidate()

    def release(self, name: str) -> None:
        """Let go of ``name``: it stays where it is now, in the world frame."""
        node = self.world[name]
        self._pending.pop(name, None)
        self.refresh()
        if isinstance(node.parent, LinkNode):
            self.world.reparent(name, None, keep_world_pose=True)
            self.scene.placed.add(name)
        self.collider.touch.pop(name, None)

    def attached_to(self, name: str) -> str | None:
        """The link node ``name`` hangs from, or None."""
        parent = self.world[name].parent
        return parent.name if isinstance(parent, LinkNode) else None

    def collisions(self) -> list[tuple[str, str]]:
        """The pairs of visible solid objects and robot links that touch now (sorted)."""
        self.refresh()
        return self.collider.pairs(self.world)

    def set_view(self, position: Any = None, target: Any = None, up: Any = None, fov: float | None = None, **kw: Any) -> None:
        """Ask for a camera of the 3D view (``ejsrl.world.view3d.set_view``)."""
        from ejsrl.world.view3d import set_view

        set_view(self.world, position, target, up, fov, **kw)

    def graspable_near(self, robot: Any, point: ArrayLike, reach: float) -> tuple[str, str] | None:
        """``(object, element)``: the nearest visible graspable object (not a robot or a link)
        within ``reach`` of ``point`` in the world, and the element that draws ``robot`` (a
        ``Robot``); None if there is none, or if no element draws ``robot``. At equal
        distances the object last in the scene wins."""
        self.refresh()  # robots and bound poses as the model has them now
        world = self.world
        element = next((n.name for n in world.walk() if isinstance(n, RobotNode) and n.model is robot), None)
        if element is None:
            return None
        tool = np.asarray(point, dtype=float).reshape(3)
        best, best_d = None, float(reach)
        for node in world.walk():
            if not node.graspable or isinstance(node, (RobotNode, LinkNode)) or not world.is_visible(node):
                continue
            d = float(np.linalg.norm(node.T_world()[:3, 3] - tool))
            if d <= best_d:
                best, best_d = node.name, d
        return (best, element) if best is not None else None


# -- collisions ----------------------------------------------------------------------------------------
def _link_shape(s: LinkShape) -> CollisionShape:
    if s.kind == "capsule":
        return CollisionShape.capsule(s.p0, s.p1, s.radius)
    return CollisionShape.cylinder(s.radius, s.height)


def _solid(node: Node) -> bool:
    return node.kind in _PRIMITIVES or bool(node.parts())


class RobotCollider:
    """Collision checks between the objects and robot links of a world, for every frame.

    Objects collide as exact primitives (box, sphere, cylinder) or the convex hull of their
    geometry; robot links as the capsules and cylinders of their automatic geometry (also
    when a robot is drawn with meshes). The checker is rebuilt only when the world's
    structure changes (objects added, hidden, attached, reshaped); otherwise a check only
    moves the shapes and runs the broad and narrow phases.
    """

    def __init__(self) -> None:
        self.cw: CollisionWorld | None = None
        self._key: tuple | None = None
        # (collision name, reported name, node, T_node_shape or None)
        self._entries: list[tuple[str, str, Node, Array | None]] = []
        self._report: dict[str, str] = {}
        self._zero_cache: dict[tuple, set[tuple[int, int]]] = {}
        #: for grasped objects: the robot links they touched when grasped (never reported)
        self.touch: dict[str, set[str]] = {}

    def invalidate(self) -> None:
        """Rebuild the checker at the next call (after a change the structure key misses)."""
        self._key = None

    def _structure(self, world: Any) -> tuple:
        items = []
        vis: dict[str, bool] = {}
        for node in world.walk():
            v = node.visible and (node.parent is None or vis[node.parent.name])
            vis[node.name] = v
            if v and (node.kind in _PRIMITIVES or node.kind == "mesh"):
                items.append((id(node), id(node.parent), node.geom_rev, id(getattr(node, "shapes", None))))
        return tuple(items)

    def _rebuild(self, world: Any) -> None:
        cw = CollisionWorld()
        entries: list[tuple[str, str, Node, Array | None]] = []
        groups: dict[str, list[str]] = {}  # reported name -> collision names
        vis: dict[str, bool] = {}
        links: dict[int, list[LinkNode]] = {}
        objects: list[Node] = []
        for node in world.walk():
            v = node.visible and (node.parent is None or vis[node.parent.name])
            vis[node.name] = v
            if not v:
                continue
            if isinstance(node, LinkNode):
                links.setdefault(id(node.robot), []).append(node)
                for k, s in enumerate(node.shapes):
                    key = f"{node.name}#{k}"
                    cw.add(key, _link_shape(s))
                    entries.append((key, node.name, node, s.T_link_shape))
                    groups.setdefault(node.name, []).append(key)
            elif not isinstance(node, RobotNode) and _solid(node):
                try:
                    shape = shape_from_node(node)
                except ValueError:
                    continue
                cw.add(node.name, shape)
                entries.append((node.name, node.name, node, None))
                groups.setdefault(node.name, []).append(node.name)
                objects.append(node)

        def ignore(a: str, b: str) -> None:
            for x in groups.get(a, ()):
                for y in groups.get(b, ()):
                    if x != y:
                        cw.ignore(x, y)

        for name, keys in groups.items():  # the pieces of one link
            for i, x in enumerate(keys):
                for y in keys[i + 1 :]:
                    cw.ignore(x, y)
        for chain in links.values():
            by_index = {ln.index: ln for ln in chain}
            robot = chain[0].robot
            for ln in chain:
                nxt = by_index.get(ln.index + 1)
                if nxt is not None:
                    ignore(ln.name, nxt.name)
            for i, j in self._touching_at_zero(robot):
                if i in by_index and j in by_index:
                    ignore(by_index[i].name, by_index[j].name)
        for obj in objects:
            parent = obj.parent
            if isinstance(parent, LinkNode):
                for ln in parent.robot.links:
                    if abs(ln.index - parent.index) <= 1 or ln.name in self.touch.get(obj.name, ()):
                        ignore(obj.name, ln.name)
            elif parent is not None and parent.name in groups:
                ignore(obj.name, parent.name)
        self.cw = cw
        self._entries = entries
        self._report = {key: rep for key, rep, _, _ in entries}

    def _touching_at_zero(self, robot: RobotNode) -> set[tuple[int, int]]:
        """Pairs of link indices (i < j, not neighbours) whose shapes touch in the zero pose."""
        model = robot.model
        links = robot.links
        key = (
            tuple((k.a, k.d, k.alpha, k.theta, k.offset, k.sigma, k.mdh) for k in model.links),
            tuple(tuple((s.kind, s.p0.tobytes(), s.p1.tobytes(), s.radius, s.height, s.T_link_shape.tobytes()) for s in ln.shapes)
                  for ln in links),
        )
        hit = self._zero_cache.get(key)
        if hit is not None:
            return hit
        q0 = np.asarray(getattr(model, "poses", {}).get("qz", np.zeros(model.n)), dtype=float)
        lim = np.asarray(model.qlim, dtype=float)
        q0 = np.clip(q0, lim[0], lim[1])
        F = np.asarray(model.fkine_all(q0), dtype=float)
        placed = [[(_link_shape(s), F[ln.index] @ s.T_link_shape) for s in ln.shapes] for ln in links]
        hit = set()
        for a in range(len(links)):
            for b in range(a + 2, len(links)):
                if any(intersects(sa, Ta, sb, Tb) for sa, Ta in placed[a] for sb, Tb in placed[b]):
                    hit.add((links[a].index, links[b].index))
        self._zero_cache[key] = hit
        return hit

    def pairs(self, world: Any) -> list[tuple[str, str]]:
        """The touching pairs of reported names (objects and ``<robot>.link<i>``), sorted."""
        key = self._structure(world)
        if key != self._key or self.cw is None:
            self._rebuild(world)
            self._key = key
        cw = self.cw
        assert cw is not None
        T_of: dict[int, Array] = {}
        for name, _rep, node, T_node_shape in self._entries:
            T = T_of.get(id(node))
            if T is None:
                T = T_of[id(node)] = node.T_world()
            cw.set_pose(name, T if T_node_shape is None else T @ T_node_shape)
        out = set()
        rep = self._report
        for a, b in cw.pairs():
            ra, rb = rep[a], rep[b]
            if ra != rb:
                out.add((ra, rb) if ra < rb else (rb, ra))
        return sorted(out)
