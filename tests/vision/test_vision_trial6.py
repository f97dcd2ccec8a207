"""Issue 15, new-user trial 6: what a first user of ejsrl.vision tripped on.

1. ``detect_features(img, "brisk")`` died with AttributeError (OpenCV 5 has no BRISK in its
   main package): every method either works or is refused with a ValueError naming those
   that work here.
2. Input gaps: NaN and complex images went through ``distance_transform``/``skeleton``/
   ``split_touching``/``gaussian_pyramid``/``hu_moments``, int64 made ``hu_moments`` raise
   cv2.error, tiny images made ``find_chessboard`` raise cv2.error. A sweep over every public
   image-taking function (in a child interpreter, so a crash is a failed case).
3. ``susan_corners`` out-of-range parameters (the patch is the lead's, in _susan.py).
4. The reference's imports and names are importable where it says.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys

import cv2
import numpy as np
import pytest
from testkit.isolated import run_surviving_crashes

import ejsrl.vision as V
from testkit import ROOT

# --- 1. feature detectors -----------------------------------------------------------------------


def _textured(h: int = 120, w: int = 160) -> np.ndarray:
    rng = np.random.default_rng(3)
    img = cv2.resize((rng.random((h // 8, w // 8)) * 255).astype(np.uint8), (w, h), interpolation=cv2.INTER_NEAREST)
    return img


def _opencv_has(cls: str) -> bool:
    """Independent of ejsrl: does the installed cv2 construct this detector under any name?"""
    for mod in (cv2, getattr(cv2, "xfeatures2d", None)):
        if mod is None:
            continue
        for make in (getattr(getattr(mod, cls, None), "create", None), getattr(mod, f"{cls}_create", None)):
            if make is not None:
                try:
                    make()
                    return True
                except cv2.error:
                    pass
    return False


@pytest.mark.parametrize("method", ["orb", "sift", "akaze", "kaze", "brisk"])
def test_every_feature_method_works_or_is_refused_naming_the_ones_that_do(method):
    img = _textured()
    if _opencv_has(method.upper()):
        f = V.detect_features(img, method, max_features=50)
        assert 0 < len(f) <= 50 and f.descriptors.shape[0] == len(f)
        assert method in V.feature_methods()
    else:
        with pytest.raises(ValueError) as e:
            V.detect_features(img, method)
        msg = str(e.value)
        assert method.upper() in msg and "opencv-contrib-python" in msg
        for ok in V.feature_methods():
            assert repr(ok) in msg
        assert method not in V.feature_methods()


def test_feature_methods_lists_exactly_what_this_opencv_has():
    expected = [m for m in ("orb", "sift", "akaze", "kaze", "brisk") if _opencv_has(m.upper())]
    assert list(V.feature_methods()) == expected
    assert {"orb", "sift"} <= set(expected)  # the main package's, OpenCV 4 and 5


def test_an_unknown_feature_method_is_a_value_error_listing_the_known_ones():
    with pytest.raises(ValueError, match=r"unknown feature method 'surf'.*'orb', 'sift'"):
        V.detect_features(_textured(), "surf")


def test_the_other_detectors_the_runtime_builds_exist_in_this_opencv():
    img = np.zeros((120, 160), np.uint8)
    cv2.fillPoly(img, [np.array([[30, 20], [130, 30], [110, 100], [40, 90]], np.int32)], 220)
    assert len(V.fast_corners(V.gaussian_blur(img))) >= 4  # FastFeatureDetector
    assert len(V.orb_features(_textured())[0]) > 0  # ORB


def test_the_reference_promises_only_the_feature_methods_that_exist():
    text = (ROOT / "specs" / "reference.md").read_text()
    line = next(ln for ln in text.splitlines() if "detect_features(img" in ln)
    promised = re.findall(r'"(\w+)"', line.split("max_features")[0])
    assert promised and set(promised) <= set(V.feature_methods()), line


# --- 2. input validation ------------------------------------------------------------------------


def _nan_image() -> np.ndarray:
    a = np.full((24, 24), 0.5)
    a[5, 7] = np.nan
    return a


BAD = {
    "nan": "np.where(np.arange(24 * 24).reshape(24, 24) == 50, np.nan, 0.5)",
    "complex": "np.ones((24, 24), np.complex128)",
    "empty": "np.zeros((0, 0), np.uint8)",
}
#: valid by the shared rules (integers in 0..255, tiny but not empty): a result or a ValueError
ODD = {
    "int64": "(np.arange(24 * 24).reshape(24, 24) % 200).astype(np.int64)",
    "1x1": "np.full((1, 1), 128, np.uint8)",
    "2x2": "np.full((2, 2), 128, np.uint8)",
    "8x8": "np.eye(8, dtype=np.uint8) * 255",
    "3x40": "np.full((3, 40), 128, np.uint8)",
    "8x8x3": "np.full((8, 8, 3), 128, np.uint8)",
}
GOOD = "np.tile(np.arange(0, 240, 10, dtype=np.uint8), (24, 1))"
PTS = "np.array([[3.0, 4.0], [10.0, 12.0]])"

#: how to call each public function that takes an image, with the bad image ``b``
SPECIAL = {
    "convolve": "V.convolve(b, np.ones((3, 3)) / 9)",
    "warp_affine": "V.warp_affine(b, np.eye(2, 3))",
    "warp_perspective": "V.warp_perspective(b, np.eye(3))",
    "crop": "V.crop(b, 0, 0, 1, 1)",
    "rotate": "V.rotate(b, 30)",
    "resize": "V.resize(b, (10, 10))",
    "color_mask": "V.color_mask(b, (0, 0, 0), (179, 255, 255))",
    "color_segment": "V.color_segment(b, 'red')",
    "match_template": "V.match_template(b, np.full((1, 1), 7, np.uint8))",
    "lk_track": "V.lk_track(b, b, np.array([[0.0, 0.0]]))",
    "draw_points": f"V.draw_points(b, {PTS})",
    "draw_lines": "V.draw_lines(b, [[0, 0, 5, 5]])",
    "draw_boxes": "V.draw_boxes(b, [[0, 0, 5, 5]])",
    "draw_circles": "V.draw_circles(b, [[5, 5, 3]])",
    "draw_contours": f"V.draw_contours(b, [{PTS}])",
    "draw_text": "V.draw_text(b, 'hi')",
    "optical_flow": "V.optical_flow(b, b)",
    "optical_flow dis": "V.optical_flow(b, b, 'dis')",
    "warp_by_flow": "V.warp_by_flow(b, np.zeros(np.shape(b)[:2] + (2,), np.float32))",
    "watershed": "V.watershed(b, np.ones(np.shape(b)[:2], np.int32))",
    "disparity": "V.disparity(b, b)",
    "disparity bm": "V.disparity(b, b, method='bm')",
    "find_chessboard": "V.find_chessboard(b, (3, 3))",
    "draw_chessboard": "V.draw_chessboard(b, (3, 3), None)",
    "calibrate_chessboard": "V.calibrate_chessboard([b, b, b], (3, 3), 0.02)",
    "detect_features sift": "V.detect_features(b, 'sift')",
    "ellipse_from_moments": "V.ellipse_from_moments(b)",
    "hu_moments binary": "V.hu_moments(b, binary=True)",
    "CameraModel.undistort": "V.CameraModel(np.shape(b)[1], np.shape(b)[0], 60, distortion=[0.1, 0, 0, 0, 0]).undistort(b)",
    "CameraModel.distort": "V.CameraModel(np.shape(b)[1], np.shape(b)[0], 60, distortion=[0.1, 0, 0, 0, 0]).distort(b)",
    "StereoRectification.rectify": (
        "V.stereo_rectify(V.CameraModel(np.shape(b)[1], np.shape(b)[0], 60), V.CameraModel(np.shape(b)[1], "
        "np.shape(b)[0], 60), np.array([[1, 0, 0, 0.1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])).rectify(b, b)"
    ),
    "Pipeline.run": "V.Pipeline('gray', 'blur', 'canny').run(b)",
    "depth_to_points": "V.depth_to_points(b, V.CameraModel(max(1, np.shape(b)[1]), max(1, np.shape(b)[0]), 60))",
}
#: public callables that take no image (points, poses, colours, classes): checked elsewhere
NO_IMAGE = {
    "structuring_element", "affine_matrix", "perspective_matrix", "Region", "Pipeline", "PipelineResult",
    "CameraModel", "intrinsics_from_fov", "look_at", "pose_from_rvec", "xyz_to_rgb", "xyz_to_lab", "lab_to_xyz",
    "lab_to_rgb", "delta_e", "flow_magnitude", "collapse_laplacian_pyramid", "Features", "feature_methods",
    "match_features", "find_homography", "find_fundamental", "find_essential", "recover_pose", "epipolar_distances",
    "StereoRectification", "stereo_rectify", "depth_from_disparity", "triangulate", "Calibration", "calibrate_camera",
    "chessboard_points", *V._servo.__all__,
    "Marker", "marker_bits", "marker_image", "marker_pose", "IcpResult", "best_rigid_transform", "estimate_normals", "icp",
    "transform_points", "voxel_downsample", "ImageSource",
}  # fmt: skip
#: functions that move pixel values without judging them (a depth map's inf/NaN stays): NaN is a valid input
MOVES_VALUES = {"CameraModel.undistort", "CameraModel.distort", "StereoRectification.rectify", "depth_to_points"}


def sweep_calls() -> dict[str, str]:
    table = {n: f"V.{n}(b)" for n in V.__all__ if callable(getattr(V, n)) and n not in NO_IMAGE}
    table.update(SPECIAL)
    return table


_CHILD = r"""
import json, sys, warnings
import numpy as np
import ejsrl.vision as V
warnings.simplefilter("error", np.exceptions.ComplexWarning)  # a complex image silently made real is a failure
calls, inputs = json.loads(sys.argv[1]), json.loads(sys.argv[2])
for name, call in calls.items():
    for case, expr in inputs.items():
        print(json.dumps({"item": [name, case], "started": True}), flush=True)
        b = eval(expr)
        try:
            eval(call)
            res = {"ok": True}
        except BaseException as e:
            res = {"raised": type(e).__name__, "message": str(e)[:300]}
        res["item"] = [name, case]
        print(json.dumps(res), flush=True)
"""


@pytest.fixture(scope="module")
def sweep() -> dict[tuple[str, str], dict]:
    """Every (function, input) run in child interpreters; a crash is recorded and the rest go on."""
    calls, inputs = sweep_calls(), {**BAD, **ODD}
    return run_surviving_crashes({(n, c) for n in calls for c in inputs},
                                 lambda pending: [sys.executable, "-c", _CHILD, json.dumps({n: calls[n] for n in sorted({n for n, _ in pending})}), json.dumps(inputs)])


def test_the_sweep_covers_every_public_vision_function():
    public = {n for n in V.__all__ if callable(getattr(V, n))}
    assert public - NO_IMAGE <= set(sweep_calls())
    assert NO_IMAGE <= public  # no stale names


@pytest.mark.parametrize("case", list(BAD) + list(ODD))
def test_every_image_function_refuses_bad_images_with_a_value_error_and_never_crashes(sweep, case):
    problems = []
    for (name, c), got in sorted(sweep.items()):
        if c != case:
            continue
        if "crashed" in got:
            problems.append(f"{name}: the interpreter died ({got['crashed']}): {got['stderr']}")
        elif "raised" in got and got["raised"] != "ValueError":
            problems.append(f"{name}: {got['raised']}: {got['message']}")
        elif "raised" in got and len(got["message"]) < 25:
            problems.append(f"{name}: unhelpful message {got['message']!r}")
        elif got.get("ok") and case in BAD and not (case == "nan" and name in MOVES_VALUES):
            problems.append(f"{name}: accepted a {case} image silently")
    assert not problems, f"{case} image:\n" + "\n".join(problems)


@pytest.mark.parametrize("fn", ["distance_transform", "skeleton", "split_touching", "gaussian_pyramid", "hu_moments"])
@pytest.mark.parametrize("bad", ["nan", "complex"])
def test_the_trial_s_nan_and_complex_images_are_refused_with_what_to_do(fn, bad):
    img = _nan_image() if bad == "nan" else np.ones((24, 24), np.complex128)
    with pytest.raises(ValueError, match="NaN" if bad == "nan" else "dtype complex128"):
        getattr(V, fn)(img)


@pytest.mark.parametrize(
    "call",
    [lambda: V.xyz_to_lab(np.ones((2, 3), np.complex128)), lambda: V.lab_to_rgb(np.ones((2, 3), np.complex128)),
     lambda: V.flow_magnitude(np.ones((4, 4, 2), np.complex64)), lambda: V.flow_magnitude(np.full((4, 4, 2), np.nan)),
     lambda: V.warp_by_flow(np.zeros((4, 4), np.uint8), np.full((4, 4, 2), np.nan))],
    ids=["xyz_to_lab complex", "lab_to_rgb complex", "flow complex", "flow nan", "warp_by_flow nan flow"],
)  # fmt: skip
def test_colour_and_flow_arrays_refuse_complex_and_nan_instead_of_dropping_the_imaginary_part(call):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's ComplexWarning was all a user got before
        with pytest.raises(ValueError, match="real numbers|NaN"):
            call()


def test_dis_flow_on_frames_too_small_for_it_is_a_value_error_not_a_crash():
    # OpenCV 5's DIS killed the interpreter on 8..14 x 60 frames; run in a child so a crash fails the test
    code = (
        "import numpy as np, ejsrl.vision as V\n"
        "a = np.random.default_rng(0).integers(0, 255, (10, 60)).astype(np.uint8)\n"
        "try:\n    V.optical_flow(a, a, 'dis')\nexcept ValueError as e:\n    print('ValueError', e)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and "at least 16 x 16" in r.stdout and "farneback" in r.stdout, (r.returncode, r.stdout, r.stderr[-300:])
    big = np.random.default_rng(0).integers(0, 255, (16, 60)).astype(np.uint8)
    assert V.optical_flow(big, big, "dis").shape == (16, 60, 2)


def test_disparity_on_images_narrower_than_the_search_says_what_to_change():
    img = np.zeros((40, 50), np.uint8)
    with pytest.raises(ValueError, match="lower max_disparity"):
        V.disparity(img, img, max_disparity=64)
    assert V.disparity(img, img, max_disparity=16, block_size=5).shape == (40, 50)


@pytest.mark.parametrize("dtype", [np.int32, np.int64, np.uint32, np.int8])
def test_hu_moments_of_an_integer_image_equal_those_of_the_same_image_in_uint8(dtype):
    img = np.zeros((40, 50), np.uint8)
    cv2.fillPoly(img, [np.array([[5, 5], [40, 8], [30, 33], [9, 25]], np.int32)], 90)
    expected = cv2.HuMoments(cv2.moments(img)).ravel()
    assert np.allclose(V.hu_moments(img.astype(dtype)), expected, rtol=1e-9, atol=0)


def test_gaussian_pyramid_of_an_int64_image_is_the_uint8_one():
    img = np.tile(np.arange(0, 240, 10), (24, 1))  # a Python-int image: int64
    got = V.gaussian_pyramid(img, 3)
    ref = [img.astype(np.uint8), cv2.pyrDown(img.astype(np.uint8))]
    ref.append(cv2.pyrDown(ref[1]))
    assert [g.dtype for g in got] == [np.uint8] * 3
    assert all(np.array_equal(g, r) for g, r in zip(got, ref))


@pytest.mark.parametrize("shape", [(1, 1), (8, 8), (3, 40), (40, 3), (8, 8, 3), (14, 200)])
def test_find_chessboard_in_an_image_too_small_for_a_board_finds_none(shape):
    assert V.find_chessboard(np.full(shape, 200, np.uint8), (8, 5)) is None


def test_find_chessboard_still_finds_a_board_just_big_enough():
    sq, margin, cols, rows = 5, 5, 3, 3
    img = np.full(((rows + 1) * sq + 2 * margin, (cols + 1) * sq + 2 * margin), 255, np.uint8)
    for j in range(rows + 1):
        for i in range(cols + 1):
            if (i + j) % 2 == 0:
                img[margin + j * sq : margin + (j + 1) * sq, margin + i * sq : margin + (i + 1) * sq] = 0
    corners = V.find_chessboard(img, (cols, rows))
    assert corners is not None and corners.shape == (9, 2)
    # the inner corners lie where the squares meet: margin + k * sq - 0.5 in pixel-centre coordinates
    want = {(margin + i * sq - 0.5, margin + j * sq - 0.5) for i in range(1, cols + 1) for j in range(1, rows + 1)}
    assert all(min(np.hypot(x - wx, y - wy) for wx, wy in want) < 0.6 for x, y in corners)


def test_find_chessboard_refuses_a_pattern_opencv_cannot_detect_and_an_empty_image():
    with pytest.raises(ValueError, match="at least 3 x 3"):
        V.find_chessboard(np.full((100, 100), 200, np.uint8), (2, 5))
    with pytest.raises(ValueError, match="empty"):
        V.find_chessboard(np.zeros((0, 0), np.uint8), (8, 5))


# --- 3. susan_corners parameters (the patch in _susan.py is the lead's) ------------------------------


@pytest.mark.parametrize(
    ("kwargs", "word"),
    [({"quality": 2}, "quality"), ({"quality": -0.1}, "quality"), ({"nms_radius": -1}, "nms_radius"),
     ({"max_corners": -1}, "max_corners"), ({"t": 0}, "t")],
)  # fmt: skip
def test_susan_corners_refuses_out_of_range_parameters(kwargs, word):
    img = np.zeros((40, 40), np.uint8)
    img[10:30, 10:30] = 200
    with pytest.raises(ValueError, match=word):
        V.susan_corners(img, **kwargs)


# --- 4. the reference's names ------------------------------------------------------------------------

REFERENCE = ROOT / "specs" / "reference.md"


def _reference_imports() -> list[tuple[str, str]]:
    """(module, name) of every ``from M import a, b`` and ``import M`` in reference.md's code (fenced or inline)."""
    text = REFERENCE.read_text()
    fenced = re.findall(r"```[^\n]*\n(.*?)```", text, flags=re.S)
    inline = re.findall(r"`([^`\n][^`]*)`", re.sub(r"```.*?```", "", text, flags=re.S))
    found: list[tuple[str, str]] = []
    # a fenced block line by line (one import a line), inline code whole (wrapped over lines)
    for code in [line for block in fenced for line in block.splitlines()] + inline:
        code = " ".join(code.split())
        for mod, names in re.findall(r"\bfrom ([\w.]+) import ([\w ,]+)", code):
            found += [(mod, n.strip()) for n in names.split(",") if n.strip()]
        found += [(mod, "") for mod in re.findall(r"(?:^|[\[;,] ?)import ([\w.]+)", code)]
    return found


def test_the_reference_s_import_lines_import():
    imports = _reference_imports()
    assert ("ejsrl", "vision") in imports and ("ejsrl.robotics", "SE3") in imports  # the parser sees them
    code = "\n".join(f"from {m} import {n}" if n else f"import {m}" for m, n in imports)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-1500:]


@pytest.mark.parametrize(
    ("module", "name"),
    [("ejsrl.world", "render"), ("ejsrl.world", "render_depth"), ("ejsrl.world", "Realism"),
     ("ejsrl.world.collision", "CollisionShape"), ("ejsrl.vision", "CameraModel"), ("ejsrl.vision", "feature_methods")],
)  # fmt: skip
def test_the_names_the_reference_uses_are_importable_where_it_says(module, name):
    mod = __import__(module, fromlist=[name])
    assert hasattr(mod, name)
    text = " ".join(REFERENCE.read_text().split())
    assert name in text


def test_realism_from_ejsrl_world_renders_as_the_reference_says():
    from ejsrl.world import Realism, World, render
    from ejsrl.world.scene import MeshNode, Part

    w = World()
    V_ = np.array([[-0.1, -0.1, 0.0], [0.1, -0.1, 0.0], [0.1, 0.1, 0.0], [-0.1, 0.1, 0.0]])
    w.add(MeshNode("sq", mesh_parts=(Part(V_, [[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]], (1.0, 1.0, 1.0)),)))
    cam = V.CameraModel(64, 48, 60)
    T = V.look_at([0, 0, 0.5], [0, 0, 0], up=(0, 1, 0))
    plain, _ = render(w, cam, T, backend="numpy")
    soft, _ = render(w, cam, T, backend="numpy", realism=Realism(antialias=3))
    assert plain.shape == soft.shape == (48, 64, 3)
    # anti-aliasing makes in-between greys on the square's edges that the plain picture lacks
    assert len(np.unique(soft)) > len(np.unique(plain))


def test_estimate_pose_is_documented_as_the_camera_s_method():
    text = " ".join(REFERENCE.read_text().split())
    assert "`estimate_pose(" not in text
    assert "`CameraModel.estimate_pose(" in text or "`cam.estimate_pose(" in text
    assert hasattr(V.CameraModel, "estimate_pose") and not hasattr(V, "estimate_pose")


def test_the_public_docs_state_the_dtype_rules_and_send_no_one_to_a_private_module():
    doc = V.__doc__ or ""
    for rule in ("uint16", "bool", "finite", "[0, 1]", "0..255", "normalize"):
        assert rule in doc, rule
    for mod in (V, *(getattr(V, n) for n in V.IMAGE_FUNCTIONS)):
        assert "ejsrl.vision._util" not in (mod.__doc__ or ""), getattr(mod, "__name__", mod)
    for path in (ROOT / "runtime" / "ejsrl" / "vision").glob("*.py"):
        head = path.read_text().split('"""')[1] if path.read_text().startswith('"""') else ""
        assert "ejsrl.vision._util" not in head or path.name == "_util.py", path.name
