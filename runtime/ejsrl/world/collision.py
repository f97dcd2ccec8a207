"""Collision checking between named convex shapes with world poses.

Two layers, as elsewhere in ejsrl: :func:`distance` and :func:`intersects` work on two
shapes and their poses; :class:`CollisionWorld` holds named shapes, updated every frame,
and answers ``pairs()``, the list behind the ``collisions()`` function of model code.

Shapes (:class:`CollisionShape`), each in its own frame:

- ``CollisionShape.sphere(radius)``: centred on the frame;
- ``CollisionShape.box(size)``: edge lengths [x, y, z], centred, axis-aligned in the frame;
- ``CollisionShape.cylinder(radius, height)``: along the frame's z axis, centred (as the
  scene's ``Cylinder`` node);
- ``CollisionShape.capsule(p0, p1, radius)``: the points within ``radius`` of the segment
  [p0, p1] (robot links: a capsule between consecutive joint frames);
- ``CollisionShape.convex(vertices)``: the convex hull of points (a mesh's hull).

Narrow phase (exact up to floating point, ~1e-9 m): closed forms for sphere/capsule pairs
(segment-segment distance) and sphere/capsule against a box (an exact piecewise-quadratic
segment-box distance), the 15-axis separating-axis test for box-box, and GJK on support
functions for every other pair (cylinders and hulls). A NumPy AABB broad phase over all
shapes picks the pairs that reach the narrow phase. Touching counts as colliding.

Example::

    cw = CollisionWorld()
    cw.add_chain(["l1", "l2", "l3"], points, radius=0.04)   # adjacent links ignored
    cw.add("table", CollisionShape.box([1, 1, 0.05]), T_world_table)
    cw.set_chain(["l1", "l2", "l3"], new_points)            # every frame
    cw.pairs()                                               # [("l3", "table")]
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.world._collision_narrow import (
    Support,
    gjk_distance,
    obb_overlap,
    segment_box_distance,
    segment_segment_distance,
)

__all__ = [
    "CollisionShape",
    "CollisionWorld",
    "distance",
    "intersects",
    "shape_from_node",
    "collisions",
    "CONTACT_TOL",
]

Array = NDArray[np.float64]

#: shapes closer than this (metres) count as touching
CONTACT_TOL = 1e-9

_ROUND = ("sphere", "capsule")


class CollisionShape:
    """A convex solid in its own frame; build it with the class methods.

    ``kind``: "sphere", "capsule", "box", "cylinder" or "convex"; ``radius``: the sphere,
    capsule or cylinder radius (0 for others); ``half``: (3,) box half edges; ``p0``, ``p1``:
    (3,) capsule end points; ``height``: cylinder height; ``vertices``: (N, 3) hull points;
    ``lo``, ``hi``: (3,) the shape's bounding box in its frame.
    """

    __slots__ = ("kind", "radius", "half", "p0", "p1", "height", "vertices", "lo", "hi")

    def __init__(self, kind: str, *, radius: float = 0.0, half: ArrayLike = (0, 0, 0), p0: ArrayLike = (0, 0, 0),
                 p1: ArrayLike = (0, 0, 0), height: float = 0.0, vertices: ArrayLike | None = None) -> None:
        self.kind = kind
        self.radius = float(radius)
        self.half = np.asarray(half, dtype=float).reshape(3)
        self.p0 = np.asarray(p0, dtype=float).reshape(3)
        self.p1 = np.asarray(p1, dtype=float).reshape(3)
        self.height = float(height)
        self.vertices = np.zeros((0, 3)) if vertices is None else np.asarray(vertices, dtype=float).reshape(-1, 3)
        if kind == "box":
            self.lo, self.hi = -self.half, self.half.copy()
        elif kind == "cylinder":
            self.hi = np.array([self.radius, self.radius, self.height / 2])
            self.lo = -self.hi
        elif kind == "convex":
            self.lo, self.hi = self.vertices.min(axis=0), self.vertices.max(axis=0)
        else:  # sphere (p0 = p1 = 0) and capsule
            self.lo = np.minimum(self.p0, self.p1) - self.radius
            self.hi = np.maximum(self.p0, self.p1) + self.radius

    @classmethod
    def sphere(cls, radius: float) -> CollisionShape:
        """A sphere of ``radius`` (m) centred on its frame."""
        return cls("sphere", radius=_positive(radius, "sphere radius"))

    @classmethod
    def box(cls, size: ArrayLike) -> CollisionShape:
        """A box with edge lengths ``size`` = [x, y, z] (m), centred on its frame."""
        s = np.broadcast_to(np.asarray(size, dtype=float), (3,))
        if np.any(~(s > 0)):
            raise ValueError(f"box size must be three positive lengths, got {s.tolist()}")
        return cls("box", half=s / 2)

    @classmethod
    def cylinder(cls, radius: float, height: float) -> CollisionShape:
        """A solid cylinder of ``radius`` and ``height`` (m) along its frame's z axis, centred."""
        return cls("cylinder", radius=_positive(radius, "cylinder radius"), height=_positive(height, "cylinder height"))

    @classmethod
    def capsule(cls, p0: ArrayLike, p1: ArrayLike, radius: float) -> CollisionShape:
        """The points within ``radius`` of the segment from ``p0`` to ``p1`` ((3,), its frame)."""
        return cls("capsule", radius=_positive(radius, "capsule radius"), p0=p0, p1=p1)

    @classmethod
    def convex(cls, vertices: ArrayLike) -> CollisionShape:
        """The convex hull of ``vertices`` (N, 3) in its frame (only hull vertices are kept)."""
        v = np.asarray(vertices, dtype=float).reshape(-1, 3)
        if len(v) == 0 or not np.all(np.isfinite(v)):
            raise ValueError("a convex shape needs at least one finite vertex")
        v = np.unique(v, axis=0)
        if len(v) > 4:
            from scipy.spatial import ConvexHull, QhullError

            try:
                v = v[ConvexHull(v).vertices]
            except QhullError:  # flat or degenerate: keep every point, the support is still right
                pass
        return cls("convex", vertices=v)

    def __repr__(self) -> str:
        if self.kind == "sphere":
            return f"CollisionShape.sphere({self.radius:g})"
        if self.kind == "box":
            return f"CollisionShape.box({(2 * self.half).tolist()})"
        if self.kind == "cylinder":
            return f"CollisionShape.cylinder({self.radius:g}, {self.height:g})"
        if self.kind == "capsule":
            return f"CollisionShape.capsule({self.p0.tolist()}, {self.p1.tolist()}, {self.radius:g})"
        return f"<CollisionShape.convex of {len(self.vertices)} vertices>"


def _positive(x: float, what: str) -> float:
    x = float(x)
    if not x > 0 or not math.isfinite(x):
        raise ValueError(f"{what} must be a positive number of metres, got {x!r}")
    return x


# -- pairwise queries -------------------------------------------------------------------------
def _core_radius(s: CollisionShape) -> float:
    return s.radius if s.kind in _ROUND else 0.0


def _segment_world(s: CollisionShape, T: Array) -> tuple[tuple[float, ...], tuple[float, ...]]:
    R, t = T[:3, :3], T[:3, 3]
    if s.kind == "sphere":
        p = tuple(t.tolist())
        return p, p
    return tuple((R @ s.p0 + t).tolist()), tuple((R @ s.p1 + t).tolist())


def _support(s: CollisionShape, T: Array) -> Support:
    """World-frame support function of a shape's core (a sphere's centre, a capsule's segment)."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = T[:3, :3].tolist()
    tx, ty, tz = T[:3, 3].tolist()
    if s.kind in _ROUND:
        a, b = _segment_world(s, T)

        def seg(dx: float, dy: float, dz: float) -> tuple[float, float, float]:
            da = dx * a[0] + dy * a[1] + dz * a[2]
            db = dx * b[0] + dy * b[1] + dz * b[2]
            return a if da >= db else b  # type: ignore[return-value]

        return seg
    if s.kind == "box":
        hx, hy, hz = s.half.tolist()

        def box(dx: float, dy: float, dz: float) -> tuple[float, float, float]:
            x = hx if r00 * dx + r10 * dy + r20 * dz >= 0 else -hx
            y = hy if r01 * dx + r11 * dy + r21 * dz >= 0 else -hy
            z = hz if r02 * dx + r12 * dy + r22 * dz >= 0 else -hz
            return (r00 * x + r01 * y + r02 * z + tx, r10 * x + r11 * y + r12 * z + ty, r20 * x + r21 * y + r22 * z + tz)

        return box
    if s.kind == "cylinder":
        rad, hh = s.radius, s.height / 2

        def cyl(dx: float, dy: float, dz: float) -> tuple[float, float, float]:
            lx = r00 * dx + r10 * dy + r20 * dz
            ly = r01 * dx + r11 * dy + r21 * dz
            lz = r02 * dx + r12 * dy + r22 * dz
            n = math.hypot(lx, ly)
            x, y = (rad * lx / n, rad * ly / n) if n > 0.0 else (0.0, 0.0)
            z = hh if lz >= 0 else -hh
            return (r00 * x + r01 * y + r02 * z + tx, r10 * x + r11 * y + r12 * z + ty, r20 * x + r21 * y + r22 * z + tz)

        return cyl
    V = s.vertices @ T[:3, :3].T + T[:3, 3]
    pts = [tuple(p) for p in V.tolist()]
    if len(pts) <= 16:

        def hull_small(dx: float, dy: float, dz: float) -> tuple[float, float, float]:
            return max(pts, key=lambda p: p[0] * dx + p[1] * dy + p[2] * dz)  # type: ignore[return-value]

        return hull_small

    def hull(dx: float, dy: float, dz: float) -> tuple[float, float, float]:
        return pts[int(np.argmax(V @ (dx, dy, dz)))]  # type: ignore[return-value]

    return hull


def _separation(a: CollisionShape, T_a: Array, b: CollisionShape, T_b: Array, stop_above: float = math.inf) -> float:
    """Distance between the shapes (0 if touching or overlapping); may return any value
    greater than ``stop_above`` once it knows the distance is greater."""
    if a.kind in _ROUND and b.kind in _ROUND:
        pa, qa = _segment_world(a, T_a)
        pb, qb = _segment_world(b, T_b)
        return max(segment_segment_distance(pa, qa, pb, qb) - a.radius - b.radius, 0.0)  # type: ignore[arg-type]
    if a.kind == "box" and b.kind in _ROUND:
        a, T_a, b, T_b = b, T_b, a, T_a
    if b.kind == "box" and a.kind in _ROUND:
        pa, qa = _segment_world(a, T_a)
        R, t = T_b[:3, :3], T_b[:3, 3]
        p = ((np.asarray(pa) - t) @ R).tolist()
        q = ((np.asarray(qa) - t) @ R).tolist()
        return max(segment_box_distance(p, q, b.half.tolist()) - a.radius, 0.0)  # type: ignore[arg-type]
    r = _core_radius(a) + _core_radius(b)
    ca = T_a[:3, :3] @ ((a.lo + a.hi) / 2) + T_a[:3, 3]
    cb = T_b[:3, :3] @ ((b.lo + b.hi) / 2) + T_b[:3, 3]
    d = gjk_distance(_support(a, T_a), _support(b, T_b), tuple((ca - cb).tolist()), stop_above + r)  # type: ignore[arg-type]
    return max(d - r, 0.0)


def distance(a: CollisionShape, T_world_a: ArrayLike, b: CollisionShape, T_world_b: ArrayLike) -> float:
    """Separation distance (m) between two shapes at world poses (4, 4); 0 if they touch or overlap."""
    return _separation(a, np.asarray(T_world_a, dtype=float), b, np.asarray(T_world_b, dtype=float))


def intersects(a: CollisionShape, T_world_a: ArrayLike, b: CollisionShape, T_world_b: ArrayLike, *, margin: float = 0.0) -> bool:
    """True if the shapes touch, overlap, or come closer than ``margin`` (m)."""
    Ta = np.asarray(T_world_a, dtype=float)
    Tb = np.asarray(T_world_b, dtype=float)
    return _intersects(a, Ta, b, Tb, float(margin))


def _intersects(a: CollisionShape, Ta: Array, b: CollisionShape, Tb: Array, margin: float) -> bool:
    if a.kind == "box" and b.kind == "box" and margin == 0.0:
        return obb_overlap(a.half, Ta, b.half, Tb, CONTACT_TOL)
    limit = margin + CONTACT_TOL
    return _separation(a, Ta, b, Tb, stop_above=limit) <= limit


# -- shapes from scene nodes ----------------------------------------------------------------
def shape_from_node(node: Any) -> CollisionShape:
    """The collision shape of a scene node, in the node's frame.

    ``Box``, ``Sphere`` and ``Cylinder`` nodes give the exact primitive; any other node
    with solid geometry (a ``MeshNode``, a robot link mesh, an ``Arrow``) gives the convex
    hull of its parts (``T_node_part`` and the node's ``scale`` applied). Raises
    ValueError for nodes with no solid geometry (lines, frames, cameras).
    """
    kind = getattr(node, "kind", None)
    props = getattr(node, "props", {})
    if kind == "box":
        return CollisionShape.box(props["size"])
    if kind == "sphere":
        return CollisionShape.sphere(props["radius"])
    if kind == "cylinder":
        return CollisionShape.cylinder(props["radius"], props["height"])
    pts = []
    for part in node.parts():
        v = part.vertices
        if part.T_node_part is not None:
            v = v @ part.T_node_part[:3, :3].T + part.T_node_part[:3, 3]
        pts.append(v)
    if not pts or sum(len(p) for p in pts) == 0:
        raise ValueError(f"{getattr(node, 'name', node)!r} ({kind}) has no solid geometry to check for collisions")
    return CollisionShape.convex(np.concatenate(pts))


# -- the world of named shapes --------------------------------------------------------------
def _pair(a: str, b: str) -> tuple[str, str]:
    return (a, b) if a <= b else (b, a)


class CollisionWorld:
    """Named shapes with world poses; ``pairs()`` lists the ones in contact.

    ``margin``: shapes closer than this (m) also count as colliding (default 0: touching
    or overlapping). Names are any strings; a pair is reported as ``(a, b)`` with
    ``a < b``, and the list is sorted, so results are deterministic.
    """

    def __init__(self, *, margin: float = 0.0) -> None:
        self.margin = float(margin)
        self._names: list[str] = []
        self._index: dict[str, int] = {}
        self._shapes: list[CollisionShape] = []
        self._poses = np.zeros((0, 4, 4))
        self._centers = np.zeros((0, 3))  # local AABB centre and half size per shape
        self._halves = np.zeros((0, 3))
        self._ignore: set[tuple[str, str]] = set()
        self._ignore_mask = np.zeros((0, 0), dtype=bool)
        self._nodes: dict[str, tuple[Any, int]] = {}  # name -> (scene node, its geom_rev)

    # -- building ---------------------------------------------------------------------------
    def add(self, name: str, shape: CollisionShape, T_world_shape: ArrayLike | None = None) -> None:
        """Add a shape under a new ``name`` at world pose ``T_world_shape`` (4, 4; default identity)."""
        if name in self._index:
            raise ValueError(f"the collision world already has a shape named {name!r}")
        self._index[name] = len(self._names)
        self._names.append(name)
        self._shapes.append(shape)
        T = np.eye(4) if T_world_shape is None else _pose(T_world_shape, name)
        self._poses = np.concatenate([self._poses, T[None]])
        self._centers = np.concatenate([self._centers, ((shape.lo + shape.hi) / 2)[None]])
        self._halves = np.concatenate([self._halves, ((shape.hi - shape.lo) / 2)[None]])
        self._rebuild_mask()

    def remove(self, name: str) -> None:
        """Remove a shape (and the ignored pairs that name it)."""
        i = self._i(name)
        del self._names[i], self._shapes[i]
        self._index = {n: k for k, n in enumerate(self._names)}
        self._poses = np.delete(self._poses, i, axis=0)
        self._centers = np.delete(self._centers, i, axis=0)
        self._halves = np.delete(self._halves, i, axis=0)
        self._ignore = {p for p in self._ignore if name not in p}
        self._nodes.pop(name, None)
        self._rebuild_mask()

    def set_shape(self, name: str, shape: CollisionShape) -> None:
        """Replace the shape of ``name`` (its pose stays)."""
        i = self._i(name)
        self._shapes[i] = shape
        self._centers[i] = (shape.lo + shape.hi) / 2
        self._halves[i] = (shape.hi - shape.lo) / 2

    def set_pose(self, name: str, T_world_shape: ArrayLike) -> None:
        """Move ``name`` to world pose ``T_world_shape`` (4, 4)."""
        self._poses[self._i(name)] = _pose(T_world_shape, name)

    def set_poses(self, poses: Mapping[str, ArrayLike]) -> None:
        """Move several shapes at once: ``{name: T_world_shape (4, 4)}``."""
        for name, T in poses.items():
            self.set_pose(name, T)

    def ignore(self, a: str, b: str) -> None:
        """Never report the pair (a, b), e.g. adjacent robot links that always touch."""
        self._i(a), self._i(b)
        self._ignore.add(_pair(a, b))
        self._rebuild_mask()

    def add_chain(self, names: Sequence[str], points: ArrayLike, radius: float, *, ignore_adjacent: bool = True) -> None:
        """Add capsules ``names[k]`` from ``points[k]`` to ``points[k + 1]`` ((len(names) + 1, 3), world).

        The links of a robot: the points are its joint-frame origins (``fkine_all``).
        Consecutive capsules share a point, so by default their pairs are ignored.
        """
        P = self._chain_points(names, points)
        for k, name in enumerate(names):
            self.add(name, CollisionShape.capsule(P[k], P[k + 1], radius))
        if ignore_adjacent:
            for a, b in zip(names[:-1], names[1:]):
                self.ignore(a, b)

    def set_chain(self, names: Sequence[str], points: ArrayLike) -> None:
        """Move a chain added with :meth:`add_chain` to new points ((len(names) + 1, 3), world)."""
        P = self._chain_points(names, points)
        for k, name in enumerate(names):
            i = self._i(name)
            self.set_shape(name, CollisionShape("capsule", radius=self._shapes[i].radius, p0=P[k], p1=P[k + 1]))
            self._poses[i] = np.eye(4)

    def add_node(self, node: Any, *, name: str | None = None) -> str:
        """Add a scene node's shape (:func:`shape_from_node`) at its world pose; :meth:`sync` follows it."""
        key = node.name if name is None else name
        self.add(key, shape_from_node(node), node.T_world())
        self._nodes[key] = (node, node.geom_rev)
        return key

    def add_world(self, world: Any, names: Iterable[str] | None = None) -> list[str]:
        """Add every solid node of a scene ``World`` (or just ``names``); returns the names added.

        Nodes with no solid geometry (frames, lines, cameras, groups) are left out.
        """
        added = []
        for node in world.walk() if names is None else (world[n] for n in names):
            if node.kind in ("box", "sphere", "cylinder") or node.parts():
                added.append(self.add_node(node))
        return added

    def follow_world(self, world: Any) -> None:
        """Track every visible solid node of a scene ``World``: add new ones, drop removed or
        hidden ones, ignore each node against its direct parent (a grasped object and the
        gripper, nested robot links), then :meth:`sync`. Shapes added by hand stay as they are."""
        wanted = {}
        for node in world.walk():
            if world.is_visible(node) and (node.kind in ("box", "sphere", "cylinder") or node.parts()):
                wanted[node.name] = node
        for key in [k for k, (node, _) in self._nodes.items() if wanted.get(k) is not node]:
            self.remove(key)
        for key, node in wanted.items():
            if key not in self._nodes:
                if key in self._index:
                    raise ValueError(f"the collision world already has a shape named {key!r} that is not the scene node")
                self.add_node(node)
        ignore = {_pair(k, node.parent.name) for k, node in wanted.items() if node.parent is not None and node.parent.name in wanted}
        stale = {p for p in self._ignore if p[0] in self._nodes and p[1] in self._nodes} - ignore
        if ignore - self._ignore or stale:
            self._ignore = (self._ignore - stale) | ignore
            self._rebuild_mask()
        self.sync()

    def sync(self) -> None:
        """Update the shapes added from scene nodes to the nodes' current poses and sizes."""
        for key, (node, rev) in self._nodes.items():
            if node.geom_rev != rev:
                self.set_shape(key, shape_from_node(node))
                self._nodes[key] = (node, node.geom_rev)
            self._poses[self._index[key]] = node.T_world()

    # -- queries ----------------------------------------------------------------------------
    @property
    def names(self) -> list[str]:
        """The shape names, in the order they were added."""
        return list(self._names)

    def shape(self, name: str) -> CollisionShape:
        """The shape called ``name``."""
        return self._shapes[self._i(name)]

    def pose(self, name: str) -> Array:
        """World pose (4, 4) of ``name``."""
        return self._poses[self._i(name)].copy()

    def candidates(self, margin: float | None = None) -> list[tuple[int, int]]:
        """Index pairs (i < j) whose world bounding boxes come within ``margin`` (broad phase)."""
        m = self.margin if margin is None else float(margin)
        n = len(self._names)
        if n < 2:
            return []
        R = self._poses[:, :3, :3]
        c = np.einsum("nij,nj->ni", R, self._centers) + self._poses[:, :3, 3]
        h = np.einsum("nij,nj->ni", np.abs(R), self._halves) + (m / 2 + CONTACT_TOL)
        lo, hi = c - h, c + h
        over = np.all((lo[:, None, :] <= hi[None, :, :]) & (lo[None, :, :] <= hi[:, None, :]), axis=2)
        over &= ~self._ignore_mask
        i, j = np.nonzero(np.triu(over, 1))
        return list(zip(i.tolist(), j.tolist()))

    def pairs(self, *, margin: float | None = None) -> list[tuple[str, str]]:
        """The colliding pairs, sorted: each ``(a, b)`` with ``a < b``; ignored pairs left out."""
        m = self.margin if margin is None else float(margin)
        out = []
        for i, j in self.candidates(m):
            if _intersects(self._shapes[i], self._poses[i], self._shapes[j], self._poses[j], m):
                out.append(_pair(self._names[i], self._names[j]))
        out.sort()
        return out

    def colliding(self, name: str, *, margin: float | None = None) -> list[str]:
        """Sorted names of the shapes in contact with ``name``."""
        self._i(name)
        return sorted({b if a == name else a for a, b in self.pairs(margin=margin) if name in (a, b)})

    def in_collision(self, *, margin: float | None = None) -> bool:
        """True if any pair (not ignored) is in contact."""
        m = self.margin if margin is None else float(margin)
        return any(
            _intersects(self._shapes[i], self._poses[i], self._shapes[j], self._poses[j], m) for i, j in self.candidates(m)
        )

    def distance(self, a: str, b: str) -> float:
        """Separation distance (m) between two named shapes; 0 if they touch or overlap."""
        i, j = self._i(a), self._i(b)
        return _separation(self._shapes[i], self._poses[i], self._shapes[j], self._poses[j])

    # -- helpers ----------------------------------------------------------------------------
    def _i(self, name: str) -> int:
        try:
            return self._index[name]
        except KeyError:
            import difflib

            close = difflib.get_close_matches(name, self._names, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise KeyError(f"no collision shape named {name!r}{hint}") from None

    def _rebuild_mask(self) -> None:
        n = len(self._names)
        mask = np.zeros((n, n), dtype=bool)
        for a, b in self._ignore:
            i, j = self._index[a], self._index[b]
            mask[i, j] = mask[j, i] = True
        self._ignore_mask = mask

    def _chain_points(self, names: Sequence[str], points: ArrayLike) -> Array:
        P = np.asarray(points, dtype=float)
        if P.ndim != 2 or P.shape[1] != 3 or len(P) != len(names) + 1:
            raise ValueError(f"a chain of {len(names)} links needs ({len(names) + 1}, 3) points, got shape {P.shape}")
        return P

    def __len__(self) -> int:
        return len(self._names)

    def __repr__(self) -> str:
        return f"<CollisionWorld of {len(self._names)} shapes>"


_FOLLOWERS: weakref.WeakKeyDictionary[Any, CollisionWorld] = weakref.WeakKeyDictionary()


def collisions(world: Any, *, margin: float = 0.0, ignore: Iterable[tuple[str, str]] = ()) -> list[tuple[str, str]]:
    """The pairs of visible solid scene nodes in contact, sorted, as ``(a, b)`` with ``a < b``.

    What model code gets from ``collisions()``. Boxes, spheres and cylinders collide as
    exact primitives, every other solid node (meshes, robot links) as the convex hull of
    its geometry. A node never collides with its direct parent; ``ignore`` names more
    pairs to leave out; ``margin`` (m) also reports pairs closer than that. The checker
    kept for each world is updated incrementally, so calling this every frame is cheap.
    """
    cw = _FOLLOWERS.get(world)
    if cw is None:
        cw = _FOLLOWERS[world] = CollisionWorld()
    cw.follow_world(world)
    skip = {_pair(a, b) for a, b in ignore}
    return [p for p in cw.pairs(margin=margin) if p not in skip]


def _pose(T: ArrayLike, name: str) -> Array:
    M = np.asarray(T, dtype=float)
    if M.shape != (4, 4) or not np.all(np.isfinite(M)):
        raise ValueError(f"the pose of {name!r} must be a finite 4x4 matrix, got shape {M.shape}")
    return M
