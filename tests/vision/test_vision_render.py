"""The virtual camera: CameraModel geometry and the renderer against analytic projections and depths.

Golden images live in tests/vision/golden/; regenerate them (after checking the new
images by eye) with ``EJSGEN_REGEN_GOLDEN=1 python -m pytest tests/vision``.
"""

from __future__ import annotations

import os
import threading
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import look_at

from ejsrl.robotics.transforms import r2t, rotx, rotz, transl
from ejsrl.vision import CameraModel
from ejsrl.world import BACKGROUND, World, render
from ejsrl.world import _gl
from ejsrl.world._raster import clip_near, rasterize
from ejsrl.world.rendering import _pick_backend
from ejsrl.world.scene import Box, CameraNode, MeshNode, Part, Sphere
from test_render_gl import require_gl

GOLDEN = Path(__file__).parent / "golden"
REGEN = os.environ.get("EJSGEN_REGEN_GOLDEN") == "1"


@pytest.fixture(params=["numpy", "gl"])
def backend(request) -> str:
    """Each render back end in turn (the OpenGL one fails, saying why, if it cannot run)."""
    if request.param == "gl":
        require_gl()
    return request.param


# -- CameraModel ------------------------------------------------------------------------------
def test_intrinsics_from_fov_and_from_K():
    cam = CameraModel(640, 480, fov_deg=90)
    assert cam.fy == pytest.approx(240.0) and cam.fx == pytest.approx(240.0)
    assert (cam.cx, cam.cy) == (319.5, 239.5)
    assert cam.fov_deg == pytest.approx(90.0)
    K = [[500, 0, 300], [0, 510, 200], [0, 0, 1]]
    c2 = CameraModel(600, 400, K=K)
    np.testing.assert_array_equal(c2.K, K)
    with pytest.raises(ValueError):
        CameraModel(10, 10, fov_deg=60, K=K)


def test_project_normalize_backproject_roundtrip(rng):
    cam = CameraModel(320, 240, K=[[300, 0, 150], [0, 310, 125], [0, 0, 1]])
    T = r2t(rotx(0.3) @ rotz(-0.7), [0.2, -0.1, 0.5])
    P_cam = np.column_stack([rng.uniform(-1, 1, (20, 2)), rng.uniform(1, 4, 20)])
    P_world = P_cam @ T[:3, :3].T + T[:3, 3]
    px = cam.project(P_world, T)
    np.testing.assert_allclose(px[:, 0], 300 * P_cam[:, 0] / P_cam[:, 2] + 150)
    np.testing.assert_allclose(px[:, 1], 310 * P_cam[:, 1] / P_cam[:, 2] + 125)
    np.testing.assert_allclose(cam.normalized(px), P_cam[:, :2] / P_cam[:, 2:3])
    np.testing.assert_allclose(cam.denormalized(cam.normalized(px)), px)
    np.testing.assert_allclose(cam.backproject(px, P_cam[:, 2], T), P_world, atol=1e-12)
    np.testing.assert_allclose(cam.depth(P_world, T), P_cam[:, 2])
    behind = cam.project([[0, 0, -1.0]], np.eye(4))
    assert np.isnan(behind).all()


def test_frustum_corners_project_to_the_image_corners():
    cam = CameraModel(64, 48, fov_deg=50, near=0.1, far=3.0)
    T = transl(1, 2, 3) @ r2t(rotx(0.4))
    F = cam.frustum(T)
    assert F.shape == (8, 3)
    px = cam.project(F, T)
    corners = [[-0.5, -0.5], [63.5, -0.5], [63.5, 47.5], [-0.5, 47.5]]
    np.testing.assert_allclose(px[:4], corners, atol=1e-9)
    np.testing.assert_allclose(px[4:], corners, atol=1e-9)
    np.testing.assert_allclose(cam.depth(F, T), [0.1] * 4 + [3.0] * 4)
    assert cam.frustum_lines(T).shape == (8, 2, 3)


# -- renderer geometry --------------------------------------------------------------------------
def _convex_margins(px_poly: np.ndarray, W: int, H: int) -> np.ndarray:
    """Signed distance (H, W) of each pixel centre to a convex polygon's edges: min over edges (>0 inside)."""
    hull = cv2.convexHull(px_poly.astype(np.float32)).reshape(-1, 2).astype(np.float64)
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float64)
    d = np.full((H, W), np.inf)
    n = len(hull)
    area = 0.5 * np.sum(hull[:, 0] * np.roll(hull[:, 1], -1) - np.roll(hull[:, 0], -1) * hull[:, 1])
    s = 1.0 if area > 0 else -1.0
    for i in range(n):
        a, b = hull[i], hull[(i + 1) % n]
        e = b - a
        dist = s * (e[0] * (yy - a[1]) - e[1] * (xx - a[0])) / np.hypot(*e)
        d = np.minimum(d, dist)
    return d


def test_rendered_box_silhouette_matches_camera_model_projection(backend):
    w = World()
    T_box = transl(0.1, -0.05, 0.2) @ r2t(rotz(0.5) @ rotx(0.2))
    w.add(Box("b", size=(0.4, 0.3, 0.25), color="orange", T_parent_local=T_box))
    cam = CameraModel(160, 120, fov_deg=55)
    T_cam = look_at((0.9, -1.1, 0.9), (0.1, -0.05, 0.2))
    rgb, depth = render(w, cam, T_cam, backend=backend)
    corners = np.array([[x, y, z] for x in (-0.2, 0.2) for y in (-0.15, 0.15) for z in (-0.125, 0.125)])
    Pw = corners @ T_box[:3, :3].T + T_box[:3, 3]
    px = cam.project(Pw, T_cam)
    margin = _convex_margins(px, 160, 120)
    covered = np.isfinite(depth)
    # every pixel more than 0.5 px inside the projected hull is drawn, none more than 0.5 px outside
    assert covered[margin > 0.5].all()
    assert not covered[margin < -0.5].any()
    assert covered.sum() > 500
    # the front-most vertex shows at exactly its projection: its depth there matches
    i = np.argmin(cam.depth(Pw, T_cam))
    x, y = np.rint(px[i]).astype(int)
    assert abs(depth[y, x] - cam.depth(Pw, T_cam)[i]) < 0.02


def test_depth_equals_the_analytic_plane_distance(backend):
    # a tilted plane n.P = c seen by the camera: Z(pixel) = c / (n . (x, y, 1)) in the camera frame
    w = World()
    T_plane = transl(0, 0, 0) @ r2t(rotx(0.5))
    V = np.array([[-3, -3, 0], [3, -3, 0], [3, 3, 0], [-3, 3, 0]], float)
    w.add(MeshNode("p", mesh_parts=(Part(V, [[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]], (0.5, 0.6, 0.7)),), T_parent_local=T_plane))
    cam = CameraModel(120, 90, fov_deg=60)
    T_cam = look_at((0.3, -0.4, 1.5), (0, 0.1, 0))
    _, depth = render(w, cam, T_cam, backend=backend)
    assert np.isfinite(depth).all()
    Tcp = np.linalg.inv(T_cam) @ T_plane
    n_c, p0_c = Tcp[:3, 2], Tcp[:3, 3]
    c = n_c @ p0_c
    yy, xx = np.mgrid[0:90, 0:120]
    xy = cam.normalized(np.column_stack([xx.ravel(), yy.ravel()]))
    Z = c / (xy @ n_c[:2] + n_c[2])
    np.testing.assert_allclose(depth.ravel(), Z, rtol=2e-6)


def test_floor_under_a_sphere_is_occluded_per_pixel(backend):
    """A painter's algorithm sorting faces by their centre's depth draws the floor over the ball here."""
    w = World()
    r = 0.3
    floor = Box("floor", size=(20, 20, 0.02), color="gray", T_parent_local=transl(0, 0, -0.01))
    ball = Sphere("ball", radius=r, color="red", T_parent_local=transl(0, 0, r))
    w.add(floor)
    w.add(ball)
    cam = CameraModel(160, 120, fov_deg=60)
    T_cam = look_at((0, -1.2, 0.5), (0, 0, 0.25))
    rgb, depth = render(w, cam, T_cam, backend=backend)
    tris, _ = w.triangles()
    centre_depth = cam.depth(tris.mean(axis=1), T_cam)
    floor_top = centre_depth[:12]
    # precondition: some floor faces have their centre nearer than the whole ball
    assert floor_top.min() < centre_depth[12:].min()
    # per-pixel truth from rays: the sphere where the ray hits it, else the floor plane z = 0
    yy, xx = np.mgrid[0:120, 0:160]
    xy = cam.normalized(np.column_stack([xx.ravel(), yy.ravel()]))
    d_cam = np.column_stack([xy, np.ones(len(xy))])  # Z = 1 per unit step
    d_w = d_cam @ T_cam[:3, :3].T
    o = T_cam[:3, 3]
    oc = o - np.array([0, 0, r])
    b = d_w @ oc
    a = np.einsum("ij,ij->i", d_w, d_w)
    disc = b * b - a * (oc @ oc - r * r)
    t_sphere = np.where(disc > 0, (-b - np.sqrt(np.maximum(disc, 0))) / a, np.inf)
    t_floor = np.where(d_w[:, 2] < 0, -o[2] / d_w[:, 2], np.inf)
    # the icosphere lies within 2% of the true radius: judge only pixels clear of its outline
    inner = b * b - a * (oc @ oc - (0.97 * r) ** 2) > 0
    outer = b * b - a * (oc @ oc - (1.01 * r) ** 2) > 0
    ball_px = inner.reshape(120, 160)
    hit = o + np.where(np.isfinite(t_floor), t_floor, 0)[:, None] * d_w
    on_floor = np.isfinite(t_floor) & (np.abs(hit[:, :2]) < 9.5).all(axis=1)
    floor_px = (~outer & on_floor).reshape(120, 160)
    red = (rgb[..., 0].astype(int) > 2 * rgb[..., 1].astype(int) + 20) & (rgb[..., 1] == rgb[..., 2])
    assert ball_px.sum() > 500 and floor_px.sum() > 5000
    assert red[ball_px].all()
    assert not red[floor_px].any()
    np.testing.assert_allclose(depth[floor_px], t_floor.reshape(120, 160)[floor_px], rtol=1e-5)
    np.testing.assert_allclose(depth[ball_px], t_sphere.reshape(120, 160)[ball_px], rtol=0.03)


def test_near_plane_clipping_keeps_the_visible_part(backend):
    # a floor that passes under and behind the camera
    w = World()
    V = np.array([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], float)
    w.add(MeshNode("floor", mesh_parts=(Part(V, [[0, 1, 2], [0, 2, 3]], (0.6, 0.6, 0.6)),)))
    cam = CameraModel(80, 60, fov_deg=70, near=0.05)
    T_cam = look_at((0, 0, 0.3), (0, 2, 0.0))
    _, depth = render(w, cam, T_cam, backend=backend)
    yy, xx = np.mgrid[0:60, 0:80]
    xy = cam.normalized(np.column_stack([xx.ravel(), yy.ravel()]))
    d_w = np.column_stack([xy, np.ones(len(xy))]) @ T_cam[:3, :3].T
    t = np.where(d_w[:, 2] < 0, -0.3 / d_w[:, 2], np.inf)
    hit = np.array([0, 0, 0.3]) + np.where(np.isfinite(t), t, 0)[:, None] * d_w
    ok = np.isfinite(t) & (np.abs(hit[:, :2]) < 4.9).all(axis=1)  # skip rays near the floor's far edge
    assert ok.sum() > 1000
    np.testing.assert_allclose(depth.ravel()[ok], t[ok], rtol=1e-5)
    # clip_near itself: a triangle crossing the plane keeps its in-front part, winding kept
    tri = np.array([[[0, 0, -1.0], [1, 0, 1.0], [0, 1, 1.0]]])
    out, src = clip_near(tri, 0.0)
    assert len(out) == 2 and (src == 0).all() and (out[:, :, 2] >= -1e-12).all()
    n0 = np.cross(tri[0, 1] - tri[0, 0], tri[0, 2] - tri[0, 0])
    for t3 in out:
        assert np.dot(np.cross(t3[1] - t3[0], t3[2] - t3[0]), n0) > 0


def test_camera_node_by_name_and_determinism(backend):
    w = World()
    w.add(Box("b", size=(0.3, 0.3, 0.3), color="blue", T_parent_local=transl(0, 0, 0.15)))
    T_cam = look_at((0.8, -0.8, 0.7), (0, 0, 0.1))
    w.add(CameraNode("cam", T_parent_local=T_cam, fov=45.0, resolution=(96, 72)))
    rgb1, d1 = render(w, "cam", backend=backend)
    rgb2, d2 = render(w, CameraModel(96, 72, fov_deg=45.0), T_cam, backend=backend)
    np.testing.assert_array_equal(rgb1, rgb2)
    np.testing.assert_array_equal(d1, d2)
    rgb3, _ = render(w, "cam", backend=backend)
    np.testing.assert_array_equal(rgb1, rgb3)
    assert rgb1.shape == (72, 96, 3) and rgb1.dtype == np.uint8 and d1.dtype == np.float32
    bg = np.rint(np.array(BACKGROUND) * 255).astype(np.uint8)
    assert (rgb1[~np.isfinite(d1)] == bg).all() and np.isinf(d1[0, 0])
    rgb_ex, d_ex = render(w, "cam", exclude=("b",), backend=backend)
    assert np.isinf(d_ex).all()
    with pytest.raises(ValueError, match="T_world_camera"):
        render(w, CameraModel(8, 8))
    with pytest.raises(KeyError, match="did you mean 'cam'"):
        render(w, "cma")


def test_threads_rendering_at_once_get_the_same_pictures(backend):
    """The NumPy back end keeps its work buffers per thread; the OpenGL one shares a context under a lock."""
    w, cam, T = _golden_scene()
    big = CameraModel(320, 240, fov_deg=50)
    want = [render(w, c, T, backend=backend) for c in (cam, big)]
    got: dict[tuple[int, int], list] = {}
    errors: list[BaseException] = []
    barrier = threading.Barrier(4)

    def worker(i: int) -> None:
        barrier.wait()
        try:
            for j in range(6):  # sizes alternate, so buffers are resized while others use theirs
                got.setdefault((i, j), []).append(render(w, (cam, big)[(i + j) % 2], T, backend=backend))
        except BaseException as exc:  # noqa: BLE001 - reported below, in the test's thread
            errors.append(exc)

    threads = [threading.Thread(target=worker, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    assert len(got) == 24
    for (i, j), [(rgb, depth)] in got.items():
        rgb_want, depth_want = want[(i + j) % 2]
        np.testing.assert_array_equal(rgb, rgb_want)
        np.testing.assert_array_equal(depth, depth_want)


def test_back_faces_are_culled_only_when_asked():
    V = np.array([[-1, -1, 0], [1, -1, 0], [0, 1, 0]], float)
    tri_facing_up = np.array([V])
    cam_below = np.array([[0, 0, 0, 1.0]])  # placeholder to keep shapes obvious
    del cam_below
    K = CameraModel(40, 30, fov_deg=60).K
    # camera frame: the triangle 2 m ahead, its normal (+z) pointing away from the camera
    tri_cam = tri_facing_up + [0, 0, 2.0]
    face, _ = rasterize(tri_cam, K, 40, 30, cull_backfaces=True)
    assert (face < 0).all()
    face, depth = rasterize(tri_cam, K, 40, 30, cull_backfaces=False)
    assert (face == 0).sum() > 50 and np.allclose(depth[face == 0], 2.0)


def _golden_scene() -> tuple[World, CameraModel, np.ndarray]:
    w = World()
    w.add(Box("floor", size=(2, 2, 0.02), color="gray", T_parent_local=transl(0, 0, -0.01)))
    w.add(Sphere("ball", radius=0.2, color="red", T_parent_local=transl(-0.2, 0.1, 0.2)))
    w.add(Box("crate", size=(0.25, 0.25, 0.25), color="blue", T_parent_local=transl(0.3, -0.1, 0.125) @ r2t(rotz(0.4))))
    from ejsrl.world.scene import Cylinder

    w.add(Cylinder("can", radius=0.08, height=0.3, color="green", T_parent_local=transl(0.1, 0.35, 0.15)))
    return w, CameraModel(96, 72, fov_deg=50), look_at((0.9, -1.2, 0.8), (0, 0, 0.1))


def test_golden_image_of_a_small_scene():
    w, cam, T = _golden_scene()
    rgb, depth = render(w, cam, T, backend="numpy")
    path = GOLDEN / "test_golden_image_of_a_small_scene.png"
    if REGEN or not path.exists():
        if not REGEN:
            pytest.fail(f"missing golden image {path}; run with EJSGEN_REGEN_GOLDEN=1 to create it")
        path.parent.mkdir(parents=True, exist_ok=True)
        cv2.imwrite(str(path), rgb[:, :, ::-1])
    want = cv2.imread(str(path))[:, :, ::-1]
    diff = np.any(want != rgb, axis=2)
    # deterministic here; allow a handful of edge pixels for other BLAS/CPU rounding
    assert diff.mean() < 0.002, f"{diff.sum()} pixels differ from {path.name}"
    # and the picture is what we expect: red ball, blue crate, green can, grey floor, background
    colours = {tuple(c) for c in rgb.reshape(-1, 3)}
    assert any(c[0] > 150 and c[1] < 50 for c in colours)
    assert any(c[2] > 150 and c[0] < 50 for c in colours)
    assert any(c[1] > 80 and c[0] < 50 and c[2] < 50 for c in colours)


# -- the rasterizer against a brute-force per-pixel reference ------------------------------------
def _brute_force(tris_cam: np.ndarray, K: np.ndarray, W: int, H: int, cull: bool, margin: float = 1e-4):
    """Per pixel and triangle, in float64: inside (> margin px from every edge), outside, or too close to call.

    Returns face (H, W) (-1: none), depth (H, W) (inf: none) and ``sure`` (H, W): no triangle is
    within ``margin`` of an edge at that pixel and the nearest two depths there differ.
    """
    n = np.cross(tris_cam[:, 1] - tris_cam[:, 0], tris_cam[:, 2] - tris_cam[:, 0])
    uv = tris_cam @ K.T
    uv = uv[:, :, :2] / uv[:, :, 2:]
    yy, xx = np.mgrid[0:H, 0:W].astype(float)
    px = np.stack([xx.ravel(), yy.ravel()], axis=1)  # (P, 2)
    area = (uv[:, 1, 0] - uv[:, 0, 0]) * (uv[:, 2, 1] - uv[:, 0, 1]) - (uv[:, 2, 0] - uv[:, 0, 0]) * (uv[:, 1, 1] - uv[:, 0, 1])
    dist = []
    for i in range(3):  # signed distance in pixels to each edge, > 0 inside
        a, b = uv[:, i], uv[:, (i + 1) % 3]
        e = b - a
        cross = e[:, 0][None] * (px[:, 1][:, None] - a[:, 1][None]) - e[:, 1][None] * (px[:, 0][:, None] - a[:, 0][None])
        dist.append(np.sign(area)[None] * cross / np.hypot(e[:, 0], e[:, 1])[None])
    dmin = np.minimum(np.minimum(dist[0], dist[1]), dist[2])  # (P, F)
    usable = np.abs(area) > 1e-9
    if cull:
        usable &= np.einsum("ij,ij->i", n, tris_cam[:, 0]) < 0
    inside = (dmin > margin) & usable[None]
    unsure = (np.abs(dmin) <= margin) & usable[None]
    ray = np.column_stack([px, np.ones(len(px))]) @ np.linalg.inv(K).T  # Z = 1 along each ray
    with np.errstate(divide="ignore", invalid="ignore"):
        Z = (n * tris_cam[:, 0]).sum(axis=1)[None] / (ray @ n.T)  # the plane's Z along each ray
    Z = np.where(inside, Z, np.inf)
    order = np.argsort(Z, axis=1, kind="stable")
    z1 = np.take_along_axis(Z, order[:, :1], axis=1)[:, 0]
    z2 = np.take_along_axis(Z, order[:, 1:2], axis=1)[:, 0]
    face = np.where(np.isfinite(z1), order[:, 0], -1)
    with np.errstate(invalid="ignore"):  # inf - inf where nothing covers the pixel
        tie = np.isfinite(z2) & (z2 - z1 <= 1e-6 * z1)
    sure = ~unsure.any(axis=1) & ~tie
    return face.reshape(H, W), z1.reshape(H, W), sure.reshape(H, W)


@pytest.mark.parametrize("cull", [True, False])
def test_rasterizer_agrees_with_a_brute_force_reference(rng, cull):
    # a soup of interpenetrating triangles in front of the camera, some reaching past the image
    centres = np.column_stack([rng.uniform(-0.8, 0.8, (120, 2)), rng.uniform(1.0, 3.0, 120)])
    tris = centres[:, None, :] + rng.normal(0.0, 0.35, (120, 3, 3))
    tris[:, :, 2] = np.maximum(tris[:, :, 2], 0.3)
    K = CameraModel(64, 48, K=[[50.0, 0.0, 31.7], [0.0, 52.0, 23.2], [0, 0, 1]]).K
    face, depth = rasterize(tris, K, 64, 48, cull_backfaces=cull)
    want_face, want_depth, sure = _brute_force(tris, K, 64, 48, cull)
    assert sure.mean() > 0.9 and (want_face >= 0).mean() > 0.5
    np.testing.assert_array_equal(face[sure], want_face[sure])
    seen = sure & (want_face >= 0)
    np.testing.assert_allclose(depth[seen], want_depth[seen], rtol=1e-6)
    assert np.isinf(depth[sure & (want_face < 0)]).all()


def test_frames_past_2_to_the_24_fragments_take_the_integer_path(monkeypatch):
    # past 2**24 fragments, pixel offsets along spans are no longer exact in float32; the
    # integer path that takes over then must draw the same picture (forced here on a small one)
    import ejsrl.world._raster as raster

    w, cam, T = _golden_scene()
    want = render(w, cam, T, backend="numpy")
    monkeypatch.setattr(raster, "_F32_EXACT", 0)
    got = render(w, cam, T, backend="numpy")
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[1], want[1])


def test_far_plane_clips_per_pixel():
    # a plane tilted away from the camera crosses the far plane: pixels beyond it stay empty
    V = np.array([[-4, -1, 1.0], [4, -1, 1.0], [4, 1, 6.0], [-4, 1, 6.0]])
    tris = V[np.array([[0, 2, 1], [0, 3, 2]])]
    K = CameraModel(60, 60, fov_deg=90).K
    face, depth = rasterize(tris, K, 60, 60, far=3.0, cull_backfaces=False)
    _, depth_all = rasterize(tris, K, 60, 60, cull_backfaces=False)
    assert np.isfinite(depth_all).sum() > np.isfinite(depth).sum() > 300
    assert depth[np.isfinite(depth)].max() <= 3.0
    beyond = np.isfinite(depth_all) & (depth_all > 3.0 + 1e-6)
    assert beyond.sum() > 100 and (face[beyond] == -1).all() and np.isinf(depth[beyond]).all()


# -- choosing the back end -----------------------------------------------------------------------
def test_backend_choice_env_override_and_errors(monkeypatch):
    w, cam, T = _golden_scene()
    monkeypatch.setenv("EJSRL_RENDER_BACKEND", "numpy")
    assert _pick_backend("auto") == "numpy"
    rgb_auto, d_auto = render(w, cam, T)
    rgb_np, d_np = render(w, cam, T, backend="numpy")
    np.testing.assert_array_equal(rgb_auto, rgb_np)
    np.testing.assert_array_equal(d_auto, d_np)
    monkeypatch.setenv("EJSRL_RENDER_BACKEND", "vulkan")
    with pytest.raises(ValueError, match="EJSRL_RENDER_BACKEND"):
        render(w, cam, T)
    with pytest.raises(ValueError, match="unknown render backend 'opengl'"):
        render(w, cam, T, backend="opengl")


def test_gl_unavailable_falls_back_silently_for_auto_and_explains_for_gl(monkeypatch):
    # as on a machine without moderngl: the cached outcome of the first attempt says why
    pool = _gl._Pool(1)  # this process's contexts: none could be made, and the first attempt said why
    pool.failure = "moderngl is not installed (No module named 'moderngl')"
    monkeypatch.setattr(_gl, "_the_pool", pool)
    monkeypatch.delenv("EJSRL_RENDER_BACKEND", raising=False)
    w, cam, T = _golden_scene()
    assert _pick_backend("auto") == "numpy"
    rgb, depth = render(w, cam, T)
    np.testing.assert_array_equal(rgb, render(w, cam, T, backend="numpy")[0])
    with pytest.raises(_gl.GLUnavailableError, match="pip install moderngl") as info:
        render(w, cam, T, backend="gl")
    assert "libegl1" in str(info.value) and "not installed" in str(info.value)
