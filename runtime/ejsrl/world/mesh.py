"""Mesh import: triangle parts from OBJ, STL, PLY, GLB/glTF, OFF (via trimesh) and VRML97.

``load_mesh(path)`` returns a list of :class:`MeshPart` (a :class:`~ejsrl.world.scene.Part`
that also keeps its ``opacity`` and source ``name``), ready for ``MeshNode(mesh_parts=...)``.
Every transform in the file (a glTF node's pose, a VRML ``Transform``) is already applied to
the vertices, so each part's vertices are in the file's frame and ``T_node_part`` is None.

Colours: a part takes the file's colour as ``rgb`` when the whole part has one colour
(an OBJ ``.mtl`` ``Kd``, a glTF ``baseColorFactor``, a VRML ``Material.diffuseColor``),
or ``face_rgb`` (F, 3) when faces differ (PLY face or vertex colours, VRML ``Color``
nodes; vertex colours are averaged over each face); trimesh reads no colours from OFF.
A part with no colour in the file has ``rgb = None`` and ``face_rgb = None``, so the node's own ``color`` shows.

Problems: a missing file raises ``FileNotFoundError``; an unknown extension or a file that
cannot be parsed raises :class:`MeshFormatError` (a ``ValueError``) whose message starts
with the path (``path:LINE:COL:`` for VRML). VRML nodes that the reader does not support
(``Viewpoint``, ``PointLight``, ``Background``, ``TimeSensor``, ``Script``, ``Inline``, ...)
are skipped, with one :class:`MeshImportWarning` per file that names them all.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ejsrl.world.scene import Part

__all__ = ["load_mesh", "MeshPart", "MeshFormatError", "MeshImportWarning", "MESH_FORMATS"]

#: the file extensions read through trimesh (besides ``.wrl``/``.wrz``, read by our VRML97 reader)
MESH_FORMATS = ("obj", "stl", "ply", "glb", "gltf", "off", "dae", "3mf")


class MeshFormatError(ValueError):
    """A mesh file that cannot be read; the message starts with ``path:`` (and ``LINE:COL:``)."""


class MeshImportWarning(UserWarning):
    """Something in a mesh file was skipped (e.g. VRML nodes with no geometry support)."""


class MeshPart(Part):
    """A :class:`Part` read from a file; ``opacity`` in [0, 1] (1 - VRML ``transparency``,
    or the colour's alpha) and ``name`` (the VRML ``DEF`` name or glTF node name, or None)."""

    __slots__ = ("opacity", "name")

    def __init__(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        rgb: Sequence[float] | None = None,
        *,
        face_rgb: ArrayLike | None = None,
        T_node_part: ArrayLike | None = None,
        opacity: float = 1.0,
        name: str | None = None,
    ) -> None:
        super().__init__(vertices, faces, rgb, face_rgb=face_rgb, T_node_part=T_node_part)
        self.opacity = float(opacity)
        self.name = name

    def __repr__(self) -> str:
        return f"<MeshPart {self.name or ''} {len(self.vertices)} vertices, {len(self.faces)} faces>"


def load_mesh(path: str | Path, *, scale: float | Sequence[float] = 1.0) -> list[MeshPart]:
    """Read the solid parts of a mesh file.

    ``path``: an OBJ, STL, PLY, GLB/glTF, OFF or VRML97 ``.wrl`` (``.wrz`` gzipped) file;
    ``scale``: a factor (or per-axis (3,) factors) applied to every vertex, e.g. 0.001 for
    a file in millimetres. Returns the parts in the file's frame, scaled, in metres.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"{p}: no such mesh file")
    if p.is_dir():
        raise MeshFormatError(f"{p}: is a folder, not a mesh file")
    ext = p.suffix.lower().lstrip(".")
    if ext in ("wrl", "wrz", "vrml"):
        from ejsrl.world._vrml import read_vrml

        parts, skipped = read_vrml(p)
        if skipped:
            warnings.warn(
                f"{p}: skipped VRML nodes that have no geometry support here: {', '.join(skipped)}",
                MeshImportWarning,
                stacklevel=2,
            )
    elif ext in MESH_FORMATS:
        parts = _read_trimesh(p, ext)
    else:
        raise MeshFormatError(
            f"{p}: unknown mesh format '.{ext}'; use one of "
            + ", ".join(f".{e}" for e in (*MESH_FORMATS[:6], "wrl"))
        )
    if not parts:
        raise MeshFormatError(f"{p}: the file has no triangles")
    s = np.broadcast_to(np.asarray(scale, dtype=float), (3,))
    if not np.array_equal(s, np.ones(3)):
        flip = np.prod(s) < 0
        parts = [
            MeshPart(q.vertices * s, q.faces[:, ::-1] if flip else q.faces, q.rgb, face_rgb=q.face_rgb,
                     opacity=q.opacity, name=q.name)
            for q in parts
        ]
    return parts


def _read_trimesh(p: Path, ext: str) -> list[MeshPart]:
    import trimesh

    try:
        loaded = trimesh.load(str(p), file_type=ext, process=False)
    except Exception as e:  # trimesh raises many kinds; all mean "cannot parse"
        raise MeshFormatError(f"{p}: could not read the .{ext} file: {e}") from e
    parts: list[MeshPart] = []
    if isinstance(loaded, trimesh.Scene):
        for node_name in loaded.graph.nodes_geometry:
            T, geom_name = loaded.graph[node_name]
            geom = loaded.geometry[geom_name]
            if isinstance(geom, trimesh.Trimesh):
                parts.extend(_parts_of(geom, np.asarray(T, dtype=float), str(node_name)))
    elif isinstance(loaded, trimesh.Trimesh):
        parts.extend(_parts_of(loaded, np.eye(4), None))
    else:
        raise MeshFormatError(f"{p}: the file holds {type(loaded).__name__}, not triangles")
    return parts


def _parts_of(mesh: Any, T: np.ndarray, name: str | None) -> list[MeshPart]:
    faces = np.asarray(mesh.faces)
    if len(faces) == 0:
        return []
    v = np.asarray(mesh.vertices, dtype=float) @ T[:3, :3].T + T[:3, 3]
    if np.linalg.det(T[:3, :3]) < 0:
        faces = faces[:, ::-1]
    rgba = _face_rgba(mesh)
    rgb = face_rgb = None
    opacity = 1.0
    if rgba is not None:
        opacity = float(rgba[:, 3].mean())
        if np.all(rgba == rgba[0]):
            rgb = rgba[0, :3]
        else:
            face_rgb = rgba[:, :3]
    return [MeshPart(v, faces, rgb, face_rgb=face_rgb, opacity=opacity, name=name)]


def _face_rgba(mesh: Any) -> np.ndarray | None:
    """(F, 4) colours in [0, 1] that the file gave the mesh, or None if it gave none."""
    visual = mesh.visual
    kind = getattr(visual, "kind", None)
    if kind == "face":
        return np.asarray(visual.face_colors, dtype=float) / 255.0
    if kind == "vertex":
        vc = np.asarray(visual.vertex_colors, dtype=float) / 255.0
        return vc[np.asarray(mesh.faces)].mean(axis=1)
    if kind == "texture":
        material = getattr(visual, "material", None)
        image = getattr(material, "image", None) or getattr(material, "baseColorTexture", None)
        if image is not None and getattr(visual, "uv", None) is not None:
            try:
                vc = np.asarray(visual.to_color().vertex_colors, dtype=float) / 255.0
                return vc[np.asarray(mesh.faces)].mean(axis=1)
            except Exception:  # a texture trimesh cannot sample: fall back to the material colour
                pass
        main = getattr(material, "main_color", None)
        if main is not None:
            return np.broadcast_to(np.asarray(main, dtype=float) / 255.0, (len(mesh.faces), 4)).copy()
    return None
