"""A solid's marker texture reaches the browser's 3D view: an image node on its +z face whose cells
are the marker's (``ejsrl.vision.markers.marker_bits``, OpenCV's ArUco bits), the size and place
the virtual camera paints it, following the node and gone with its texture."""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.view._marker_face import CELL_PX
from ejsrl.view._scene_mirror import ROOT, SceneMirror
from ejsrl.view.viser_view import make_server
from ejsrl.world.scene import Box, World


@pytest.fixture
def scene():
    server, _url = make_server("127.0.0.1", 0, banner=False)
    yield server.scene
    server.stop()


def test_a_marker_texture_is_an_image_on_the_top_face(scene):
    import cv2

    world = World()
    plate = world.add(Box("plate", size=(0.4, 0.4, 0.024), color=(0.96, 0.96, 0.96), texture="aruco_4x4_50:7", texture_size=0.2))
    mirror = SceneMirror(scene)
    mirror.sync(world)
    image = mirror._nodes["plate"].marker[1]
    assert image.name == f"{ROOT}/plate/marker"
    assert image.render_width == pytest.approx(0.2) and image.render_height == pytest.approx(0.2)
    assert 0.012 < image.position[2] < 0.0125  # just above the top face (z = 0.012)
    # the picture, turned the right way up (viser shows row 0 towards -y), is OpenCV's marker 7
    import io

    from PIL import Image

    picture = np.asarray(Image.open(io.BytesIO(image._impl.props._data)).convert("L"))[::-1]
    cells = picture[CELL_PX // 2 :: CELL_PX, CELL_PX // 2 :: CELL_PX] < 128
    d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    want = cv2.aruco.generateImageMarker(d, 7, 6, borderBits=1) < 128
    assert cells.shape == (6, 6) and np.array_equal(cells, want)
    # black cells are the face's colour times MARKER_DARK, as the virtual camera paints them
    assert picture.min() == round(245 * 0.08) and picture.max() == 245
    # a new id is a new picture; no texture, no picture
    plate.set(texture="aruco_4x4_50:3")
    mirror.sync(world)
    assert mirror._nodes["plate"].marker[1] is not image and image._impl.removed
    plate.set(texture=None)
    mirror.sync(world)
    assert mirror._nodes["plate"].marker is None
