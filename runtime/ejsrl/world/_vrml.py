"""A reader for VRML97 (ISO/IEC 14772-1) geometry: the subset that robot models use.

``read_vrml(path)`` parses the file into a small tree of :class:`VNode` and walks it,
returning the triangle parts in the file's frame (every ``Transform`` already applied to
the vertices) and the sorted names of the node types it skipped.

Supported: ``Transform`` (``translation``, ``rotation``, ``scale``, ``scaleOrientation``,
``center``), ``Group``, ``Anchor``, ``Collision``, ``Billboard`` (as a group), ``Switch``
(``whichChoice``), ``LOD`` (first level), ``Shape`` with ``Appearance``/``Material``
(``diffuseColor``, ``transparency``), ``IndexedFaceSet`` (``coord``, ``coordIndex``,
``ccw``, ``color``, ``colorIndex``, ``colorPerVertex``; ``solid``, ``convex``,
``creaseAngle``, normals and texture coordinates are read and ignored), the ``Box``,
``Sphere``, ``Cylinder`` and ``Cone`` primitives (VRML axes: cylinders and cones along
+y), ``DEF``/``USE``, ``ROUTE`` (ignored) and ``PROTO``/``EXTERNPROTO`` declarations
(skipped; their instances count as unsupported nodes).

Errors are :class:`~ejsrl.world.mesh.MeshFormatError` with ``path:LINE:COL: message``.
"""

from __future__ import annotations

import bisect
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ejsrl.world.mesh import MeshFormatError, MeshPart

__all__ = ["read_vrml", "parse_vrml", "VNode", "vrml_transform"]

Array = NDArray[np.float64]

#: node types that hold children in a ``children`` field and apply no transform
_GROUPS = {"Group", "Anchor", "Collision", "Billboard"}
#: node types read without a warning because they never change the geometry
_SILENT = {"WorldInfo", "NavigationInfo", "Normal", "TextureCoordinate"}
#: sections of the tessellated round primitives
CIRCLE_SECTIONS = 32
SPHERE_SUBDIVISIONS = 2

_SKIP = re.compile(r"(?:[\s,]+|#[^\n\r]*)*")
_NUMBER = re.compile(r"[+\-]?(?:0[xX][0-9a-fA-F]+|(?:\d+\.?\d*|\.\d+)(?:[eE][+\-]?\d+)?)")
_IDENT = re.compile(r"[^\x00-\x20\"'#,.\[\]\\{}0-9+\-][^\x00-\x20\"'#,.\[\]\\{}]*")
_STRING = re.compile(r'"((?:[^"\\]|\\.)*)"', re.S)
_NUMERIC_LIST = re.compile(r"\[([\s,0-9eE.+\-]*)\]")


@dataclass
class VNode:
    """One parsed VRML node: its ``type``, its ``fields`` (name -> value) and where it starts.

    Field values are: ``np.ndarray`` (a run of numbers, flat), ``bool``, ``str``,
    ``list`` (of strings or of nodes), ``VNode`` or ``None`` (``NULL``).
    ``field_pos`` keeps each field's offset in the file for error messages.
    """

    type: str
    pos: int
    fields: dict[str, Any] = field(default_factory=dict)
    field_pos: dict[str, int] = field(default_factory=dict)
    def_name: str | None = None


class _Parser:
    def __init__(self, text: str, path: str) -> None:
        self.text = text
        self.path = path
        self.pos = 0
        self.defs: dict[str, VNode] = {}
        self.protos: set[str] = set()
        self._line_starts = [0] + [m.end() for m in re.finditer(r"\r\n|\n|\r", text)]

    # -- positions and errors ---------------------------------------------------------
    def where(self, pos: int) -> tuple[int, int]:
        line = bisect.bisect_right(self._line_starts, pos)
        return line, pos - self._line_starts[line - 1] + 1

    def error(self, message: str, pos: int | None = None) -> MeshFormatError:
        line, col = self.where(self.pos if pos is None else pos)
        return MeshFormatError(f"{self.path}:{line}:{col}: {message}")

    # -- tokens -------------------------------------------------------------------------
    def skip(self) -> None:
        self.pos = _SKIP.match(self.text, self.pos).end()

    def peek(self) -> str:
        """The next token's first character ('' at the end), after whitespace."""
        self.skip()
        return self.text[self.pos : self.pos + 1]

    def describe_next(self) -> str:
        self.skip()
        if self.pos >= len(self.text):
            return "the end of the file"
        for rx in (_IDENT, _NUMBER, _STRING):
            m = rx.match(self.text, self.pos)
            if m:
                return repr(m.group(0)[:30])
        return repr(self.text[self.pos])

    def expect(self, ch: str, what: str) -> None:
        if self.peek() != ch:
            raise self.error(f"expected '{ch}' {what}, found {self.describe_next()}")
        self.pos += 1

    def ident(self, what: str) -> str:
        self.skip()
        m = _IDENT.match(self.text, self.pos)
        if not m:
            raise self.error(f"expected {what}, found {self.describe_next()}")
        self.pos = m.end()
        return m.group(0)

    def try_ident(self) -> str | None:
        self.skip()
        m = _IDENT.match(self.text, self.pos)
        return m.group(0) if m else None

    # -- grammar ------------------------------------------------------------------------
    def parse_file(self) -> list[VNode]:
        nodes: list[VNode] = []
        while True:
            self.skip()
            if self.pos >= len(self.text):
                return nodes
            word = self.try_ident()
            if word == "ROUTE":
                self.parse_route()
            elif word in ("PROTO", "EXTERNPROTO"):
                self.parse_proto(word)
            elif word is None:
                raise self.error(f"expected a node, found {self.describe_next()}")
            else:
                node = self.parse_node()
                if node is not None:
                    nodes.append(node)

    def parse_route(self) -> None:
        self.ident("ROUTE")
        for what in ("a node name", "'.'", "an event name", "TO", "a node name", "'.'", "an event name"):
            if what == "'.'":
                self.expect(".", "in ROUTE")
            elif what == "TO":
                if self.ident("TO") != "TO":
                    raise self.error("expected TO in ROUTE")
            else:
                self.ident(what)

    def parse_proto(self, word: str) -> None:
        self.ident(word)
        self.protos.add(self.ident("a PROTO name"))
        self.skip_balanced("[", "]")
        if word == "PROTO":
            self.skip_balanced("{", "}")
        else:
            self.parse_value("url")

    def skip_balanced(self, open_ch: str, close_ch: str) -> None:
        start = self.pos
        self.expect(open_ch, "")
        depth = 1
        while depth:
            self.skip()
            if self.pos >= len(self.text):
                raise self.error(f"'{open_ch}' is never closed", start)
            ch = self.text[self.pos]
            if ch == '"':
                m = _STRING.match(self.text, self.pos)
                if not m:
                    raise self.error("unterminated string")
                self.pos = m.end()
                continue
            if ch == open_ch:
                depth += 1
            elif ch == close_ch:
                depth -= 1
            self.pos += 1

    def parse_node(self) -> VNode | None:
        """A node statement: ``DEF name Type {...}``, ``USE name``, ``Type {...}`` or NULL."""
        start = self.pos
        word = self.ident("a node type")
        if word == "NULL":
            return None
        if word == "USE":
            self.skip()
            name_pos = self.pos
            name = self.ident("a DEF name after USE")
            if name not in self.defs:
                known = ", ".join(sorted(self.defs)) or "none"
                raise self.error(f"USE of {name!r}, which no DEF before it names (DEF names so far: {known})", name_pos)
            return self.defs[name]
        def_name = None
        if word == "DEF":
            def_name = self.ident("a name after DEF")
            start = self.pos + len(_SKIP.match(self.text, self.pos).group(0))
            word = self.ident("a node type after DEF")
        node = VNode(word, start, def_name=def_name)
        if word in ("Script",) or word in self.protos:
            # interface declarations (eventIn SFTime t ...) are not plain fields
            self.skip_balanced("{", "}")
        else:
            self.expect("{", f"after the node type {word}")
            while True:
                ch = self.peek()
                if ch == "}":
                    self.pos += 1
                    break
                if ch == "":
                    raise self.error(f"the {word} node that starts here is never closed with '}}'", start)
                fpos = self.pos
                fname = self.ident(f"a field name or '}}' in {word}")
                if fname == "ROUTE":
                    self.pos = fpos
                    self.parse_route()
                    continue
                if fname in ("PROTO", "EXTERNPROTO"):
                    self.pos = fpos
                    self.parse_proto(fname)
                    continue
                node.fields[fname] = self.parse_value(fname)
                node.field_pos[fname] = fpos
        if def_name is not None:
            self.defs[def_name] = node
        return node

    def parse_value(self, fname: str) -> Any:
        ch = self.peek()
        if ch == "[":
            m = _NUMERIC_LIST.match(self.text, self.pos)
            if m:
                try:
                    values = np.array(m.group(1).replace(",", " ").split(), dtype=float)
                except ValueError:
                    pass
                else:
                    self.pos = m.end()
                    return values
            return self.parse_list(fname)
        if ch == '"':
            return self.string()
        word = self.try_ident()
        if word is not None:
            if word == "TRUE" or word == "FALSE":
                self.pos += len(word)
                return word == "TRUE"
            return self.parse_node()
        nums = self.numbers()
        if not nums:
            raise self.error(f"expected a value for the field {fname!r}, found {self.describe_next()}")
        return np.array(nums, dtype=float)

    def parse_list(self, fname: str) -> Any:
        start = self.pos
        self.pos += 1
        nums: list[float] = []
        items: list[Any] = []
        while True:
            ch = self.peek()
            if ch == "]":
                self.pos += 1
                break
            if ch == "":
                raise self.error(f"the list of {fname!r} that starts here is never closed with ']'", start)
            if ch == '"':
                items.append(self.string())
                continue
            word = self.try_ident()
            if word is not None:
                if word in ("TRUE", "FALSE"):
                    self.pos += len(word)
                    items.append(word == "TRUE")
                    continue
                if word == "ROUTE":
                    self.parse_route()
                    continue
                if word in ("PROTO", "EXTERNPROTO"):
                    self.parse_proto(word)
                    continue
                node = self.parse_node()
                if node is not None:
                    items.append(node)
                continue
            got = self.numbers()
            if not got:
                raise self.error(f"unexpected {self.describe_next()} in the list of {fname!r}")
            nums.extend(got)
        if nums and items:
            raise self.error(f"the list of {fname!r} mixes numbers with other values", start)
        return np.array(nums, dtype=float) if nums or not items else items

    def numbers(self) -> list[float]:
        out: list[float] = []
        while True:
            self.skip()
            m = _NUMBER.match(self.text, self.pos)
            if not m:
                return out
            end = m.end()
            if end < len(self.text) and not (self.text[end].isspace() or self.text[end] in ",]}#["):
                raise self.error(f"malformed number {self.describe_next()}")
            tok = m.group(0)
            out.append(float(int(tok, 16)) if "x" in tok or "X" in tok else float(tok))
            self.pos = end

    def string(self) -> str:
        m = _STRING.match(self.text, self.pos)
        if not m:
            raise self.error("unterminated string")
        self.pos = m.end()
        return re.sub(r"\\(.)", r"\1", m.group(1))


def parse_vrml(text: str, path: str = "<string>") -> tuple[list[VNode], _Parser]:
    """Parse VRML97 text (with its ``#VRML V2.0 utf8`` header) into top-level nodes."""
    first = text.split("\n", 1)[0].rstrip("\r")
    p = _Parser(text, path)
    if not first.startswith("#VRML"):
        raise p.error("not a VRML97 file: the first line must be '#VRML V2.0 utf8'", 0)
    if not first.startswith("#VRML V2.0"):
        raise p.error(f"only VRML97 ('#VRML V2.0 utf8') is supported, this file says {first[:30]!r}", 0)
    return p.parse_file(), p


# -- geometry ------------------------------------------------------------------------------


def _rotation(axis_angle: Array) -> Array:
    """(3, 3) rotation of ``angle`` about ``axis`` (Rodrigues); identity for a zero axis."""
    axis = np.asarray(axis_angle[:3], dtype=float)
    angle = float(axis_angle[3])
    n = float(np.linalg.norm(axis))
    if n < 1e-12 or angle == 0.0:
        return np.eye(3)
    x, y, z = axis / n
    K = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * (K @ K)


def vrml_transform(
    translation: Array = (0, 0, 0),
    rotation: Array = (0, 0, 1, 0),
    scale: Array = (1, 1, 1),
    scale_orientation: Array = (0, 0, 1, 0),
    center: Array = (0, 0, 0),
) -> Array:
    """(4, 4) matrix of a VRML ``Transform``: ``T * C * R * SR * S * -SR * -C`` (ISO 14772 6.52)."""

    def h(R: Array | None = None, t: Array | None = None, s: Array | None = None) -> Array:
        M = np.eye(4)
        if R is not None:
            M[:3, :3] = R
        if s is not None:
            M[:3, :3] = np.diag(s)
        if t is not None:
            M[:3, 3] = t
        return M

    SR = _rotation(np.asarray(scale_orientation, dtype=float))
    c = np.asarray(center, dtype=float)
    return (
        h(t=np.asarray(translation, dtype=float))
        @ h(t=c)
        @ h(R=_rotation(np.asarray(rotation, dtype=float)))
        @ h(R=SR)
        @ h(s=np.asarray(scale, dtype=float))
        @ h(R=SR.T)
        @ h(t=-c)
    )


def _box(size: Array) -> tuple[Array, NDArray[np.int64]]:
    v = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]) * size
    f = np.array(
        [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
         [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    )
    return v, f


def _sphere(radius: float) -> tuple[Array, NDArray[np.int64]]:
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=SPHERE_SUBDIVISIONS, radius=radius)
    return np.asarray(m.vertices), np.asarray(m.faces)


def _round(r_bottom: float, r_top: float, height: float, side: bool, bottom: bool, top: bool) -> tuple[Array, NDArray[np.int64]]:
    """A cylinder (or a cone when ``r_top`` is 0) along +y, centred, outward winding."""
    n = CIRCLE_SECTIONS
    a = 2 * np.pi * np.arange(n) / n
    # VRML: angle 0 on +z... any start works; x = sin, z = cos keeps the ring CCW seen from +y
    ring = np.column_stack([np.sin(a), np.zeros(n), np.cos(a)])
    y0, y1 = -height / 2, height / 2
    verts = [ring * r_bottom + (0, y0, 0)]
    cone = r_top == 0.0
    verts.append(np.array([[0.0, y1, 0.0]]) if cone else ring * r_top + (0, y1, 0))
    verts.append(np.array([[0.0, y0, 0.0], [0.0, y1, 0.0]]))  # cap centres
    v = np.concatenate(verts)
    i = np.arange(n)
    j = (i + 1) % n
    top0 = n
    cb, ct = (2 * n, 2 * n + 1) if not cone else (n + 1, n + 2)
    faces = []
    if side:
        if cone:
            faces.append(np.column_stack([i, j, np.full(n, top0)]))
        else:
            faces.append(np.column_stack([i, j, top0 + j]))
            faces.append(np.column_stack([i, top0 + j, top0 + i]))
    if bottom:
        faces.append(np.column_stack([np.full(n, cb), j, i]))
    if top and not cone:
        faces.append(np.column_stack([np.full(n, ct), top0 + i, top0 + j]))
    f = np.concatenate(faces) if faces else np.zeros((0, 3), dtype=np.int64)
    return v, f


def _polygon_triangles(poly: list[int], pts: Array) -> list[tuple[int, int, int]]:
    """Triangulate one polygon (vertex indices into ``pts``): a fan if convex, else ear clipping."""
    n = len(poly)
    if n == 3:
        return [(poly[0], poly[1], poly[2])]
    P = pts[poly]
    normal = np.zeros(3)
    for k in range(n):  # Newell's normal
        a, b = P[k], P[(k + 1) % n]
        normal += ((a[1] - b[1]) * (a[2] + b[2]), (a[2] - b[2]) * (a[0] + b[0]), (a[0] - b[0]) * (a[1] + b[1]))
    axis = int(np.argmax(np.abs(normal)))
    if normal[axis] == 0.0:
        return [(poly[0], poly[k], poly[k + 1]) for k in range(1, n - 1)]
    u, w = [(1, 2), (2, 0), (0, 1)][axis]
    xy = P[:, [u, w]] * (1.0 if normal[axis] > 0 else -1.0, 1.0)  # CCW in 2D
    e1 = np.roll(xy, -1, axis=0) - xy
    e0 = xy - np.roll(xy, 1, axis=0)
    turns = e0[:, 0] * e1[:, 1] - e0[:, 1] * e1[:, 0]
    if np.all(turns >= -1e-12 * np.abs(turns).max()):
        return [(poly[0], poly[k], poly[k + 1]) for k in range(1, n - 1)]
    return _ear_clip(poly, xy)


def _ear_clip(poly: list[int], xy: Array) -> list[tuple[int, int, int]]:
    idx = list(range(len(poly)))
    tris: list[tuple[int, int, int]] = []

    def cross(o: Array, a: Array, b: Array) -> float:
        return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))

    guard = 0
    while len(idx) > 3 and guard < 10 * len(poly) ** 2:
        guard += 1
        m = len(idx)
        for k in range(m):
            i0, i1, i2 = idx[k - 1], idx[k], idx[(k + 1) % m]
            a, b, c = xy[i0], xy[i1], xy[i2]
            if cross(a, b, c) <= 0:
                continue  # reflex or degenerate corner
            ok = True
            for j in idx:
                if j in (i0, i1, i2):
                    continue
                p = xy[j]
                if cross(a, b, p) >= 0 and cross(b, c, p) >= 0 and cross(c, a, p) >= 0:
                    ok = False
                    break
            if ok:
                tris.append((poly[i0], poly[i1], poly[i2]))
                idx.pop(k)
                break
        else:  # no ear (self-intersecting or degenerate polygon): fan the rest
            break
    tris.extend((poly[idx[0]], poly[idx[k]], poly[idx[k + 1]]) for k in range(1, len(idx) - 1))
    return tris


class _Builder:
    def __init__(self, parser: _Parser) -> None:
        self.p = parser
        self.parts: list[MeshPart] = []
        self.skipped: set[str] = set()

    def num(self, node: VNode, name: str, default: Any, count: int | None = None) -> Any:
        if name not in node.fields:
            return default
        value = node.fields[name]
        if isinstance(value, bool) and count is None and isinstance(default, bool):
            return value
        if isinstance(default, bool):
            raise self.p.error(f"{node.type}.{name} must be TRUE or FALSE", node.field_pos[name])
        if not isinstance(value, np.ndarray) or (count is not None and value.size != count):
            want = f"{count} numbers" if count else "numbers"
            got = f"{value.size} numbers" if isinstance(value, np.ndarray) else type(value).__name__
            raise self.p.error(f"{node.type}.{name} needs {want}, got {got}", node.field_pos[name])
        return value if count != 1 else float(value[0])

    def node_field(self, node: VNode, name: str) -> VNode | None:
        value = node.fields.get(name)
        if value is None or isinstance(value, VNode):
            return value
        if isinstance(value, list) and len(value) == 1 and isinstance(value[0], VNode):
            return value[0]
        raise self.p.error(f"{node.type}.{name} must be a node", node.field_pos[name])

    def children(self, node: VNode, name: str = "children") -> list[VNode]:
        value = node.fields.get(name, [])
        if value is None:
            return []
        if isinstance(value, VNode):
            return [value]
        if isinstance(value, np.ndarray) and value.size == 0:
            return []
        if isinstance(value, list) and all(isinstance(v, VNode) for v in value):
            return value
        raise self.p.error(f"{node.type}.{name} must be a list of nodes", node.field_pos[name])

    # -- walking ----------------------------------------------------------------------
    def walk(self, node: VNode, M: Array) -> None:
        t = node.type
        if t == "Transform":
            L = vrml_transform(
                self.num(node, "translation", (0, 0, 0), 3),
                self.num(node, "rotation", (0, 0, 1, 0), 4),
                self.num(node, "scale", (1, 1, 1), 3),
                self.num(node, "scaleOrientation", (0, 0, 1, 0), 4),
                self.num(node, "center", (0, 0, 0), 3),
            )
            for c in self.children(node):
                self.walk(c, M @ L)
        elif t in _GROUPS:
            for c in self.children(node):
                self.walk(c, M)
        elif t == "Switch":
            choice = self.children(node, "choice")
            k = int(self.num(node, "whichChoice", -1.0, 1))
            if 0 <= k < len(choice):
                self.walk(choice[k], M)
        elif t == "LOD":
            level = self.children(node, "level")
            if level:
                self.walk(level[0], M)
        elif t == "Shape":
            self.shape(node, M)
        elif t not in _SILENT:
            self.skipped.add(t)

    def shape(self, node: VNode, M: Array) -> None:
        rgb: Array | None = None
        opacity = 1.0
        app = self.node_field(node, "appearance")
        if app is not None:
            if app.type != "Appearance":
                raise self.p.error(f"Shape.appearance must be an Appearance node, not {app.type}", app.pos)
            for key in app.fields:
                if key not in ("material", "texture", "textureTransform"):
                    raise self.p.error(f"Appearance has no field {key!r}", app.field_pos[key])
            mat = self.node_field(app, "material")
            if mat is not None:
                if mat.type != "Material":
                    raise self.p.error(f"Appearance.material must be a Material node, not {mat.type}", mat.pos)
                rgb = np.clip(self.num(mat, "diffuseColor", np.array([0.8, 0.8, 0.8]), 3), 0.0, 1.0)
                opacity = 1.0 - float(np.clip(self.num(mat, "transparency", 0.0, 1), 0.0, 1.0))
            for key in ("texture", "textureTransform"):
                tex = self.node_field(app, key)
                if tex is not None:
                    self.skipped.add(tex.type)
        geom = self.node_field(node, "geometry")
        if geom is None:
            return
        face_rgb = None
        g = geom.type
        if g == "Box":
            size = self.num(geom, "size", np.array([2.0, 2.0, 2.0]), 3)
            if np.any(size <= 0):
                raise self.p.error("Box.size must be positive", geom.field_pos["size"])
            v, f = _box(size)
        elif g == "Sphere":
            v, f = _sphere(self.positive(geom, "radius", 1.0))
        elif g == "Cylinder":
            v, f = _round(
                self.positive(geom, "radius", 1.0), self.positive(geom, "radius", 1.0), self.positive(geom, "height", 2.0),
                self.num(geom, "side", True), self.num(geom, "bottom", True), self.num(geom, "top", True),
            )
        elif g == "Cone":
            v, f = _round(
                self.positive(geom, "bottomRadius", 1.0), 0.0, self.positive(geom, "height", 2.0),
                self.num(geom, "side", True), self.num(geom, "bottom", True), False,
            )
        elif g == "IndexedFaceSet":
            v, f, face_rgb = self.face_set(geom)
        else:
            self.skipped.add(g)
            return
        if len(f) == 0:
            return
        v = v @ M[:3, :3].T + M[:3, 3]
        if np.linalg.det(M[:3, :3]) < 0:  # a mirroring transform turns faces inside out
            f = f[:, ::-1]
        self.parts.append(MeshPart(v, f, None if face_rgb is not None else rgb, face_rgb=face_rgb, opacity=opacity, name=node.def_name))

    def positive(self, node: VNode, name: str, default: float) -> float:
        value = self.num(node, name, default, 1)
        if not value > 0:
            raise self.p.error(f"{node.type}.{name} must be positive, got {value:g}", node.field_pos[name])
        return float(value)

    def face_set(self, geom: VNode) -> tuple[Array, NDArray[np.int64], Array | None]:
        coord = self.node_field(geom, "coord")
        if coord is None:
            return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), None
        if coord.type != "Coordinate":
            raise self.p.error(f"IndexedFaceSet.coord must be a Coordinate node, not {coord.type}", coord.pos)
        pts = self.num(coord, "point", np.zeros(0))
        if pts.size % 3:
            raise self.p.error(f"Coordinate.point needs x y z triples, got {pts.size} numbers", coord.field_pos["point"])
        pts = pts.reshape(-1, 3)
        index = self.num(geom, "coordIndex", np.zeros(0)).astype(np.int64)
        ipos = geom.field_pos.get("coordIndex", geom.pos)
        if index.size and (index.max() >= len(pts) or index.min() < -1):
            bad = int(index[(index >= len(pts)) | (index < -1)][0])
            raise self.p.error(f"coordIndex {bad} is out of range: the Coordinate node has {len(pts)} points", ipos)
        starts, lengths = _split(index)
        # triangles go straight through; larger polygons are triangulated one by one
        k3 = np.flatnonzero(lengths == 3)
        corner_parts = [starts[k3, None] + np.arange(3)]
        owner_parts = [k3]
        for k in np.flatnonzero(lengths > 3).tolist():
            s0 = int(starts[k])
            poly = index[s0 : s0 + lengths[k]]
            local = np.array(_polygon_triangles(list(range(len(poly))), pts[poly]), dtype=np.int64).reshape(-1, 3)
            corner_parts.append(s0 + local)
            owner_parts.append(np.full(len(local), k))
        owner = np.concatenate(owner_parts)
        order = np.argsort(owner, kind="stable")  # faces in the file's polygon order
        owner = owner[order]
        corners = np.concatenate(corner_parts).astype(np.int64)[order]
        f = index[corners] if len(corners) else np.zeros((0, 3), dtype=np.int64)
        if not self.num(geom, "ccw", True):
            f = f[:, ::-1]
        face_rgb = self.face_colors(geom, len(starts), owner, corners, index)
        return pts, f, face_rgb

    def face_colors(self, geom: VNode, n_polys: int, owner: NDArray[np.int64], corners: NDArray[np.int64], index: NDArray[np.int64]) -> Array | None:
        color = self.node_field(geom, "color")
        if color is None:
            return None
        if color.type != "Color":
            raise self.p.error(f"IndexedFaceSet.color must be a Color node, not {color.type}", color.pos)
        cols = self.num(color, "color", np.zeros(0))
        if cols.size % 3:
            raise self.p.error(f"Color.color needs r g b triples, got {cols.size} numbers", color.field_pos["color"])
        cols = np.clip(cols.reshape(-1, 3), 0.0, 1.0)
        cindex = self.num(geom, "colorIndex", np.zeros(0)).astype(np.int64)
        cpos = geom.field_pos.get("colorIndex", color.pos)
        per_vertex = self.num(geom, "colorPerVertex", True)
        if not per_vertex:
            which = cindex if cindex.size else np.arange(n_polys)
            if len(which) < n_polys:
                raise self.p.error(f"colorPerVertex FALSE needs a colour for each of the {n_polys} faces, got {len(which)}", cpos)
            which = which[:n_polys]
            if which.size and (which.max() >= len(cols) or which.min() < 0):
                raise self.p.error(f"colour index out of range: the Color node has {len(cols)} colours", cpos)
            return cols[which[owner]]
        if cindex.size:
            if cindex.size < index.size:
                raise self.p.error("colorIndex must have an entry for each entry of coordIndex", cpos)
            which = cindex[: index.size]
        else:
            which = index
        per_corner = which[corners] if len(corners) else np.zeros((0, 3), dtype=np.int64)
        if per_corner.size and (per_corner.max() >= len(cols) or per_corner.min() < 0):
            raise self.p.error(f"colour index out of range: the Color node has {len(cols)} colours", cpos)
        return cols[per_corner].mean(axis=1)


def _split(index: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Start offsets and lengths of the polygons of a ``coordIndex`` list (``-1`` ends each)."""
    ends = np.flatnonzero(index == -1)
    starts = np.concatenate([[0], ends + 1])
    stops = np.concatenate([ends, [len(index)]])
    if starts[-1] == len(index):  # nothing after the last -1
        starts, stops = starts[:-1], stops[:-1]
    return starts.astype(np.int64), (stops - starts).astype(np.int64)


def read_vrml(path: str | Path) -> tuple[list[MeshPart], list[str]]:
    """Read a VRML97 file: its parts in the file frame and the node types it skipped."""
    raw = Path(path).read_bytes()
    if raw[:2] == b"\x1f\x8b":  # .wrz / gzipped .wrl
        import gzip

        raw = gzip.decompress(raw)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise MeshFormatError(f"{path}:1:1: not UTF-8 text ({e.reason} at byte {e.start})") from None
    nodes, parser = parse_vrml(text, str(path))
    b = _Builder(parser)
    for node in nodes:
        b.walk(node, np.eye(4))
    return b.parts, sorted(b.skipped)
