"""Every image function of ejsrl.vision refuses bad input with a clear ValueError.

The bad inputs (an empty 0x0 image, a NaN pixel, two channels, a complex dtype) are fed to
every name in ``IMAGE_FUNCTIONS`` in a child interpreter, so a function that kills the
interpreter (OpenCV's connectedComponents did on a 0x0 image) shows up as a failed case
instead of taking pytest down. Then the bugs of issue 15, each against an independent
reference: brightness that saturates instead of folding, float/uint16/NaN coercion,
``threshold``'s level in the image's own units, unknown option strings.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

import ejsrl.vision as V

GOOD = np.tile(np.arange(0, 200, 10, dtype=np.uint8), (20, 1))
PTS = np.array([[3.0, 4.0], [10.0, 12.0]])


def _bad_inputs() -> dict[str, object]:
    nan = np.full((20, 20), 0.5)
    nan[3, 4] = np.nan
    return {
        "empty": np.zeros((0, 0), np.uint8),
        "nan": nan,
        "two_channels": np.zeros((20, 20, 2), np.uint8),
        "complex": np.zeros((20, 20), np.complex128),
        "none": None,
    }


#: what each bad input's error message must say
EXPECTED_WORDS = {"empty": "empty", "nan": "NaN", "two_channels": "grey", "complex": "dtype", "none": "None"}


def calls() -> dict[str, object]:
    """How to call each image function with a bad image ``b`` (every other argument valid)."""
    one = {name: (lambda b, f=getattr(V, name): f(b)) for name in V.IMAGE_FUNCTIONS}
    one.update(
        {
            "convolve": lambda b: V.convolve(b, np.ones((3, 3)) / 9),
            "warp_affine": lambda b: V.warp_affine(b, np.eye(2, 3)),
            "warp_perspective": lambda b: V.warp_perspective(b, np.eye(3)),
            "crop": lambda b: V.crop(b, 0, 0, 5, 5),
            "rotate": lambda b: V.rotate(b, 30),
            "resize": lambda b: V.resize(b, (10, 10)),
            "color_mask": lambda b: V.color_mask(b, (0, 0, 0), (179, 255, 255)),
            "color_segment": lambda b: V.color_segment(b, "red"),
            "match_template": lambda b: V.match_template(b, GOOD[:5, :5]),
            "lk_track": lambda b: V.lk_track(b, GOOD, PTS),
            "draw_points": lambda b: V.draw_points(b, PTS),
            "draw_lines": lambda b: V.draw_lines(b, [[0, 0, 5, 5]]),
            "draw_boxes": lambda b: V.draw_boxes(b, [[0, 0, 5, 5]]),
            "draw_circles": lambda b: V.draw_circles(b, [[5, 5, 3]]),
            "draw_contours": lambda b: V.draw_contours(b, [PTS]),
            "draw_text": lambda b: V.draw_text(b, "hi"),
        }
    )
    # no image argument: their own bad-input test is below
    for name in ("structuring_element", "affine_matrix", "perspective_matrix"):
        one.pop(name)
    return one


NOT_IMAGE_TAKING = {"structuring_element", "affine_matrix", "perspective_matrix"}
CASES = [(name, case) for name in V.IMAGE_FUNCTIONS if name not in NOT_IMAGE_TAKING for case in _bad_inputs()]

_WORKER = r"""
import importlib.util, json, sys
spec = importlib.util.spec_from_file_location("vision_validation_calls", sys.argv[1])
mod = importlib.util.module_from_spec(spec)
spec.loader.exec_module(mod)
table, bad = mod.calls(), mod._bad_inputs()
for item in json.loads(sys.argv[2]):
    name, case = item
    print(json.dumps({"item": item, "started": True}), flush=True)
    try:
        out = table[name](bad[case])
        res = {"item": item, "returned": type(out).__name__}
    except BaseException as e:
        res = {"item": item, "raised": type(e).__name__, "message": str(e)}
    print(json.dumps(res), flush=True)
"""


@pytest.fixture(scope="module")
def outcomes() -> dict[tuple[str, str], dict]:
    """Run every (function, bad input) in child interpreters; a crash is recorded and the rest go on."""
    from testkit.isolated import run_surviving_crashes  # here: the child imports this file, without testkit on its path

    return run_surviving_crashes(set(CASES), lambda pending: [sys.executable, "-c", _WORKER, str(Path(__file__)), json.dumps([list(c) for c in CASES if c in pending])])


@pytest.mark.parametrize(("name", "case"), CASES, ids=[f"{n}-{c}" for n, c in CASES])
def test_every_image_function_refuses_bad_input_with_a_value_error(outcomes, name, case):
    got = outcomes[(name, case)]
    assert "crashed" not in got, f"{name} killed the interpreter (exit {got.get('crashed')}): {got.get('stderr')}"
    assert "returned" not in got, f"{name} returned a {got['returned']} for a {case} image instead of refusing it"
    assert got["raised"] == "ValueError", got
    assert EXPECTED_WORDS[case].lower() in got["message"].lower(), got["message"]


def test_the_call_table_covers_every_image_function():
    assert set(calls()) | NOT_IMAGE_TAKING == set(V.IMAGE_FUNCTIONS)


def test_functions_without_an_image_refuse_bad_arguments():
    with pytest.raises(ValueError, match="did you mean 'ellipse'"):
        V.structuring_element("elipse", 3)
    with pytest.raises(ValueError, match="at least 1"):
        V.structuring_element("rect", 0)
    with pytest.raises(ValueError, match="3 finite"):
        V.affine_matrix(PTS, PTS)
    with pytest.raises(ValueError, match="4 finite"):
        V.perspective_matrix([[0, 0], [1, 0], [1, 1], [0, np.nan]], [[0, 0], [1, 0], [1, 1], [0, 1]])


# -- the bugs of issue 15, each against an independent reference ------------------------------


def test_negative_brightness_saturates_at_black_instead_of_folding_back():
    img = np.array([[10, 100, 250]], np.uint8)
    out = V.adjust_brightness_contrast(img, brightness=-100)
    np.testing.assert_array_equal(out, [[0, 0, 150]])  # cv2.convertScaleAbs gave 90 for the 10
    ref = np.clip(np.rint(1.5 * img.astype(float) + 20), 0, 255)
    np.testing.assert_array_equal(V.adjust_brightness_contrast(img, 20, 1.5), ref)


def test_a_float_pixel_above_one_is_refused_instead_of_darkening_the_image():
    img = np.full((10, 10), 0.8)
    assert V.to_gray(img)[0, 0] == 204  # floats in [0, 1] scale by 255
    img[0, 0] = 1.5
    with pytest.raises(ValueError, match=r"\[0, 1\].*normalize"):
        V.to_gray(img)
    assert V.normalize(img).max() == 255  # normalize takes any range, as its message says


def test_uint16_scales_to_the_full_uint8_range_and_nan_is_refused():
    img = np.array([[0, 257, 32768, 65535]], np.uint16)
    np.testing.assert_array_equal(V.to_gray(img), [[0, 1, 128, 255]])  # the old code clipped 32768 to 255
    with pytest.raises(ValueError, match="NaN"):
        V.invert(np.array([[0.1, np.nan]]))
    with pytest.raises(ValueError, match="outside 0..255"):
        V.to_gray(np.array([[-3, 300]]))
    np.testing.assert_array_equal(V.to_gray(np.array([[0, 7, 255]])), [[0, 7, 255]])  # Python ints: int64


def test_threshold_level_is_in_the_images_own_units():
    ramp = np.linspace(0.0, 1.0, 101).reshape(1, -1)
    out = V.threshold(ramp, 0.5)  # was: the image scaled to 0..255, the level left at 0.5
    np.testing.assert_array_equal(out[0] > 0, ramp[0] > 0.5)
    np.testing.assert_array_equal(V.threshold(ramp)[0] > 0, ramp[0] > 0.5)  # default: the middle
    u8 = np.arange(256, dtype=np.uint8).reshape(1, -1)
    np.testing.assert_array_equal(V.threshold(u8, 100)[0] > 0, np.arange(256) > 100)
    u16 = (np.arange(256, dtype=np.uint16) * 257).reshape(1, -1)
    np.testing.assert_array_equal(V.threshold(u16, 30000)[0] > 0, u16[0] > 30000)
    rgb = np.dstack([ramp, ramp, ramp])
    np.testing.assert_array_equal(V.threshold(rgb, 0.25)[0] > 0, ramp[0] > 0.25 + 1e-6)


@pytest.mark.parametrize(
    ("call", "typo", "suggestion"),
    [
        (lambda: V.flip(GOOD, "horizontl"), "horizontl", "horizontal"),
        (lambda: V.resize(GOOD, (5, 5), interpolation="cubik"), "cubik", "cubic"),
        (lambda: V.threshold_adaptive(GOOD, method="gausian"), "gausian", "gaussian"),
        (lambda: V.match_template(GOOD, GOOD[:4, :4], method="ccoeff_norm"), "ccoeff_norm", "ccoeff_normed"),
        (lambda: V.draw_points(GOOD, PTS, marker="crosss"), "crosss", "cross"),
        (lambda: V.sobel(GOOD, "magnitud"), "magnitud", "magnitude"),
        (lambda: V.color_mask(GOOD, (0, 0, 0), (1, 1, 1), space="hvs"), "hvs", "hsv"),
        (lambda: V.convolve(GOOD, np.ones((3, 3)), output="flot"), "flot", "float"),
        (lambda: V.erode(GOOD, 3, shape="crss"), "crss", "cross"),
        (lambda: V.susan(GOOD, kind="corner"), "corner", "corners"),
    ],
)
def test_unknown_option_strings_are_value_errors_that_suggest_the_fix(call, typo, suggestion):
    with pytest.raises(ValueError, match=f"unknown .*'{typo}'; did you mean '{suggestion}'"):
        call()


def test_opencv_refusals_become_value_errors_naming_the_function():
    with pytest.raises(ValueError, match="gaussian_blur: OpenCV refused"):
        V.gaussian_blur(GOOD, 4)  # an even kernel
    with pytest.raises(ValueError, match="larger than the image"):
        V.match_template(GOOD[:4, :4], GOOD)


def test_valid_images_of_every_supported_type_agree():
    u8 = GOOD
    as_float = u8 / 255.0
    as_bool = u8 > 100
    np.testing.assert_array_equal(V.gaussian_blur(as_float), V.gaussian_blur(u8))
    np.testing.assert_array_equal(V.invert(as_bool), np.where(as_bool, 0, 255))
    np.testing.assert_array_equal(V.canny(as_float.astype(np.float32)), cv2.Canny(u8, 50, 150))
    assert V.resize(as_float, (10, 10)).dtype == np.float64  # the warps keep float images float
