"""load_mesh through trimesh: geometry and colours survive a trimesh export, errors name the file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from ejsrl.world import MeshFormatError, MeshPart, World, load_mesh
from ejsrl.world.scene import MeshNode


def triangles(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each triangle's corners, rotated so the smallest corner comes first, rows sorted."""
    tri = np.round(np.asarray(vertices, dtype=float)[np.asarray(faces)], 6) + 0.0
    out = []
    for t in tri:
        k = min(range(3), key=lambda i: tuple(t[i]))
        out.append(np.roll(t, -k, axis=0).ravel())
    out = np.array(out)
    return out[np.lexsort(out.T[::-1])]


@pytest.fixture
def box() -> trimesh.Trimesh:
    return trimesh.creation.box([0.3, 0.2, 0.1])


@pytest.mark.parametrize("ext", ["stl", "ply", "off", "obj", "glb"])
def test_geometry_round_trips_through_trimesh_export(tmp_path: Path, box: trimesh.Trimesh, ext: str) -> None:
    path = tmp_path / f"box.{ext}"
    box.export(path)
    parts = load_mesh(path)
    assert all(isinstance(p, MeshPart) for p in parts)
    v = np.concatenate([p.vertices for p in parts])
    f = np.concatenate([p.faces + sum(len(q.vertices) for q in parts[:k]) for k, p in enumerate(parts)])
    # same triangles with the same winding (outward), whatever the vertex order in the file
    np.testing.assert_allclose(triangles(v, f), triangles(box.vertices, box.faces), atol=1e-6)
    assert trimesh.Trimesh(v, f).volume == pytest.approx(0.3 * 0.2 * 0.1, rel=1e-5)


def test_obj_takes_each_material_colour_from_its_mtl(tmp_path: Path) -> None:
    (tmp_path / "two.mtl").write_text("newmtl red\nKd 1 0 0\nnewmtl green\nKd 0 1 0\n")
    (tmp_path / "two.obj").write_text(
        "mtllib two.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
        "usemtl red\nf 1 2 3\nf 1 3 4\nusemtl green\nf 1 2 5\n"
    )
    parts = load_mesh(tmp_path / "two.obj")
    by_colour = {tuple(np.round(p.rgb, 6)): p for p in parts}
    assert set(by_colour) == {(1.0, 0.0, 0.0), (0.0, 1.0, 0.0)}
    red, green = by_colour[(1.0, 0.0, 0.0)], by_colour[(0.0, 1.0, 0.0)]
    assert len(red.faces) == 2 and len(green.faces) == 1
    np.testing.assert_allclose(triangles(green.vertices, green.faces), triangles([[0, 0, 0], [1, 0, 0], [0, 0, 1]], [[0, 1, 2]]))


def test_ply_face_colours_become_face_rgb(tmp_path: Path, box: trimesh.Trimesh) -> None:
    colours = np.zeros((12, 4), dtype=np.uint8)
    colours[:, 3] = 255
    colours[:6, 0] = 255  # first six faces red, the rest blue
    colours[6:, 2] = 255
    box.visual.face_colors = colours
    box.export(tmp_path / "c.ply")
    (part,) = load_mesh(tmp_path / "c.ply")
    assert part.rgb is None
    assert len(part.faces) == 12
    # match each read face to the written one by its corners and compare colours
    written = {tuple(triangles(box.vertices, box.faces[[k]])[0]): colours[k, :3] / 255 for k in range(12)}
    for k in range(len(part.faces)):
        key = tuple(triangles(part.vertices, part.faces[[k]])[0])
        np.testing.assert_allclose(part.face_rgb[k], written[key])


def test_glb_applies_node_transforms_and_keeps_the_base_colour(tmp_path: Path, box: trimesh.Trimesh) -> None:
    box.visual.face_colors = [51, 102, 204, 255]
    scene = trimesh.Scene()
    T = trimesh.transformations.rotation_matrix(0.5, [0, 0, 1])
    T[:3, 3] = [1, 2, 3]
    scene.add_geometry(box, node_name="link1", transform=T)
    scene.add_geometry(trimesh.creation.icosphere(1, 0.1), node_name="ball", transform=trimesh.transformations.translation_matrix([0, 0, -1]))
    scene.export(tmp_path / "s.glb")
    parts = {p.name: p for p in load_mesh(tmp_path / "s.glb")}
    assert set(parts) == {"link1", "ball"}
    expected = box.vertices @ T[:3, :3].T + T[:3, 3]
    np.testing.assert_allclose(triangles(parts["link1"].vertices, parts["link1"].faces), triangles(expected, box.faces), atol=1e-6)
    np.testing.assert_allclose(parts["link1"].rgb, [0.2, 0.4, 0.8], atol=1 / 255)
    np.testing.assert_allclose(parts["ball"].vertices.mean(axis=0), [0, 0, -1], atol=1e-6)


def test_scale_multiplies_vertices_and_a_mirror_keeps_faces_outward(tmp_path: Path, box: trimesh.Trimesh) -> None:
    box.export(tmp_path / "b.stl")
    (mm,) = load_mesh(tmp_path / "b.stl", scale=0.001)
    (raw,) = load_mesh(tmp_path / "b.stl")
    np.testing.assert_allclose(mm.vertices, raw.vertices * 0.001)
    (mirrored,) = load_mesh(tmp_path / "b.stl", scale=[-1, 1, 1])
    assert trimesh.Trimesh(mirrored.vertices, mirrored.faces).volume == pytest.approx(0.006, rel=1e-5)


def test_loaded_parts_show_in_a_world_with_their_colours(tmp_path: Path) -> None:
    (tmp_path / "m.wrl").write_text(
        "#VRML V2.0 utf8\nShape { appearance Appearance { material Material { diffuseColor 0 0 1 } } geometry Box { } }\n"
    )
    world = World()
    world.add(MeshNode("part", mesh_parts=load_mesh(tmp_path / "m.wrl"), scale=0.5, color="red"))
    tris, rgb = world.triangles()
    assert tris.shape == (12, 3, 3)
    np.testing.assert_allclose(np.abs(tris).max(), 0.5)  # a 2 m box scaled by 0.5
    np.testing.assert_allclose(rgb, np.tile([0, 0, 1.0], (12, 1)))  # the file's colour wins


def test_missing_file_names_it(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="nothere.obj"):
        load_mesh(tmp_path / "nothere.obj")


def test_unknown_format_names_the_file_and_the_choices(tmp_path: Path) -> None:
    (tmp_path / "part.xyz").write_text("1 2 3\n")
    with pytest.raises(MeshFormatError, match=r"part\.xyz: unknown mesh format '\.xyz'; use one of .*\.wrl"):
        load_mesh(tmp_path / "part.xyz")


@pytest.mark.parametrize(("name", "content"), [("bad.ply", b"ply\nformat nonsense\n"), ("bad.glb", b"glTF not really"), ("empty.obj", b"# nothing\n")])
def test_unreadable_files_raise_mesh_format_error_naming_them(tmp_path: Path, name: str, content: bytes) -> None:
    (tmp_path / name).write_bytes(content)
    with pytest.raises(MeshFormatError) as err:
        load_mesh(tmp_path / name)
    assert str(err.value).startswith(str(tmp_path / name) + ":")
