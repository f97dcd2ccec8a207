"""The more realistic virtual camera: anti-aliasing, smooth shading, noise, blur, lens
distortion and depth, each checked for what a user notices, against analytic references
(the covered share of a pixel, a Gaussian's profile, ``CameraModel.distort_points``, the
distance to a plane), on both back ends, and the two back ends against each other.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
import pytest

from ejsrl.robotics.transforms import transl
from ejsrl.vision import CameraModel
from ejsrl.world import World, render
from ejsrl.world import _gl
from ejsrl.world.rendering import Realism, render_depth
from ejsrl.world.scene import Box, CameraNode, MeshNode, Part, Sphere

BACKENDS = ["numpy", "gl"]
W, H = 160, 120
F_PX = 150.0
H_CAM = 1.0  # the camera is 1 m above the floor, looking straight down
BLACK = (0.0, 0.0, 0.0)


@pytest.fixture(params=BACKENDS)
def backend(request) -> str:
    if request.param == "gl" and not _gl.available():
        pytest.fail(f"{_gl.describe()} (scripts/setup.sh installs what the OpenGL tests need)")
    return request.param


def _down() -> np.ndarray:
    """Camera pose 1 m above the origin looking down -z, image x along world x, image y along -y."""
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = (0.0, 0.0, H_CAM)
    return T


def _cam(**kw) -> CameraModel:
    return CameraModel(W, H, K=[[F_PX, 0, (W - 1) / 2], [0, F_PX, (H - 1) / 2], [0, 0, 1]], **kw)


def _u_of_x(x: float, depth: float) -> float:
    """Image column of world x seen at ``depth`` by the downward camera."""
    return F_PX * x / depth + (W - 1) / 2


def _plate(x_edge_u: float, depth: float = H_CAM, rgb: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> World:
    """A square plate (white), face up, on the floor, whose left edge is seen at column ``x_edge_u``."""
    x0 = (x_edge_u - (W - 1) / 2) * depth / F_PX
    V = np.array([[x0, -0.3, 0], [x0 + 0.6, -0.3, 0], [x0 + 0.6, 0.3, 0], [x0, 0.3, 0]])
    w = World()
    w.add(MeshNode("plate", mesh_parts=(Part(V, [[0, 1, 2], [0, 2, 3]], rgb),), T_parent_local=transl(0, 0, H_CAM - depth)))
    return w


def _realism(**kw) -> Realism:
    return Realism(**kw)


# -- defaults: the plain render, bit for bit --------------------------------------------------------
def test_a_camera_that_asks_for_nothing_renders_bit_for_bit_as_before(backend: str) -> None:
    w = World()
    w.add(Box("floor", size=(3, 3, 0.02), color="gray", T_parent_local=transl(0, 0, -0.01)))
    w.add(Box("crate", size=(0.25, 0.25, 0.25), color="blue", T_parent_local=transl(0.1, 0.05, 0.125)))
    w.add(Sphere("ball", radius=0.1, color="red", T_parent_local=transl(-0.2, 0.1, 0.1)))
    w.add(CameraNode("cam", T_parent_local=_down(), intrinsics=_cam().K, resolution=(W, H)))
    rgb0, d0 = render(w, _cam(), _down(), backend=backend)  # a CameraModel: the plain pinhole path
    for realism in (None, Realism()):
        rgb, d = render(w, "cam", backend=backend, realism=realism)
        assert np.array_equal(rgb, rgb0) and np.array_equal(d, d0)
    assert np.array_equal(render_depth(w, "cam", backend=backend), d0)


# -- anti-aliasing ----------------------------------------------------------------------------------
@pytest.mark.parametrize("s", [1, 5])
def test_antialiasing_gives_an_edge_pixel_its_covered_share(backend: str, s: int) -> None:
    # the plate's left edge at column 80.1: pixel 80 ([79.5, 80.5]) is 40 % white
    w = _plate(80.1)
    rgb, _ = render(w, _cam(), _down(), backend=backend, background=BLACK, realism=_realism(antialias=s))
    white = float(rgb[60, 100, 0])
    assert white > 200 and rgb[60, 60, 0] == 0
    edge = rgb[20:100, 80, 0].astype(float) / white
    levels = np.unique(rgb[20:100, 70:95, 0])
    if s == 1:  # aliased: only black and white, the edge pixel all one or the other
        assert len(levels) == 2 and set(np.unique(edge)) <= {0.0, 1.0}
    else:  # five samples across, two of them on the plate: 40 % grey, the same all down the edge
        assert len(levels) == 3
        np.testing.assert_allclose(edge, 0.4, atol=0.01)


def test_antialiasing_keeps_the_depth_at_the_pixel_centres(backend: str) -> None:
    w = World()
    w.add(Box("floor", size=(4, 4, 0.02), color="gray", T_parent_local=transl(0, 0, -0.01)))
    T = np.array(_down())
    T[:3, :3] = T[:3, :3] @ np.array([[1, 0, 0], [0, math.cos(0.5), -math.sin(0.5)], [0, math.sin(0.5), math.cos(0.5)]])
    ref = _plane_depth(T)
    for s in (2, 3):
        d = render(w, _cam(), T, backend=backend, realism=_realism(antialias=s))[1]
        np.testing.assert_allclose(d, ref, rtol=2e-5)


# -- noise -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("sigma", [2.0, 6.0])
def test_noise_has_the_asked_standard_deviation_on_a_flat_face(backend: str, sigma: float) -> None:
    w = World()  # mid grey fills the image: no clipping at 0 or 255
    w.add(Box("floor", size=(6, 6, 0.02), color=(0.5, 0.5, 0.5), T_parent_local=transl(0, 0, -0.01)))
    clean, _ = render(w, _cam(), _down(), backend=backend, background=BLACK)
    noisy, _ = render(w, _cam(), _down(), backend=backend, background=BLACK, realism=_realism(noise=sigma),
                      rng=np.random.default_rng(1))
    diff = noisy.astype(float) - clean.astype(float)
    assert abs(diff.std() - sigma) <= 0.1 * sigma, diff.std()
    assert abs(diff.mean()) < 0.1
    # independent from pixel to pixel and channel to channel
    assert abs(np.corrcoef(diff[:, :-1, 0].ravel(), diff[:, 1:, 0].ravel())[0, 1]) < 0.05
    assert abs(np.corrcoef(diff[..., 0].ravel(), diff[..., 1].ravel())[0, 1]) < 0.05


def test_a_camera_nodes_noise_changes_from_frame_to_frame_and_repeats_from_run_to_run() -> None:
    def frames() -> list[np.ndarray]:
        w = _plate(-40.0)
        w.add(CameraNode("cam", T_parent_local=_down(), intrinsics=_cam().K, resolution=(W, H), noise=3.0))
        return [render(w, "cam", backend="numpy")[0] for _ in range(2)]

    a, b = frames(), frames()
    assert not np.array_equal(a[0], a[1])
    assert all(np.array_equal(x, y) for x, y in zip(a, b))


# -- blur ------------------------------------------------------------------------------------------
def _phi(x: np.ndarray) -> np.ndarray:
    from math import erf

    return 0.5 * (1.0 + np.vectorize(erf)(x / math.sqrt(2.0)))


@pytest.mark.parametrize("sigma", [1.0, 2.5])
def test_blur_turns_an_edge_into_a_gaussian_profile(backend: str, sigma: float) -> None:
    w = _plate(79.5)  # a sharp step between columns 79 (black) and 80 (white)
    sharp, _ = render(w, _cam(), _down(), backend=backend, background=BLACK)
    assert sharp[60, 79, 0] == 0 and sharp[60, 80, 0] > 200
    blurred, _ = render(w, _cam(), _down(), backend=backend, background=BLACK, realism=_realism(blur=sigma))
    white = float(sharp[60, 100, 0])
    cols = np.arange(60, 100)
    profile = blurred[60, cols, 0].astype(float) / white
    np.testing.assert_allclose(profile, _phi((cols - 79.5) / sigma), atol=0.02)
    # the 10-90 % rise is 2.563 sigma wide
    rise = np.interp(0.9, profile, cols) - np.interp(0.1, profile, cols)
    assert rise == pytest.approx(2.563 * sigma, rel=0.1)


# -- lens distortion -------------------------------------------------------------------------------
DIST = (-0.25, 0.08, 0.002, -0.001, 0.0)


def _marker_world(x: float, y: float) -> World:
    """A white floor and a small black square at (x, y)."""
    w = World()
    w.add(Box("floor", size=(6, 6, 0.02), color="white", T_parent_local=transl(0, 0, -0.01)))
    w.add(Box("marker", size=(0.02, 0.02, 0.002), color="black", T_parent_local=transl(x, y, 0.001)))
    return w


@pytest.mark.parametrize("xy", [(0.35, 0.25), (-0.42, -0.3), (0.05, -0.02)])
def test_distortion_moves_a_point_where_the_camera_model_says(backend: str, xy: tuple[float, float]) -> None:
    w = _marker_world(*xy)
    lens = _cam(distortion=DIST)
    ideal = _cam().project(np.array([[xy[0], xy[1], 0.001]]), _down())
    expected = lens.distort_points(ideal)[0]
    rgb, depth = render(w, _cam(), _down(), backend=backend, realism=_realism(antialias=4, distortion=DIST))
    dark = 255.0 - rgb[..., 0].astype(float)
    dark[dark < 20] = 0.0
    rows, cols = np.indices(dark.shape)
    found = np.array([(dark * cols).sum(), (dark * rows).sum()]) / dark.sum()
    assert np.linalg.norm(found - expected) < 0.5, (found, expected)
    assert np.linalg.norm(found - ideal[0]) > (2.0 if abs(xy[0]) > 0.2 else 0.0)  # the lens did move it
    # barrel distortion pulls no black border in: the render has a margin
    assert rgb[[0, 0, -1, -1], [0, -1, 0, -1]].min() > 200 and np.isfinite(depth).all()


# -- depth -----------------------------------------------------------------------------------------
def _plane_depth(T: np.ndarray, cam: CameraModel | None = None) -> np.ndarray:
    """Analytic Z of the floor plane z = 0 at every pixel centre of a camera at pose ``T``."""
    cam = cam or _cam()
    v, u = np.mgrid[0:H, 0:W]
    rays = np.linalg.inv(cam.K) @ np.stack([u.ravel(), v.ravel(), np.ones(u.size)])  # Z = 1
    R, t = T[:3, :3], T[:3, 3]
    dz = (R @ rays)[2]  # world z change per unit of Z
    with np.errstate(divide="ignore"):
        Z = -t[2] / dz
    Z[~(Z > 0)] = np.inf
    return Z.reshape(H, W)


def test_capture_depth_equals_the_distance_to_a_box_and_a_plane(backend: str) -> None:
    w = World()
    w.add(Box("floor", size=(6, 6, 0.02), color="gray", T_parent_local=transl(0, 0, -0.01)))
    w.add(Box("crate", size=(0.3, 0.3, 0.4), color="blue", T_parent_local=transl(0.0, 0.0, 0.2)))
    T = np.array(_down())
    w.add(CameraNode("cam", T_parent_local=T, intrinsics=_cam().K, resolution=(W, H), antialias=3, noise=5.0, blur=2.0))
    d = render_depth(w, "cam", backend=backend)
    # the box top (0.4 m up) is 0.6 m away; the floor around it 1 m (0.3 m box: 45 px square)
    assert d[60, 80] == pytest.approx(0.6, rel=1e-6) and d[5, 5] == pytest.approx(1.0, rel=1e-6)
    top = np.abs(np.arange(W) - (W - 1) / 2) < 0.15 * F_PX / 0.6 - 1
    assert np.allclose(d[60, top], 0.6, rtol=1e-6)
    # a tilted view of the floor alone: Z along the ray, at every pixel
    w2 = World()
    w2.add(Box("floor", size=(20, 20, 0.02), color="gray", T_parent_local=transl(0, 0, -0.01)))
    T2 = np.array(T)
    T2[:3, :3] = T2[:3, :3] @ np.array([[1, 0, 0], [0, math.cos(0.6), -math.sin(0.6)], [0, math.sin(0.6), math.cos(0.6)]])
    w2.add(CameraNode("cam", T_parent_local=T2, intrinsics=_cam().K, resolution=(W, H)))
    np.testing.assert_allclose(render_depth(w2, "cam", backend=backend), _plane_depth(T2), rtol=2e-5)


def test_a_distorted_cameras_depth_is_the_depth_seen_through_the_lens(backend: str) -> None:
    w = World()
    w.add(Box("floor", size=(20, 20, 0.02), color="gray", T_parent_local=transl(0, 0, -0.01)))
    T = np.array(_down())
    T[:3, :3] = T[:3, :3] @ np.array([[1, 0, 0], [0, math.cos(0.6), -math.sin(0.6)], [0, math.sin(0.6), math.cos(0.6)]])
    w.add(CameraNode("cam", T_parent_local=T, intrinsics=_cam().K, resolution=(W, H), distortion=list(DIST)))
    d = render_depth(w, "cam", backend=backend)
    # the pixel sees the floor along the ray of its undistorted position
    v, u = np.mgrid[0:H, 0:W]
    ideal = _cam(distortion=DIST).undistort_points(np.column_stack([u.ravel(), v.ravel()]).astype(float))
    rays = np.linalg.inv(_cam().K) @ np.vstack([ideal.T, np.ones(len(ideal))])
    Z = (-T[2, 3] / (T[:3, :3] @ rays)[2]).reshape(H, W)
    # nearest-pixel resampling: within the depth change of half a pixel
    step = np.abs(np.gradient(Z)).max()
    assert np.abs(d - Z).max() <= step
    assert np.abs(d - _plane_depth(T)).max() > 5 * step  # and not the pinhole depth


# -- smooth shading --------------------------------------------------------------------------------
def test_smooth_shading_rounds_a_sphere_and_leaves_a_box_flat(backend: str) -> None:
    w = World()
    w.add(Sphere("ball", radius=0.3, color="white", T_parent_local=transl(0, 0, 0)))
    T = np.array(_down())
    T[:3, :3] = T[:3, :3] @ np.array([[1, 0, 0], [0, math.cos(0.5), -math.sin(0.5)], [0, math.sin(0.5), math.cos(0.5)]])
    T[:3, 3] = (0.0, -0.5, 0.9)
    flat, _ = render(w, _cam(), T, backend=backend)
    smooth, _ = render(w, _cam(), T, backend=backend, realism=_realism(shading="smooth"))
    inside = np.isfinite(render(w, _cam(), T, backend="numpy")[1])
    core = inside.copy()
    for _ in range(3):
        core[1:-1, 1:-1] &= core[:-2, 1:-1] & core[2:, 1:-1] & core[1:-1, :-2] & core[1:-1, 2:]

    def kinks(img: np.ndarray) -> np.ndarray:
        """|second difference| along rows inside the sphere: a step between facets shows as a large one."""
        return np.abs(np.diff(img[..., 0].astype(int), 2, axis=1))[core[:, 2:] & core[:, 1:-1] & core[:, :-2]]

    assert kinks(flat).max() >= 20  # facets: steps between neighbouring pixels
    assert kinks(smooth).max() <= 6  # a round surface: the shade changes gradually
    # a box's faces meet at 90 degrees, past the crease angle: it stays flat
    wb = World()
    wb.add(Box("crate", size=(0.3, 0.3, 0.3), color="orange", T_parent_local=transl(0, 0, 0.15)))
    b_flat, _ = render(wb, _cam(), T, backend=backend)
    b_smooth, _ = render(wb, _cam(), T, backend=backend, realism=_realism(shading="smooth"))
    assert np.abs(b_flat.astype(int) - b_smooth).max() <= (0 if backend == "numpy" else 1)


# -- checker texture -------------------------------------------------------------------------------
def _checker_box(x: float = 0.0) -> World:
    w = World()
    w.add(Box("crate", size=(0.4, 0.4, 0.4), color=(1.0, 0.6, 0.2), texture="checker", texture_size=0.1,
              T_parent_local=transl(x, 0.0, 0.2)))
    return w


def test_a_checker_texture_shows_squares_that_stay_on_the_object(backend: str) -> None:
    # the box top, 0.6 m below the camera, seen head on: squares of 0.1 m are 25 px across
    rgb, _ = render(_checker_box(), _cam(), _down(), backend=backend, background=BLACK)
    px = 0.1 * F_PX / 0.6
    centres = (np.arange(4) - 1.5) * px
    level = np.array([[rgb[int(round((H - 1) / 2 + cy)), int(round((W - 1) / 2 + cx)), 0] for cx in centres] for cy in centres], dtype=float)
    bright = level.max()
    parity = (np.add.outer(np.arange(4), np.arange(4)) % 2).astype(bool)
    # alternate squares, the dark ones 0.4 times as bright (to a grey level)
    assert np.all(level[parity] == level[parity][0]) and np.all(level[~parity] == level[~parity][0])
    assert min(level[parity][0], level[~parity][0]) == pytest.approx(0.4 * bright, abs=1.0)
    # whole squares from the face's centre lines: the colour changes exactly there
    row = rgb[int((H - 1) / 2 + 0.5 * px), :, 0].astype(int)  # through the middle of a row of squares
    changes = np.flatnonzero(np.diff(row)) + 0.5
    np.testing.assert_allclose(changes, (W - 1) / 2 + np.arange(-2, 3) * px, atol=1.0)
    # moved by one square, the pattern moves with the box
    moved, _ = render(_checker_box(0.1), _cam(), _down(), backend=backend, background=BLACK)
    shift = int(round(0.1 * F_PX / 0.6))
    a, b = rgb[30:90, 45:100], moved[30:90, 45 + shift : 100 + shift]
    assert (a != b).any(axis=2).mean() < 0.03  # the same squares, 25 px (0.1 m) to the right
    # without a texture the top is one colour
    plain = World()
    plain.add(Box("crate", size=(0.4, 0.4, 0.4), color=(1.0, 0.6, 0.2), T_parent_local=transl(0.0, 0.0, 0.2)))
    assert len(np.unique(render(plain, _cam(), _down(), backend=backend, background=BLACK)[0][40:80, 60:100, 0])) == 1


def test_an_unknown_texture_names_the_object_and_the_choices() -> None:
    w = World()
    w.add(Box("crate", size=(0.4, 0.4, 0.4), texture="marble"))
    with pytest.raises(ValueError, match="'crate': texture 'marble' is not one of 'checker'"):
        render(w, _cam(), _down(), backend="numpy")


# -- the two back ends -----------------------------------------------------------------------------
def test_gl_and_numpy_agree_with_every_option_on() -> None:
    if not _gl.available():
        pytest.fail(_gl.describe())
    w = World()
    w.add(Box("floor", size=(3, 3, 0.02), color="gray", T_parent_local=transl(0, 0, -0.01)))
    w.add(Box("crate", size=(0.25, 0.25, 0.25), color="blue", T_parent_local=transl(0.1, 0.05, 0.125)))
    w.add(Sphere("ball", radius=0.12, color="red", T_parent_local=transl(-0.2, 0.1, 0.12)))
    w.add(Box("tiles", size=(0.3, 0.2, 0.1), color="white", texture="checker", texture_size=0.04, T_parent_local=transl(0.25, -0.2, 0.05)))
    T = np.array(_down())
    T[:3, :3] = T[:3, :3] @ np.array([[1, 0, 0], [0, math.cos(0.5), -math.sin(0.5)], [0, math.sin(0.5), math.cos(0.5)]])
    T[:3, 3] = (0.0, -0.6, 0.9)
    r = _realism(antialias=3, shading="smooth", noise=2.0, blur=0.8, distortion=DIST)
    rgb_n, d_n = render(w, _cam(), T, backend="numpy", realism=r, rng=np.random.default_rng(7))
    rgb_g, d_g = render(w, _cam(), T, backend="gl", realism=r, rng=np.random.default_rng(7))
    diff = np.abs(rgb_n.astype(int) - rgb_g).max(axis=2)
    assert (diff <= 2).mean() >= 0.99 and diff.max() <= 12, (diff <= 2).mean()
    both = np.isfinite(d_n) & np.isfinite(d_g)
    assert (np.abs(d_n[both] - d_g[both]) / d_n[both] <= 1e-4).mean() >= 0.99


# -- the options in a spec -------------------------------------------------------------------------
def test_invalid_options_say_what_is_allowed() -> None:
    with pytest.raises(ValueError, match="antialias must be a whole number from 1"):
        Realism(antialias=0)
    with pytest.raises(ValueError, match="shading must be one of 'flat', 'smooth'"):
        Realism(shading="phong")
    with pytest.raises(ValueError, match="noise must be a number >= 0"):
        Realism(noise=-1.0)
    with pytest.raises(ValueError, match=r"distortion takes \[k1, k2, p1, p2, k3\]"):
        Realism(distortion=(0.1, 0.2, 0.3))


def test_a_specs_camera_options_reach_capture_and_capture_depth(tmp_path: Path) -> None:
    from testkit.robots import load_built

    from ejsgen.cli import build

    spec = tmp_path / "cam.ejs.yaml"
    spec.write_text(textwrap.dedent("""\
        ejs: 1
        title: Camera options
        model:
          variables:
            t: 0.0
            sigma: 3.0
            img: {expr: "np.zeros((1, 1, 3))"}
            depth: {expr: "np.zeros((1, 1))"}
          custom: |
            def shoot():
                img = capture("cam")
                depth = capture_depth("cam")
        view:
          - scene:
              - box: {name: floor, size: [6, 6, 0.02], position: [0, 0, -0.01], color: white}
              - box: {name: marker, size: [0.2, 0.2, 0.002], position: [0.3, 0.2, 0.001], color: black}
              - box: {name: tiles, size: [0.4, 0.4, 0.01], position: [-0.3, -0.2, 0.005], color: white,
                      texture: checker, texture_size: 0.1}
              - camera: {name: cam, position: [0, 0, 1], rotation: [3.141592653589793, 0, 0], fov: 60,
                         resolution: [160, 120], antialias: 2, noise: sigma, blur: 0.5,
                         distortion: [-0.2, 0.05, 0, 0, 0], shading: smooth}
        """), encoding="utf-8")
    app = load_built(build(spec, tmp_path / "app"))
    img = app.model.capture("cam")
    depth = app.model.capture_depth("cam")
    assert img.shape == (120, 160, 3) and depth.shape == (120, 160) and depth.dtype == np.float32
    assert depth[60, 80] == pytest.approx(1.0, abs=1e-6)  # straight down onto the floor, 1 m
    assert 1.5 < np.std(img[5:15, 60:90, 0].astype(float)) < 4.5  # the noise of sigma = 3 on white-ish floor
    tiles = img[70:95, 35:62, 0].astype(float)  # the checkered tiles: two clusters of grey levels
    assert np.percentile(tiles, 25) < 0.55 * np.percentile(tiles, 75)
    assert app.world["tiles"].props["texture"] == "checker"
    node = app.world["cam"]
    assert node.props["antialias"] == 2 and node.props["shading"] == "smooth"
    assert list(node.props["distortion"]) == [-0.2, 0.05, 0, 0, 0] and node.props["noise"] == 3.0
