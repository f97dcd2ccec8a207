"""The OpenGL back end (moderngl on headless EGL) against the NumPy rasterizer and analytic depths.

scripts/setup.sh (the README's test command) installs moderngl and Mesa's EGL, so these
tests always run, and fail, saying why, if the back end cannot.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
import trimesh
from conftest import look_at

from ejsrl.robotics.transforms import r2t, rotx, rotz, transl
from ejsrl.vision import CameraModel
from ejsrl.world import World, render
from ejsrl.world import _gl
from ejsrl.world.scene import Box, Cylinder, MeshNode, Part, Sphere


def require_gl() -> None:
    """Fail, saying why, when the "gl" back end cannot run here."""
    if not _gl.available():
        pytest.fail(f"{_gl.describe()} (scripts/setup.sh installs what the OpenGL tests need)")


def _scene() -> World:
    w = World()
    w.add(Box("floor", size=(3, 3, 0.02), color="gray", T_parent_local=transl(0, 0, -0.01)))
    m = trimesh.creation.icosphere(subdivisions=3, radius=0.25)
    w.add(MeshNode("blob", mesh_parts=(Part(m.vertices, m.faces, (0.2, 0.7, 0.3)),), T_parent_local=transl(-0.2, 0.1, 0.25)))
    w.add(Box("crate", size=(0.25, 0.25, 0.25), color="blue", T_parent_local=transl(0.3, -0.1, 0.125) @ r2t(rotz(0.4))))
    w.add(Cylinder("can", radius=0.08, height=0.3, color="orange", T_parent_local=transl(0.1, 0.35, 0.15)))
    w.add(Sphere("ball", radius=0.1, color="red", T_parent_local=transl(0.35, 0.3, 0.1)))
    return w


def _edges(face: np.ndarray) -> np.ndarray:
    """(H, W) bool: pixels whose 3 x 3 neighbourhood sees more than one face (or the background)."""
    H, W = face.shape
    pad = np.pad(face, 1, mode="edge")
    edge = np.zeros((H, W), dtype=bool)
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            edge |= pad[dy : dy + H, dx : dx + W] != face
    return edge


CAMERAS = [
    CameraModel(640, 480, fov_deg=50),
    CameraModel(97, 61, fov_deg=70),  # odd sizes: rows not a multiple of 4 bytes
    CameraModel(200, 150, K=[[180, 0, 80.3], [0, 175, 90.7], [0, 0, 1]]),  # off-centre, non-square pixels
]


@pytest.mark.parametrize("cam", CAMERAS, ids=["640x480", "97x61", "offcentre-K"])
def test_gl_draws_what_numpy_draws_except_along_edges(cam: CameraModel):
    require_gl()
    w = _scene()
    T = look_at((0.9, -1.3, 0.9), (0.0, 0.0, 0.15))
    rgb_n, d_n = render(w, cam, T, backend="numpy")
    rgb_g, d_g = render(w, cam, T, backend="gl")
    assert rgb_g.shape == rgb_n.shape and rgb_g.dtype == np.uint8 and d_g.dtype == np.float32
    same = np.abs(rgb_n.astype(int) - rgb_g.astype(int)).max(axis=2) <= 2
    assert same.mean() >= 0.99, f"only {100 * same.mean():.2f} % of pixels agree"
    # every pixel that differs lies on an edge of the NumPy picture (triangle or silhouette)
    from ejsrl.world._raster import rasterize
    from ejsrl.world.rendering import _to_camera

    tris, _ = w.triangles()
    face, _ = rasterize(_to_camera(tris, T).transpose(2, 0, 1), cam.K, cam.width, cam.height, near=cam.near, far=cam.far)
    assert not (~same & ~_edges(face)).any()
    # depth: the same surfaces, to float32 rounding, wherever both see one
    both = np.isfinite(d_n) & np.isfinite(d_g)
    assert (np.isfinite(d_n) != np.isfinite(d_g)).mean() < 0.01
    rel = np.abs(d_g[both] - d_n[both]) / d_n[both]
    assert (rel <= 1e-4).mean() >= 0.99
    # the colours are the NumPy back end's to the bit away from edges
    inner = ~_edges(face)
    np.testing.assert_array_equal(rgb_g[inner], rgb_n[inner])


def test_gl_depth_equals_the_analytic_plane_distance():
    require_gl()
    w = World()
    V = np.array([[-3, -3, 0], [3, -3, 0], [3, 3, 0], [-3, 3, 0]], float)
    T_plane = r2t(rotx(0.5))
    w.add(MeshNode("p", mesh_parts=(Part(V, [[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]], (0.5, 0.6, 0.7)),), T_parent_local=T_plane))
    cam = CameraModel(120, 90, fov_deg=60)
    T_cam = look_at((0.3, -0.4, 1.5), (0, 0.1, 0))
    _, depth = render(w, cam, T_cam, backend="gl")
    assert np.isfinite(depth).all()
    Tcp = np.linalg.inv(T_cam) @ T_plane
    n_c, p0_c = Tcp[:3, 2], Tcp[:3, 3]
    yy, xx = np.mgrid[0:90, 0:120]
    xy = cam.normalized(np.column_stack([xx.ravel(), yy.ravel()]))
    Z = (n_c @ p0_c) / (xy @ n_c[:2] + n_c[2])
    np.testing.assert_allclose(depth.ravel(), Z, rtol=1e-5)


def test_gl_clips_at_the_near_and_far_planes_like_numpy():
    require_gl()
    w = World()
    V = np.array([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], float)
    w.add(MeshNode("floor", mesh_parts=(Part(V, [[0, 1, 2], [0, 2, 3]], (0.6, 0.6, 0.6)),)))
    cam = CameraModel(80, 60, fov_deg=70, near=0.05, far=2.0)
    T_cam = look_at((0, 0, 0.3), (0, 2, 0.0))  # the floor runs under the camera and past the far plane
    rgb_n, d_n = render(w, cam, T_cam, backend="numpy")
    rgb_g, d_g = render(w, cam, T_cam, backend="gl")
    drawn_n, drawn_g = np.isfinite(d_n), np.isfinite(d_g)
    assert drawn_n.sum() > 1000 and (~drawn_n).sum() > 500  # both planes cut something
    assert (drawn_n != drawn_g).mean() < 0.02  # only along the far cut
    assert d_g[drawn_g].max() <= 2.0 * (1 + 1e-5) and d_g[drawn_g].min() >= 0.05
    both = drawn_n & drawn_g
    np.testing.assert_allclose(d_g[both], d_n[both], rtol=1e-4)


@pytest.mark.parametrize("far", [100.0, np.inf])
def test_gl_separates_nearly_coplanar_surfaces_far_away(far):
    # a decal 0.1 mm in front of a wall 10 and 20 m away: with the usual 1 - near / Z depth
    # (near 1 cm) the wall would show through; both back ends must draw the decal
    require_gl()
    cam = CameraModel(40, 30, fov_deg=40, near=0.01, far=far)
    for Z in (10.0, 20.0):
        w = World()
        for name, z, colour in (("wall", Z + 1e-4, (1.0, 0.0, 0.0)), ("decal", Z, (0.0, 0.0, 1.0))):
            V = np.array([[-99, -99, z], [99, -99, z], [99, 99, z], [-99, 99, z]], float)
            w.add(MeshNode(name, mesh_parts=(Part(V, [[0, 2, 1], [0, 3, 2]], colour),)))
        for backend in ("numpy", "gl"):
            rgb, depth = render(w, cam, np.eye(4), backend=backend)
            assert (rgb[..., 2] > rgb[..., 0]).all(), (backend, Z)
            np.testing.assert_allclose(depth, Z, rtol=1e-6)


def test_gl_empty_scene_and_background():
    require_gl()
    w = World()
    rgb, depth = render(w, CameraModel(33, 17, fov_deg=40), np.eye(4), background=(0.1, 0.2, 0.3), backend="gl")
    assert np.isinf(depth).all()
    assert (rgb == np.rint(np.array([0.1, 0.2, 0.3]) * 255).astype(np.uint8)).all()


def test_auto_picks_gl_when_it_works():
    require_gl()
    from ejsrl.world.rendering import _pick_backend, available_backends

    assert available_backends() == ["numpy", "gl"]
    assert _pick_backend("auto") == "gl" or os.environ.get("EJSRL_RENDER_BACKEND", "auto") != "auto"


def test_projection_matrix_puts_pixel_centres_where_the_camera_model_does(rng):
    # no GL needed: the matrix alone, against CameraModel.project
    cam = CameraModel(200, 150, K=[[180, 2.0, 80.3], [0, 175, 90.7], [0, 0, 1]], near=0.1, far=7.0)
    M = _gl.projection_matrix(cam.K, cam.width, cam.height, cam.near, cam.far)
    P = np.column_stack([rng.uniform(-1, 1, (50, 2)), rng.uniform(0.1, 7.0, 50)])
    clip = np.column_stack([P, np.ones(50)]) @ M.T
    ndc = clip[:, :3] / clip[:, 3:]
    px = cam.project(P, np.eye(4))
    np.testing.assert_allclose((ndc[:, 0] + 1) * cam.width / 2 - 0.5, px[:, 0], atol=1e-9)
    np.testing.assert_allclose((ndc[:, 1] + 1) * cam.height / 2 - 0.5, px[:, 1], atol=1e-9)
    np.testing.assert_allclose(clip[:, 3], P[:, 2])
    z_ndc = lambda Z: (M[2, 2] * Z + M[2, 3]) / Z  # noqa: E731
    assert z_ndc(0.1) == pytest.approx(-1.0) and z_ndc(7.0) == pytest.approx(1.0)
    assert (np.diff(z_ndc(np.linspace(0.1, 7.0, 20))) > 0).all()
    M_inf = _gl.projection_matrix(cam.K, cam.width, cam.height, 0.1, np.inf)
    assert (M_inf[2, 2] * 0.1 + M_inf[2, 3]) / 0.1 == pytest.approx(-1.0)


def test_a_gl_render_lets_other_threads_run_while_it_rasterises():
    """A served class renders cameras in its stepper threads: while Mesa rasterises, the
    other sessions' Python must run (moderngl keeps the GIL; the back end waits for the
    pixels in a glFinish called without it). A 3000 x 3000 picture of a few faces spends
    most of its time filling pixels; a thread spinning meanwhile must never be held off for
    most of the render (holding the GIL in that wait, the longest hold measured 0.5-0.8 of
    it; letting go, 0.1-0.3, the rest being the copy of the pixels)."""
    import threading
    import time

    require_gl()
    w = World()
    m = trimesh.creation.icosphere(subdivisions=3, radius=0.5)
    w.add(MeshNode("blob", mesh_parts=(Part(m.vertices, m.faces, (0.2, 0.7, 0.3)),), T_parent_local=transl(0, 0, 0.5)))
    cam = CameraModel(3000, 3000, fov_deg=60)
    T = look_at((0.0, -1.5, 1.2), (0.0, 0.0, 0.5))
    render(w, cam, T, backend="gl")  # the context and targets made
    shares = []
    for _ in range(3):
        done = threading.Event()
        thread = threading.Thread(target=lambda: (render(w, cam, T, backend="gl"), done.set()))
        longest, start = 0.0, time.perf_counter()
        last = start
        thread.start()
        while not done.is_set():
            now = time.perf_counter()
            longest, last = max(longest, now - last), now
        thread.join()
        shares.append(longest / (time.perf_counter() - start))
    assert min(shares) < 0.35, f"the spinning thread was held off for {min(shares):.0%} of the render at best"


@pytest.mark.parametrize("realism", [None, "antialias", "smooth"])
@pytest.mark.parametrize("dictionary,marker_id", [("aruco_4x4_50", 7), ("apriltag_36h11", 5)])
def test_gl_draws_a_marker_texture_as_numpy_does_and_opencv_finds_it(dictionary: str, marker_id: int, realism: str | None):
    """A marker on a tilted plate: the GL image is NumPy's but for pixels on the cells' edges, and
    OpenCV's ArUco detector finds the marker in it at the scene's true corners."""
    import cv2

    from ejsrl.robotics.transforms import trotx
    from ejsrl.vision import look_at as look
    from ejsrl.vision.markers import detect_markers, marker_corners_3d
    from ejsrl.world.rendering import Realism

    require_gl()
    side = 0.1
    T_plate = transl(0.01, -0.02, 0.0) @ r2t(rotz(0.6)) @ trotx(0.4)
    w = World()
    w.add(Box("plate", size=(0.3, 0.3, 0.01), color="white", texture=f"{dictionary}:{marker_id}", texture_size=side, T_parent_local=T_plate))
    w.add(Box("floor", size=(1, 1, 0.01), color="gray", T_parent_local=transl(0, 0, -0.1)))
    cam = CameraModel(640, 480, fov_deg=50)
    T_cam = look([0.1, -0.3, 0.45], [0.0, 0.0, 0.0], [0, 0, 1])
    real = {None: None, "antialias": Realism(antialias=3), "smooth": Realism(shading="smooth")}[realism]
    rgb_np, depth_np = render(w, cam, T_cam, backend="numpy", realism=real)
    rgb_gl, depth_gl = render(w, cam, T_cam, backend="gl", realism=real)
    diff = np.abs(rgb_np.astype(int) - rgb_gl.astype(int)).max(axis=2)
    black = (rgb_np.max(axis=2) < 100).mean()
    assert black > 0.01  # the marker is there, and large
    assert (diff > 2).mean() < 0.004, f"{(diff > 2).mean():.4f} of the pixels differ"
    seen = np.isfinite(depth_np)
    assert np.array_equal(seen, np.isfinite(depth_gl))
    assert (np.abs(depth_np[seen] - depth_gl[seen]) > 2e-4).mean() < 0.004  # the decals' lift is 0.05 mm; edges aside
    # OpenCV's own detector (not ours) finds the marker in GL's pixels, where the scene has it
    aruco = cv2.aruco
    name = {"aruco_4x4_50": "DICT_4X4_50", "apriltag_36h11": "DICT_APRILTAG_36h11"}[dictionary]
    det = aruco.ArucoDetector(aruco.getPredefinedDictionary(getattr(aruco, name)))
    corners, ids, _ = det.detectMarkers(cv2.cvtColor(rgb_gl, cv2.COLOR_RGB2GRAY))
    assert ids is not None and ids.ravel().tolist() == [marker_id]
    T_world_marker = T_plate @ transl(0, 0, 0.005)
    truth = cam.project((T_world_marker @ np.column_stack([marker_corners_3d(side), np.ones(4)]).T).T[:, :3], T_cam)
    assert np.linalg.norm(corners[0].reshape(4, 2) - truth, axis=1).max() < 1.0
    ours = detect_markers(rgb_gl, dictionary)
    assert [m.id for m in ours] == [marker_id]
    assert np.linalg.norm(ours[0].corners - truth, axis=1).max() < (0.5 if realism == "antialias" else 0.8)
