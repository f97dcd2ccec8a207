"""The VRML97 reader, checked against transforms and shapes computed independently here."""

from __future__ import annotations

import gzip
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from ejsrl.world import MeshFormatError, load_mesh
from ejsrl.world.mesh import MeshImportWarning

HEADER = "#VRML V2.0 utf8\n"
BOX_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float) / 2


def write(tmp_path: Path, body: str, name: str = "m.wrl", header: str = HEADER) -> Path:
    p = tmp_path / name
    p.write_text(header + body)
    return p


def load_quiet(path: Path) -> list:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any warning fails the test
        return load_mesh(path)


def rows(a: np.ndarray) -> np.ndarray:
    """Rows sorted lexicographically (after rounding), to compare point sets."""
    a = np.round(np.asarray(a, dtype=float), 9) + 0.0
    return a[np.lexsort(a.T[::-1])]


def H(R: np.ndarray | None = None, t=(0, 0, 0), s=None) -> np.ndarray:
    M = np.eye(4)
    if R is not None:
        M[:3, :3] = R
    if s is not None:
        M[:3, :3] = np.diag(s)
    M[:3, 3] = t
    return M


def rot(axis, angle) -> np.ndarray:
    axis = np.asarray(axis, dtype=float)
    return Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle).as_matrix()


def apply(M: np.ndarray, v: np.ndarray) -> np.ndarray:
    return (np.c_[v, np.ones(len(v))] @ M.T)[:, :3]


def signed_volume(part) -> float:
    return trimesh.Trimesh(part.vertices, part.faces, process=False).volume


# -- transforms ------------------------------------------------------------------------------
def test_full_transform_matches_T_C_R_SR_S_minus_SR_minus_C(tmp_path: Path) -> None:
    body = """
    Transform {
      translation 1 2 3
      rotation 0 1 1 0.7
      scale 2 0.5 1.5
      scaleOrientation 1 0 0 0.3
      center 0.1 -0.2 0.3
      children [ Shape { geometry Box { size 1 2 3 } } ]
    }"""
    (part,) = load_quiet(write(tmp_path, body))
    R, SR = rot([0, 1, 1], 0.7), rot([1, 0, 0], 0.3)
    c = np.array([0.1, -0.2, 0.3])
    M = H(t=[1, 2, 3]) @ H(t=c) @ H(R) @ H(SR) @ H(s=[2, 0.5, 1.5]) @ H(SR.T) @ H(t=-c)
    expected = apply(M, BOX_CORNERS * [1, 2, 3])
    np.testing.assert_allclose(rows(part.vertices), rows(expected), atol=1e-12)
    assert part.T_node_part is None


def test_nested_transforms_compose_parent_first(tmp_path: Path) -> None:
    body = """
    Transform { translation 0 0 1 rotation 0 0 1 1.5707963267948966 children [
      Group { children [
        Transform { translation 1 0 0 scale 2 2 2 children Shape { geometry Box { } } }
      ] }
    ] }"""
    (part,) = load_quiet(write(tmp_path, body))
    M = H(rot([0, 0, 1], math.pi / 2), t=[0, 0, 1]) @ H(t=[1, 0, 0]) @ H(s=[2, 2, 2])
    # default Box size is 2 2 2
    np.testing.assert_allclose(rows(part.vertices), rows(apply(M, BOX_CORNERS * 2)), atol=1e-12)
    # the box centre lands at (0, 1, 1): x=1 rotated by 90 degrees about z, lifted by 1
    np.testing.assert_allclose(part.vertices.mean(axis=0), [0, 1, 1], atol=1e-12)


def test_mirroring_scale_keeps_faces_outward(tmp_path: Path) -> None:
    (part,) = load_quiet(write(tmp_path, "Transform { scale -1 1 1 children Shape { geometry Box { } } }"))
    assert signed_volume(part) == pytest.approx(8.0)


# -- appearance, DEF/USE, grouping -------------------------------------------------------------
def test_material_colour_and_transparency(tmp_path: Path) -> None:
    body = """
    Shape { appearance Appearance { material Material { diffuseColor 0.2 0.4 0.6 transparency 0.25 } }
            geometry Sphere { radius 0.5 } }
    Shape { appearance Appearance { material Material { } } geometry Box { } }
    Shape { geometry Box { } }"""
    a, b, c = load_quiet(write(tmp_path, body))
    np.testing.assert_allclose(a.rgb, [0.2, 0.4, 0.6])
    assert a.opacity == pytest.approx(0.75)
    np.testing.assert_allclose(b.rgb, [0.8, 0.8, 0.8])  # the VRML default diffuseColor
    assert b.opacity == 1.0
    assert c.rgb is None and c.face_rgb is None  # no material: the scene node's colour shows


def test_def_use_reuses_a_shape_under_another_transform(tmp_path: Path) -> None:
    body = """
    DEF Link Shape { appearance Appearance { material DEF Red Material { diffuseColor 1 0 0 } }
                     geometry Box { size 1 1 1 } }
    Transform { translation 5 0 0 children [ USE Link ] }
    Shape { appearance Appearance { material USE Red } geometry Sphere { radius 0.1 } }"""
    a, b, c = load_quiet(write(tmp_path, body))
    np.testing.assert_allclose(rows(a.vertices), rows(BOX_CORNERS))
    np.testing.assert_allclose(rows(b.vertices), rows(BOX_CORNERS + [5, 0, 0]))
    assert a.name == b.name == "Link"
    np.testing.assert_allclose(c.rgb, [1, 0, 0])


def test_switch_lod_anchor_and_collision_groups(tmp_path: Path) -> None:
    body = """
    Switch { whichChoice 1 choice [ Shape { geometry Box { size 9 9 9 } } Shape { geometry Box { size 1 1 1 } } ] }
    Switch { choice [ Shape { geometry Box { size 7 7 7 } } ] }
    LOD { level [ Shape { geometry Box { size 2 2 2 } } Shape { geometry Box { size 8 8 8 } } ] }
    Anchor { url "x.wrl" children [ Collision { children [ Shape { geometry Box { size 3 3 3 } } ] } ] }"""
    parts = load_quiet(write(tmp_path, body))
    sizes = sorted(float(np.ptp(p.vertices[:, 0])) for p in parts)
    assert sizes == [1.0, 2.0, 3.0]


def test_comments_commas_routes_and_protos_are_handled(tmp_path: Path) -> None:
    body = """# a comment { with braces [
    PROTO Wheel [ field SFFloat r 1 ] { Shape { geometry Sphere { radius IS r } } }
    DEF T Transform { # another comment
      translation 1, 2, 3 # commas are whitespace
      children [ Shape { geometry Box { size 1,1,1 } } ]
    }
    DEF S TimeSensor { cycleInterval 2 loop TRUE }
    ROUTE S.fraction_changed TO T.set_translation
    """
    with pytest.warns(MeshImportWarning) as record:
        (part,) = load_mesh(write(tmp_path, body))
    np.testing.assert_allclose(part.vertices.mean(axis=0), [1, 2, 3])
    assert len(record) == 1
    assert "TimeSensor" in str(record[0].message)


def test_unsupported_nodes_give_one_warning_naming_them_all(tmp_path: Path) -> None:
    body = """
    Viewpoint { position 0 0 10 description "front" }
    PointLight { location 1 1 1 }
    Background { skyColor [ 0 0 1 ] }
    Script { eventIn SFTime tick field SFFloat k 1 url "javascript: function tick(t) { }" }
    Inline { url "other.wrl" }
    WorldInfo { title "cell" }
    Shape { geometry Text { string [ "hi" ] } }
    Shape { geometry Box { } }"""
    path = write(tmp_path, body)
    with pytest.warns(MeshImportWarning) as record:
        parts = load_mesh(path)
    assert len(parts) == 1
    assert len(record) == 1
    msg = str(record[0].message)
    assert str(path) in msg
    for name in ("Background", "Inline", "PointLight", "Script", "Text", "Viewpoint"):
        assert name in msg
    assert "WorldInfo" not in msg  # carries no geometry, so it is not worth a warning


# -- IndexedFaceSet -----------------------------------------------------------------------------
def ifs(points: str, index: str, extra: str = "") -> str:
    return f"Shape {{ geometry IndexedFaceSet {{ coord Coordinate {{ point [ {points} ] }} coordIndex [ {index} ] {extra} }} }}"


def test_quad_is_fanned_and_ccw_false_flips_the_winding(tmp_path: Path) -> None:
    pts = "0 0 0, 1 0 0, 1 1 0, 0 1 0"
    (a,) = load_quiet(write(tmp_path, ifs(pts, "0 1 2 3 -1")))
    (b,) = load_quiet(write(tmp_path, ifs(pts, "0 1 2 3 -1", "ccw FALSE solid FALSE"), "b.wrl"))
    assert a.faces.tolist() == [[0, 1, 2], [0, 2, 3]]
    assert b.faces.tolist() == [[2, 1, 0], [3, 2, 0]]
    np.testing.assert_array_equal(a.vertices, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    na = trimesh.Trimesh(a.vertices, a.faces, process=False).face_normals
    nb = trimesh.Trimesh(b.vertices, b.faces, process=False).face_normals
    np.testing.assert_allclose(na, [[0, 0, 1]] * 2)
    np.testing.assert_allclose(nb, [[0, 0, -1]] * 2)


def test_concave_polygon_is_ear_clipped_into_its_own_area(tmp_path: Path) -> None:
    # an L-shaped hexagon in the plane x = 2 (so the projection axis is x), area 3
    yz = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)
    pts = ", ".join(f"2 {y} {z}" for y, z in yz)
    (part,) = load_quiet(write(tmp_path, ifs(pts, "0 1 2 3 4 5 -1")))
    assert len(part.faces) == 4
    tri = part.vertices[part.faces][:, :, 1:]
    cross = (tri[:, 1, 0] - tri[:, 0, 0]) * (tri[:, 2, 1] - tri[:, 0, 1]) - (tri[:, 1, 1] - tri[:, 0, 1]) * (tri[:, 2, 0] - tri[:, 0, 0])
    assert np.all(cross > 0)  # every triangle keeps the polygon's counter-clockwise order
    assert cross.sum() / 2 == pytest.approx(3.0)  # and together they tile the L exactly
    # no triangle covers the notch at (1.5, 1.5)
    centroids = tri.mean(axis=1)
    assert not np.any((centroids[:, 0] > 1) & (centroids[:, 1] > 1))


def test_colour_per_face_with_and_without_colour_index(tmp_path: Path) -> None:
    pts = "0 0 0, 1 0 0, 1 1 0, 0 1 0, 0 0 1"
    index = "0 1 2 3 -1 0 1 4 -1"
    colours = "color Color { color [ 1 0 0, 0 1 0, 0 0 1 ] }"
    (a,) = load_quiet(write(tmp_path, ifs(pts, index, f"colorPerVertex FALSE {colours} colorIndex [ 2 0 ]")))
    (b,) = load_quiet(write(tmp_path, ifs(pts, index, f"colorPerVertex FALSE {colours}"), "b.wrl"))
    np.testing.assert_array_equal(a.face_rgb, [[0, 0, 1], [0, 0, 1], [1, 0, 0]])  # quad -> 2 triangles
    np.testing.assert_array_equal(b.face_rgb, [[1, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert a.rgb is None


def test_colour_per_vertex_is_averaged_over_each_triangle(tmp_path: Path) -> None:
    pts = "0 0 0, 1 0 0, 0 1 0"
    (a,) = load_quiet(write(tmp_path, ifs(pts, "0 1 2 -1", "color Color { color [ 1 0 0, 0 1 0, 0 0 1 ] }")))
    np.testing.assert_allclose(a.face_rgb, [[1 / 3, 1 / 3, 1 / 3]])
    (b,) = load_quiet(write(tmp_path, ifs(pts, "0 1 2 -1", "color Color { color [ 1 0 0, 0 1 0 ] } colorIndex [ 0 0 1 -1 ]"), "b.wrl"))
    np.testing.assert_allclose(b.face_rgb, [[2 / 3, 1 / 3, 0]])


def test_last_polygon_needs_no_trailing_minus_one_and_normals_are_ignored(tmp_path: Path) -> None:
    body = ifs("0 0 0, 1 0 0, 0 1 0, 0 0 1", "0 2 1 -1 0 1 3",
               "normal Normal { vector [ 0 0 1 ] } texCoord TextureCoordinate { point [ 0 0 ] } creaseAngle 0.5 convex TRUE")
    (part,) = load_quiet(write(tmp_path, body))
    assert part.faces.tolist() == [[0, 2, 1], [0, 1, 3]]


# -- primitives (VRML axes: cylinders and cones along +y) ------------------------------------------
def test_box_default_and_sized(tmp_path: Path) -> None:
    a, b = load_quiet(write(tmp_path, "Shape { geometry Box { } } Shape { geometry Box { size 0.1 0.2 0.3 } }"))
    np.testing.assert_array_equal(rows(a.vertices), rows(BOX_CORNERS * 2))
    np.testing.assert_allclose(rows(b.vertices), rows(BOX_CORNERS * [0.1, 0.2, 0.3]))
    assert signed_volume(b) == pytest.approx(0.006)


def test_sphere_vertices_lie_on_the_radius(tmp_path: Path) -> None:
    (part,) = load_quiet(write(tmp_path, "Shape { geometry Sphere { radius 0.3 } }"))
    np.testing.assert_allclose(np.linalg.norm(part.vertices, axis=1), 0.3)
    assert 0.9 * 4 / 3 * math.pi * 0.3**3 < signed_volume(part) < 4 / 3 * math.pi * 0.3**3


def test_cylinder_is_along_y_closed_with_the_polygon_volume(tmp_path: Path) -> None:
    from ejsrl.world._vrml import CIRCLE_SECTIONS as n

    (part,) = load_quiet(write(tmp_path, "Shape { geometry Cylinder { radius 0.2 height 0.5 } }"))
    v = part.vertices
    assert set(np.round(v[:, 1], 12)) == {-0.25, 0.25}
    rim = np.hypot(v[:, 0], v[:, 2])
    np.testing.assert_allclose(rim[rim > 1e-12], 0.2)
    mesh = trimesh.Trimesh(v, part.faces, process=True)
    assert mesh.is_watertight
    assert mesh.volume == pytest.approx(n / 2 * 0.2**2 * math.sin(2 * math.pi / n) * 0.5, rel=1e-12)


def test_cylinder_without_caps_and_cone_along_y(tmp_path: Path) -> None:
    from ejsrl.world._vrml import CIRCLE_SECTIONS as n

    body = """Shape { geometry Cylinder { top FALSE bottom FALSE } }
              Shape { geometry Cone { bottomRadius 0.5 height 2 } }
              Shape { geometry Cone { bottom FALSE } }"""
    tube, cone, open_cone = load_quiet(write(tmp_path, body))
    assert len(tube.faces) == 2 * n
    assert np.all(np.abs(tube.vertices[tube.faces][..., 1]) == 1.0)  # only side walls
    apex = cone.vertices[np.argmax(cone.vertices[:, 1])]
    np.testing.assert_allclose(apex, [0, 1, 0])
    assert cone.vertices[:, 1].min() == -1.0
    base_area = n / 2 * 0.5**2 * math.sin(2 * math.pi / n)
    mesh = trimesh.Trimesh(cone.vertices, cone.faces, process=True)
    assert mesh.is_watertight
    assert mesh.volume == pytest.approx(base_area * 2 / 3, rel=1e-12)
    assert len(open_cone.faces) == n


# -- round trip from trimesh primitives ----------------------------------------------------------------
def to_vrml(mesh: trimesh.Trimesh) -> str:
    """A test-side VRML writer: one Shape with an IndexedFaceSet, full float precision."""
    pts = ",\n".join(" ".join(repr(float(x)) for x in p) for p in mesh.vertices)
    idx = "\n".join(" ".join(str(int(i)) for i in f) + " -1" for f in mesh.faces)
    return f"""Shape {{
  appearance Appearance {{ material Material {{ diffuseColor 0.1 0.5 0.9 }} }}
  geometry IndexedFaceSet {{ solid TRUE coord Coordinate {{ point [ {pts} ] }} coordIndex [ {idx} ] }}
}}"""


@pytest.mark.parametrize(
    "mesh",
    [trimesh.creation.box([0.3, 0.2, 0.1]), trimesh.creation.icosphere(2, 0.25), trimesh.creation.cylinder(0.1, 0.4, sections=20)],
    ids=["box", "icosphere", "cylinder"],
)
def test_round_trip_of_trimesh_primitives(tmp_path: Path, mesh: trimesh.Trimesh) -> None:
    (part,) = load_quiet(write(tmp_path, to_vrml(mesh)))
    np.testing.assert_array_equal(part.vertices, mesh.vertices)
    np.testing.assert_array_equal(part.faces, mesh.faces)
    np.testing.assert_allclose(part.rgb, [0.1, 0.5, 0.9])


def test_gzipped_wrz(tmp_path: Path) -> None:
    p = tmp_path / "m.wrz"
    p.write_bytes(gzip.compress((HEADER + "Shape { geometry Box { } }").encode()))
    (part,) = load_quiet(p)
    assert len(part.faces) == 12


# -- errors ---------------------------------------------------------------------------------------
def location(err: pytest.ExceptionInfo, path: Path) -> tuple[int, int, str]:
    m = re.match(re.escape(str(path)) + r":(\d+):(\d+): (.*)", str(err.value), re.S)
    assert m, f"message does not start with path:line:col: {err.value}"
    return int(m.group(1)), int(m.group(2)), m.group(3)


@pytest.mark.parametrize(
    ("body", "line", "col", "words"),
    [
        ("Shape {\n  geometry Box { size 1 2 }\n}", 2, 18, "Box.size needs 3 numbers"),
        ("Transform {\n  translation 1.2.3 0 0\n}", 2, 15, "malformed number"),
        ("Group { children [\n  USE Nowhere\n] }", 2, 7, "USE of 'Nowhere'"),
        ("Shape { geometry IndexedFaceSet {\n coord Coordinate { point [0 0 0, 1 0 0, 0 1 0] }\n   coordIndex [0 1 7 -1] } }", 3, 4, "coordIndex 7 is out of range"),
        ("Group { children [\n  Shape { geometry Box { } }\n", 1, 18, "never closed with ']'"),
        ("\n\nTransform {\n  children []\n", 3, 1, "Transform node that starts here is never closed"),
        ("Shape { geometry Sphere { radius -1 } }", 1, 27, "Sphere.radius must be positive"),
        ("Shape { appearance Material { } }", 1, 20, "must be an Appearance node"),
        ("Transform { translation 0 0 0 } }", 1, 33, "expected a node"),
        ("Transform { rotation 0 0 1 }", 1, 13, "Transform.rotation needs 4 numbers"),
        ("Group { children [ 1 2 ] }", 1, 9, "Group.children must be a list of nodes"),
    ],
)
def test_malformed_files_name_path_line_and_column(tmp_path: Path, body: str, line: int, col: int, words: str) -> None:
    # the header is line 1, so the body starts on line 2
    path = write(tmp_path, body)
    with pytest.raises(MeshFormatError) as err:
        load_mesh(path)
    assert location(err, path) [:2] == (line + 1, col)
    assert words in str(err.value)


def test_header_is_checked(tmp_path: Path) -> None:
    v1 = write(tmp_path, "Separator { }", "v1.wrl", header="#VRML V1.0 ascii\n")
    with pytest.raises(MeshFormatError) as err:
        load_mesh(v1)
    assert location(err, v1)[:2] == (1, 1)
    assert "VRML97" in str(err.value)
    plain = write(tmp_path, "Shape { }", "plain.wrl", header="")
    with pytest.raises(MeshFormatError, match="first line must be '#VRML V2.0 utf8'"):
        load_mesh(plain)
    assert isinstance(err.value, ValueError)


def test_file_with_only_unsupported_nodes_has_no_triangles(tmp_path: Path) -> None:
    path = write(tmp_path, "Viewpoint { }")
    with pytest.warns(MeshImportWarning), pytest.raises(MeshFormatError, match="no triangles"):
        load_mesh(path)
