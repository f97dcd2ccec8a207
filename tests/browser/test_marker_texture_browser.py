"""A plate's fiducial-marker texture shows in the browser's 3D view (a real Chromium), where the
plate is, the right way round: OpenCV's ArUco detector, run on a screenshot of the view looking
straight down at the plate, finds the marker's id, its corners where the camera the browser
reports puts the marker's corners (worked out here from the spec's numbers), in the marker's own
order; and the same marker in the marker lab's 3D view. Before, the plate was plain in the view
(viser got no texture) while the virtual camera's image showed the marker."""

from __future__ import annotations

import numpy as np
import pytest

from testkit.browser import ARTIFACTS, canvas_pixels, hide_notifications, project, serving, wait_until

SLOW = 120_000

LAB = """\
ejs: 1
title: Marker plate
model:
  variables:
    t: 0.0
    yaw: 0.3
view:
  - scene:
      - view: {position: [0, 0, 1.2], target: [0, 0, 0], up: [0, 1, 0], fov: 40}
      - box: {name: plate, position: [0.05, -0.03, 0], rotation: [0, 0, yaw], size: [0.4, 0.4, 0.024], color: whitesmoke,
              texture: "aruco_4x4_50:7", texture_size: 0.2}
"""


def detect(img: np.ndarray) -> tuple[list[int], list[np.ndarray]]:
    """ArUco 4x4_50 markers in an RGB picture: ids and corners (4, 2) pixels (top-left first, clockwise)."""
    import cv2

    gray = cv2.cvtColor(img.astype(np.uint8), cv2.COLOR_RGB2GRAY)
    detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50), cv2.aruco.DetectorParameters())
    corners, ids, _rejected = detector.detectMarkers(gray)
    if ids is None:
        return [], []
    return [int(i) for i in ids.reshape(-1)], [c.reshape(4, 2) for c in corners]


@pytest.mark.browser
def test_the_plate_shows_its_marker_in_the_3d_view(tmp_path, page):
    from ejsgen.cli import build

    spec = tmp_path / "plate.ejs.yaml"
    spec.write_text(LAB)
    with serving(build(spec, tmp_path / "app")) as (app, url):
        page.set_default_timeout(SLOW)
        page.goto(url)
        page.wait_for_selector("canvas", state="attached", timeout=SLOW)
        hide_notifications(page)

        def client_camera():
            clients = list(app.views[0].server.get_clients().values())
            return clients[0].camera if clients else None

        def looks_down() -> bool:
            cam = client_camera()
            try:
                return cam is not None and np.allclose(cam.position, [0, 0, 1.2], atol=1e-3)
            except AssertionError:  # not reported yet
                return False

        wait_until(looks_down, timeout=60, what="the browser's camera to look down at the plate")
        found: tuple[list[int], list[np.ndarray]] = ([], [])

        def decoded() -> bool:
            nonlocal found
            img = canvas_pixels(page)
            img[-120:, :120] = 255  # the axes gizmo
            found = detect(img)
            return 7 in found[0]

        wait_until(decoded, timeout=60, what="ArUco marker 7 in a screenshot of the 3D view")
        page.screenshot(path=str(ARTIFACTS / "marker_texture_plate.png"))
        img = canvas_pixels(page)
        cam = client_camera()
    assert found[0] == [7], found[0]
    # where the browser's camera draws the marker's corners: the texture_size square about the plate's
    # centre, turned by its yaw, on its top face; in the marker's order (top-left = -x, +y first)
    yaw, c = 0.3, np.array([0.05, -0.03, 0.012])
    R = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    local = 0.1 * np.array([[-1, 1, 0], [1, 1, 0], [1, -1, 0], [-1, -1, 0]], dtype=float)
    ndc = project(cam, local @ R.T + c)
    h, w = img.shape[:2]
    want = np.column_stack([(ndc[:, 0] + 1) / 2 * w, (1 - ndc[:, 1]) / 2 * h])
    err = np.linalg.norm(found[1][0] - want, axis=1)
    print("marker corners off by", np.round(err, 2), "px; side", round(float(np.linalg.norm(want[1] - want[0])), 1), "px")
    assert err.max() < 3.0, (found[1][0], want)


@pytest.mark.browser
def test_the_marker_lab_shows_its_marker_in_the_3d_view(built, page):
    """The marker lab's plate (examples/marker_servoing) in its 3D view, seen from beyond it (the arm
    and its camera hang over it, between the plate and the robot's base): marker 7, with the lab's
    depth points hidden as they are at start."""
    with serving(built("marker_servoing")) as (app, url):
        page.set_default_timeout(SLOW)
        page.goto(url)
        page.wait_for_selector("canvas", state="attached", timeout=SLOW)
        hide_notifications(page)
        with app.lock:
            plate = app.world["plate"].T_world()[:3, 3]
        cam_at = plate + [0.45, 0.2, 0.35]
        wait_until(lambda: bool(app.views[0].server.get_clients()), timeout=60, what="the tab")
        client = next(iter(app.views[0].server.get_clients().values()))
        client.camera.position = tuple(cam_at)
        client.camera.look_at = tuple(plate)
        found: list[int] = []

        def decoded() -> bool:
            nonlocal found
            img = canvas_pixels(page)
            img[-120:, :120] = 255
            found = detect(img)[0]
            return 7 in found

        wait_until(decoded, timeout=60, what="ArUco marker 7 in the marker lab's 3D view")
        page.screenshot(path=str(ARTIFACTS / "marker_texture_lab.png"))
    assert found == [7], found
