"""Fiducial markers: drawn by the virtual camera on a world object, found by OpenCV's ArUco detector,
posed by IPPE; checked against the scene's own ground truth (the pose the test placed)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from ejsrl.robotics.transforms import transl, trotx, troty, trotz
from ejsrl.vision import CameraModel, look_at
from ejsrl.vision.markers import MARKER_DICTIONARIES, detect_markers, marker_bits, marker_corners_3d, marker_image, marker_pose
from ejsrl.world import World, render
from ejsrl.world.rendering import Realism
from ejsrl.world.scene import Box

W, H = 640, 480
CAM = CameraModel(W, H, fov_deg=50)
SIDE = 0.10


def _plate(texture: str, T: np.ndarray, side: float = SIDE) -> World:
    w = World()
    w.add(Box("plate", size=(0.3, 0.3, 0.01), color="white", texture=texture, texture_size=side, T_parent_local=T))
    return w


def _top(T_plate: np.ndarray) -> np.ndarray:
    """The marker's frame: the plate's top face (its +z side), 5 mm above the plate's origin."""
    return T_plate @ transl(0, 0, 0.005)


def _rot_deg(R: np.ndarray) -> float:
    return math.degrees(math.acos(np.clip((np.trace(R) - 1) / 2, -1, 1)))


POSES = [
    (transl(0.02, -0.01, 0.0), look_at([0.0, -0.05, 0.5], [0.0, 0.0, 0.0], [0, 1, 0])),
    (transl(0.0, 0.0, 0.0) @ trotz(0.7) @ trotx(0.5), look_at([0.15, -0.35, 0.45], [0.0, 0.0, 0.0], [0, 0, 1])),
    (transl(0.05, 0.03, 0.1) @ troty(-0.6) @ trotz(-1.2), look_at([-0.3, 0.1, 0.5], [0.05, 0.03, 0.1], [0, 0, 1])),
]


@pytest.mark.parametrize("dictionary,marker_id", [("aruco_4x4_50", 7), ("aruco_6x6_250", 123), ("apriltag_36h11", 5)])
@pytest.mark.parametrize("k", range(len(POSES)))
def test_a_rendered_marker_is_found_where_it_is_and_posed(dictionary: str, marker_id: int, k: int) -> None:
    T_plate, T_cam = POSES[k]
    w = _plate(f"{dictionary}:{marker_id}", T_plate)
    rgb, _ = render(w, CAM, T_cam, backend="auto", realism=Realism(antialias=3))
    found = detect_markers(rgb, dictionary)
    assert [m.id for m in found] == [marker_id]
    # the corners where the camera model projects the marker's true corners (ground truth of the scene)
    T_world_marker = _top(T_plate)
    P = (T_world_marker @ np.column_stack([marker_corners_3d(SIDE), np.ones(4)]).T).T[:, :3]
    truth = CAM.project(P, T_cam)
    err = np.linalg.norm(found[0].corners - truth, axis=1)
    assert err.max() < 0.5, err
    T_cm = found[0].pose(SIDE, CAM)
    T_true = np.linalg.inv(T_cam) @ T_world_marker
    assert np.linalg.norm(T_cm[:3, 3] - T_true[:3, 3]) < 0.004  # metres, at 0.5-0.6 m
    assert _rot_deg(T_cm[:3, :3].T @ T_true[:3, :3]) < 1.5


def test_two_markers_with_their_ids_and_blur_and_noise() -> None:
    w = World()
    w.add(Box("a", size=(0.2, 0.2, 0.01), color="white", texture="aruco_4x4_50:3", texture_size=0.12, T_parent_local=transl(-0.15, 0, 0)))
    w.add(Box("b", size=(0.2, 0.2, 0.01), color="white", texture="aruco_4x4_50:41", texture_size=0.12, T_parent_local=transl(0.15, 0, 0)))
    T_cam = look_at([0.0, -0.2, 0.7], [0, 0, 0], [0, 0, 1])
    rgb, _ = render(w, CAM, T_cam, realism=Realism(antialias=2, blur=1.0, noise=3.0), rng=np.random.default_rng(1))
    found = detect_markers(rgb, "aruco_4x4_50")
    assert [m.id for m in found] == [3, 41]
    # marker 3 is on the left of the picture (x < W/2), 41 on the right
    assert found[0].center[0] < W / 2 < found[1].center[0]


def test_the_marker_image_is_the_dictionarys_own() -> None:
    # OpenCV's detector (the independent reference) reads our printable image as the id we asked for
    for name, i in [("aruco_5x5_100", 99), ("apriltag_16h5", 29), ("aruco_original", 1000)]:
        img = marker_image(name, i, 200)
        ids = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(MARKER_DICTIONARIES[name])).detectMarkers(img)[1]
        assert ids is not None and ids.reshape(-1).tolist() == [i]
    bits = marker_bits("aruco_4x4_50", 0)
    assert bits.shape == (6, 6) and bits[0].all() and bits[-1].all() and bits[:, 0].all()


def test_marker_pose_of_known_corners_is_exact() -> None:
    T_true = transl(0.03, -0.02, 0.4) @ trotx(0.3) @ troty(-0.2) @ trotz(0.5)
    P = (T_true @ np.column_stack([marker_corners_3d(0.08), np.ones(4)]).T).T[:, :3]
    px = CAM.project_camera(P)
    T = marker_pose(px, 0.08, CAM)
    np.testing.assert_allclose(T, T_true, atol=1e-6)
    # seen exactly square-on (OpenCV's IPPE_SQUARE alone returns no rotation and a 90 px error here)
    T_on = transl(0.0, 0.0, 0.4) @ trotx(math.pi)
    P = (T_on @ np.column_stack([marker_corners_3d(0.2), np.ones(4)]).T).T[:, :3]
    px = CAM.project_camera(P)
    np.testing.assert_allclose(marker_pose(px, 0.2, CAM), T_on, atol=1e-6)
    np.testing.assert_allclose(marker_pose(px, 0.2, CAM, previous=T_on), T_on, atol=1e-6)


def test_bad_marker_textures_and_arguments_say_what_is_wrong() -> None:
    eye = look_at([0, 0, 0.5], [0, 0, 0], [0, 1, 0])
    with pytest.raises(ValueError, match="'plate': unknown marker dictionary 'aruco_4x4_5'; did you mean 'aruco_4x4_50'"):
        render(_plate("aruco_4x4_5:1", np.eye(4)), CAM, eye)
    with pytest.raises(ValueError, match="'plate': marker id 50 is not in 'aruco_4x4_50', which has ids 0..49"):
        render(_plate("aruco_4x4_50:50", np.eye(4)), CAM, eye)
    with pytest.raises(ValueError, match="after the ':' comes the marker's id"):
        render(_plate("apriltag_36h11:x", np.eye(4)), CAM, eye)
    with pytest.raises(ValueError, match="side is the marker's side"):
        marker_pose(np.zeros((4, 2)), -1, CAM)
    with pytest.raises(ValueError, match="unknown marker dictionary"):
        detect_markers(np.zeros((10, 10), np.uint8), "qr")


_SPEC = """\
ejs: 1
title: Marker
model:
  variables:
    t: 0.0
    dt: 0.1
  evolution:
    - code: t = t + dt
view:
  - scene:
      - box: {name: plate, size: [0.3, 0.3, 0.01], texture: "TEX", texture_size: 0.1}
"""


@pytest.mark.parametrize(
    ("texture", "expect"),
    [
        ("aruco_4x4_5:1", "11:61: error: unknown marker dictionary 'aruco_4x4_5'; did you mean 'aruco_4x4_50'?"),
        ("aruco_4x4_50:50", "11:61: error: marker id 50 is not in 'aruco_4x4_50', which has ids 0..49; pick an id in that range"),
        ("marble", "11:61: error: texture 'marble' is not one of 'checker' or a marker '<dictionary>:<id>'; e.g. texture: checker"),
    ],
)
def test_a_bad_marker_texture_is_a_build_error_at_its_place(tmp_path, capsys, texture: str, expect: str) -> None:
    from ejsgen.cli import main

    spec = tmp_path / "m.ejs.yaml"
    spec.write_text(_SPEC.replace("TEX", texture))
    assert main(["validate", str(spec)]) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err and f"{spec}:{expect}" in err, err
    spec.write_text(_SPEC.replace("TEX", "apriltag_36h11:586"))
    assert main(["validate", str(spec)]) == 0
