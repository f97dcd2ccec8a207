"""``ejsgen build --web`` refuses what cannot run in a browser, at the spec's FILE:LINE:COL (issue #32).

Each test writes a tiny spec using one feature that needs what a browser's WebAssembly Python
lacks (OpenCV, native libraries, sockets, threads, too much data) and checks that
``web_refusals`` names that feature, says why and what to do, at the line and column of the
text that asks for it (found in the spec's own text, not hard-coded); and that the labs the web
build is for (the pendulum, six-axis kinematics, a trajectory lab) are refused nothing.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest

from ejsgen._web_check import DATA_LIMIT_BYTES, web_refusals
from ejsgen.errors import SpecError
from ejsgen.validate import validate
from ejsgen.yamlload import load_yaml
from testkit import EXAMPLES

HEAD = """\
ejs: 1
title: Web check
model:
  variables:
    t: 0.0
    dt: 0.01
    x: 0.5
    img: {expr: "np.zeros((8, 8, 3), np.uint8)"}
  evolution:
    - code: t = t + dt
"""


def refusals(tmp_path: Path, text: str, name: str = "lab.ejs.yaml") -> tuple[list[SpecError], str]:
    spec = tmp_path / name
    spec.write_text(text, encoding="utf-8")
    return web_refusals(validate(load_yaml(spec, display_name=name)), spec), text


def position(text: str, needle: str, nth: int = 0) -> tuple[int, int]:
    """1-based (line, column) of the ``nth`` occurrence of ``needle`` in ``text``."""
    at = -1
    for _ in range(nth + 1):
        at = text.index(needle, at + 1)
    line = text.count("\n", 0, at) + 1
    return line, at - (text.rfind("\n", 0, at) + 1) + 1


def one(errors: list[SpecError], text: str, needle: str, *words: str) -> SpecError:
    """The single refusal, at ``needle``'s place, whose message has every word in ``words``."""
    assert len(errors) == 1, [e.format() for e in errors]
    err = errors[0]
    assert (err.where.line, err.where.col) == position(text, needle), err.format()
    assert err.where.file == "lab.ejs.yaml"
    text_of = err.format()
    assert text_of.startswith(f"lab.ejs.yaml:{err.where.line}:{err.where.col}: error: ")
    assert "cannot run in a browser" in text_of and "serve this lab instead" in text_of
    for word in words:
        assert word in text_of, (word, text_of)
    return err


@pytest.mark.parametrize("lab", ["pendulum", "paper/six_axis_kinematics", "paper/path_planning_434", "projectile_2d",
                                 "mobile_ekf_slam", "paper/pick_and_place"])
def test_the_labs_a_web_build_is_for_are_refused_nothing(lab: str) -> None:
    spec = EXAMPLES / f"{lab}.ejs.yaml"
    assert web_refusals(validate(load_yaml(spec, display_name=spec.name)), spec) == []


def test_an_opencv_function_in_imports(tmp_path: Path) -> None:
    text = HEAD.replace("title: Web check\n", "title: Web check\nimports:\n  - from ejsrl.vision import look_at, canny\n")
    errors, text = refusals(tmp_path, text)
    err = one(errors, text, "from ejsrl.vision import look_at, canny", "`canny`", "OpenCV")
    assert "look_at" not in err.message  # the camera-pose helper is NumPy's: it runs


def test_numpy_only_vision_imports_pass(tmp_path: Path) -> None:
    text = HEAD.replace("title: Web check\n", "title: Web check\nimports:\n  - from ejsrl.vision import CameraModel, "
                        "interaction_matrix, rgb_to_lab, icp\n  - import numpy.linalg as la\n  - from scipy.integrate import solve_ivp\n"
                        "  - import math, json\n")
    errors, _ = refusals(tmp_path, text)
    assert errors == []


def test_an_opencv_function_reached_through_the_vision_module_in_code(tmp_path: Path) -> None:
    text = HEAD.replace("title: Web check\n", "title: Web check\nimports:\n  - from ejsrl import vision\n").replace(
        "    - code: t = t + dt\n", "    - code: |\n        t = t + dt\n        edges = vision.canny(img)\n")
    errors, text = refusals(tmp_path, text)
    one(errors, text, "vision.canny", "`vision.canny`", "OpenCV")


@pytest.mark.parametrize("line, word", [
    ("import cv2", "OpenCV (`cv2`)"), ("from ejsrl.vision import filters", "ejsrl.vision.filters"),
    ("from ejsrl.vision.features import blobs", "`blobs`"), ("from ejsrl.vision import ImageSource", "OpenCV and the devices"),
    ("import pandas", "the package `pandas`"), ("import socket", "network sockets"), ("import threading", "threads"),
    ("from subprocess import run", "processes"), ("from ejsrl.fmi import FmuInstance", "native"),
])
def test_modules_and_packages_a_browser_lacks_in_imports(tmp_path: Path, line: str, word: str) -> None:
    text = HEAD.replace("title: Web check\n", f"title: Web check\nimports:\n  - {line}\n")
    errors, text = refusals(tmp_path, text)
    one(errors, text, line, word)


def test_an_import_inside_code_is_refused_where_it_is(tmp_path: Path) -> None:
    text = HEAD.replace("    - code: t = t + dt\n", "    - code: |\n        t = t + dt\n        import cv2\n")
    errors, text = refusals(tmp_path, text)
    one(errors, text, "import cv2", "OpenCV")


def test_urdf_robots_run_in_a_page(tmp_path: Path) -> None:
    """The page gets yourdfpy's Python and lxml's (tests/web/test_web_robotics.py runs examples/urdf_arm)."""
    text = HEAD.replace("title: Web check\n", "title: Web check\nimports:\n  - from ejsrl.robotics import models, load_urdf\n").replace(
        '    img: {expr: "np.zeros((8, 8, 3), np.uint8)"}\n', '    arm: {expr: "models.ur5_urdf()"}\n')
    errors, _ = refusals(tmp_path, text)
    assert errors == [], [e.format() for e in errors]


def test_a_map_read_from_an_image_file(tmp_path: Path) -> None:
    text = HEAD.replace("title: Web check\n", "title: Web check\nimports:\n  - from ejsrl.mobile.grid import OccupancyGrid\n"
                        "assets: [map.png]\n").replace(
        '    img: {expr: "np.zeros((8, 8, 3), np.uint8)"}\n', "    grid: {expr: \"OccupancyGrid.from_image('map.png')\"}\n")
    (tmp_path / "map.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    errors, text = refusals(tmp_path, text)
    one(errors, text, "OccupancyGrid.from_image", "`from_image`", "OpenCV")


VIEW_IMAGE = HEAD + "view:\n  - image: {source: img, label: Camera, points: '[[1, 2]]'}\n"


def test_an_image_element_and_its_points_run_in_a_page(tmp_path: Path) -> None:
    """The points are drawn with NumPy (``ejsrl.view._image.draw_rings``): nothing to refuse."""
    errors, _ = refusals(tmp_path, VIEW_IMAGE)
    assert errors == []


CAMERA = HEAD + """\
view:
  - image: {source: 'capture("eye")', label: Camera}
  - folder:
      label: Scene
      children:
        - scene:
            - box: {name: block, position: [0, 0, 0], size: [0.1, 0.1, 0.1]}
            - camera: {name: eye, position: [1, 0, 0.5], fov: 50, resolution: [64, 48]EXTRA}
"""


@pytest.mark.parametrize("extra, needle, words", [
    (", source: 0", "source: 0", ("a real image source", "devices")),
    (", blur: 1.5", "blur:", ("defocus `blur`", "OpenCV", "leave `blur` out")),
    (", blur: 'x*2'", "blur:", ("defocus `blur`",)),
    (", distortion: [0.1, 0, 0, 0, 0]", "distortion:", ("lens `distortion`", "OpenCV")),
])
def test_camera_features_that_need_opencv(tmp_path: Path, extra: str, needle: str, words: tuple[str, ...]) -> None:
    errors, text = refusals(tmp_path, CAMERA.replace("EXTRA", extra))
    one(errors, text, needle, *words)


def test_a_virtual_camera_itself_and_off_settings_pass(tmp_path: Path) -> None:
    """A virtual camera renders with NumPy: it, and blur 0 or no distortion, are not refused."""
    errors, _ = refusals(tmp_path, CAMERA.replace("EXTRA", ", blur: 0, noise: 2, distortion: [0, 0, 0, 0, 0]"))
    assert errors == []


def test_a_marker_texture(tmp_path: Path) -> None:
    text = CAMERA.replace("size: [0.1, 0.1, 0.1]}", "size: [0.1, 0.1, 0.1], texture: 'aruco_4x4_50:7'}").replace("EXTRA", "")
    errors, text = refusals(tmp_path, text)
    one(errors, text, "texture:", "marker texture 'aruco_4x4_50:7'", "ArUco")


def test_a_2d_image_runs_but_a_file_opencv_cannot_read_is_refused(tmp_path: Path) -> None:
    """An array and a picture file are shown in the page (the build decodes the file); a file
    that OpenCV cannot read is refused at its `file` key, which says to convert it to PNG."""
    import cv2
    import numpy as np

    cv2.imwrite(str(tmp_path / "good.png"), np.full((4, 4, 3), 200, np.uint8))
    cv2.imwrite(str(tmp_path / "good.jpg"), np.full((4, 4, 3), 200, np.uint8))
    (tmp_path / "bad.png").write_bytes(b"not a picture at all" * 10)
    text = HEAD + """\
view:
  - drawing:
      x_range: [0, 1]
      y_range: [0, 1]
      children:
        - point: {position: [x, 0.5]}
        - image: {source: img, position: [0.5, 0.5], size: [1, 1]}
        - image: {file: good.png, position: [0.5, 0.5], size: [1, 1]}
        - image: {file: good.jpg, position: [0.5, 0.5], size: [1, 1]}
"""
    errors, _ = refusals(tmp_path, text)
    assert errors == [], [e.format() for e in errors]
    errors, text = refusals(tmp_path, text + "        - image: {file: bad.png, position: [0.5, 0.5], size: [1, 1]}\n")
    err = one(errors, text, "file: bad.png", "the image file 'bad.png'", "OpenCV", "cannot read")
    assert "convert it to PNG" in err.hint


def test_a_collada_mesh(tmp_path: Path) -> None:
    text = HEAD + "view:\n  - scene:\n      - mesh: {name: part, file: part.dae}\n"
    (tmp_path / "part.dae").write_text("<COLLADA/>")
    errors, text = refusals(tmp_path, text)
    one(errors, text, "file: part.dae", "the mesh 'part.dae'", "pycollada", "convert it to GLB")


def _fmu_spec(folder: str) -> str:
    return HEAD + f"fmus:\n  drives:\n    file: {folder}\n    kind: co_simulation\n"


def test_an_fmu_kept_as_c_sources(tmp_path: Path) -> None:
    from testkit.fmu import fmu_folder

    fmu_folder(tmp_path)
    errors, text = refusals(tmp_path, _fmu_spec("drives"))
    one(errors, text, "drives:", "the FMU 'drives'", "C sources", "native library")


def test_an_fmu_with_native_binaries(tmp_path: Path) -> None:
    with zipfile.ZipFile(tmp_path / "motor.fmu", "w") as zf:
        zf.writestr("modelDescription.xml", "<fmiModelDescription/>")
        zf.writestr("binaries/linux64/motor.so", b"\x7fELF")
    errors, text = refusals(tmp_path, _fmu_spec("motor.fmu"))
    one(errors, text, "drives:", "the FMU 'drives'", "native binary", "binaries/")


def test_a_remote_plant(tmp_path: Path) -> None:
    text = HEAD + "plant:\n  host: 127.0.0.1\n  commands:\n    x: {to: joints}\n"
    errors, text = refusals(tmp_path, text)
    one(errors, text, "plant:", "a remote plant", "MQTT or OPC UA", "no sockets")


def test_data_beyond_the_limit_names_the_file_that_crosses_it(tmp_path: Path) -> None:
    half = DATA_LIMIT_BYTES // 2
    for name, size in (("a.csv", half), ("b.csv", half - 10), ("c.csv", 1000)):
        with open(tmp_path / name, "wb") as f:  # sparse files: the size is what counts
            f.truncate(size)
    text = HEAD.replace("title: Web check\n", "title: Web check\nassets: [a.csv, b.csv]\n")
    errors, _ = refusals(tmp_path, text)
    assert errors == []  # just under the limit
    text = HEAD.replace("title: Web check\n", "title: Web check\nassets:\n  - a.csv\n  - b.csv\n  - c.csv\n")
    errors, text = refusals(tmp_path, text)
    err = one(errors, text, "c.csv", f"more than {DATA_LIMIT_BYTES // 2**20} MB", "'a.csv' 10.0 MB", "first visit")
    assert "make the data smaller" in err.hint


def test_every_refusal_of_a_lab_is_reported_in_file_order(tmp_path: Path) -> None:
    text = HEAD.replace("title: Web check\n", "title: Web check\nimports:\n  - import cv2\n") + \
        CAMERA.removeprefix(HEAD).replace("EXTRA", ", blur: 1.5") + "plant:\n  commands:\n    x: {to: joints}\n"
    errors, text = refusals(tmp_path, text)
    assert [(e.where.line, e.where.col) for e in errors] == [position(text, "import cv2"), position(text, "blur:"),
                                                             position(text, "plant:")]


def test_the_examples_that_need_opencv_or_a_plant_are_refused() -> None:
    """Every example is checked; those that cannot run in a browser say why."""
    expect = {"camera_calibration": "OpenCV", "marker_servoing": "OpenCV", "paper/visual_servoing_eih": "OpenCV",
              "paper/fmu_motor_control": "native library", "paper/robualab": "remote plant"}
    for lab, word in expect.items():
        spec = EXAMPLES / f"{lab}.ejs.yaml"
        errors = web_refusals(validate(load_yaml(spec, display_name=spec.name)), spec)
        assert errors and any(word in e.format() for e in errors), (lab, [e.format() for e in errors])
        text = spec.read_text(encoding="utf-8").splitlines()
        for e in errors:  # each points into the spec at a real place
            assert 1 <= e.where.line <= len(text) and 1 <= e.where.col <= len(text[e.where.line - 1]) + 1, e.format()


def test_the_stated_limit_is_the_documented_one() -> None:
    doc = (Path(__file__).resolve().parents[2] / "specs" / "web.md").read_text(encoding="utf-8")
    assert f"{DATA_LIMIT_BYTES // 2**20} MB" in doc
    assert "What `--web` refuses" in doc and "What runs in the browser" in doc


def test_build_web_refuses_at_the_command_line_and_writes_nothing(tmp_path: Path) -> None:
    import subprocess
    import sys

    text = HEAD.replace("title: Web check\n", "title: Web check\nimports:\n  - import cv2\n") + "plant:\n  commands:\n    x: {to: joints}\n"
    (tmp_path / "lab.ejs.yaml").write_text(text, encoding="utf-8")
    r = subprocess.run([sys.executable, "-m", "ejsgen", "build", "lab.ejs.yaml", "--web", "-o", "site"], cwd=tmp_path,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode != 0
    lines = [line for line in r.stderr.splitlines() if ": error: " in line]
    (l1, c1), (l2, c2) = position(text, "import cv2"), position(text, "plant:")
    assert lines[0].startswith(f"lab.ejs.yaml:{l1}:{c1}: error: OpenCV (`cv2`) cannot run in a browser"), r.stderr
    assert lines[1].startswith(f"lab.ejs.yaml:{l2}:{c2}: error: a remote plant (`plant:`) cannot run in a browser"), r.stderr
    assert "Traceback" not in r.stderr
    assert not (tmp_path / "site").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lab.ejs.yaml"]


def test_the_build_says_what_a_first_visit_downloads_part_by_part(tmp_path: Path, monkeypatch, capsys) -> None:
    """The trial found only the total in the build's line; the split was in manifest.json alone."""
    import argparse

    from ejsgen import _web_build, cli

    out = tmp_path / "site"
    (out / "ejsweb").mkdir(parents=True)
    (out / "index.html").write_bytes(b"x" * 600_000)
    (out / "ejsweb" / "bridge.js").write_bytes(b"y" * 300_000)
    site = _web_build.WebBuild(out, {"python.wasm": (70e6, 19_300_000), "python315.zip": (9e6, 3_800_000), "lab.bin": (5e6, 1_800_000)}, 11.4)
    monkeypatch.setattr(_web_build, "build_web", lambda spec, dest: site)
    assert cli._cmd_build(argparse.Namespace(web=True, spec="lab.ejs.yaml", output=str(out))) == 0
    line = capsys.readouterr().out
    assert "25.8 MB for a first visit (Python 19.3, its library 3.8, the lab 1.8, the page 0.9)" in line, line
