"""2D ``image`` elements in a lab built with ``ejsgen build --web`` (issue #32): a PNG file, a
JPEG file and an array expression drawn in the 2D panel of the page, run by the browser's
Python (which has no OpenCV), show the pictures the served app shows, pixel for pixel.

References: the served app of the same spec, opened in the same Chromium (its pictures are
read by OpenCV at run time); Pillow's decoders for the files (the PNG exactly, with its alpha
dropped as the served panel drops it; the JPEG within a decoder's rounding); the array's
values written out in NumPy; and the page's canvas at the picture's quadrants.
"""

from __future__ import annotations

import io

import numpy as np
import pytest
from testkit.browser import serving

pytestmark = pytest.mark.browser

SPEC = """\
ejs: 1
title: Pictures in a page
model:
  variables:
    t: 0.0
    dt: 0.01
    board: {expr: "np.kron((np.indices((4, 4)).sum(axis=0) % 2) * 255, np.ones((2, 2))).astype(np.uint8)"}
  evolution:
    - code: t = t + dt
view:
  - drawing:
      x_range: [0, 9]
      y_range: [0, 2]
      height: 300
      children:
        - image: {file: pics/quadrants.png, position: [1.5, 1], size: [3, 2]}
        - image: {file: pics/photo.jpg, position: [4.5, 1], size: [3, 2]}
        - image: {source: board, position: [7.5, 1], size: [3, 2]}
"""

#: the PNG's quadrants (RGB), top-left, top-right, bottom-left, bottom-right; its alpha varies
QUADRANTS = ((230, 20, 20), (20, 200, 40), (30, 40, 220), (250, 200, 20))


def quadrants() -> np.ndarray:
    """(40, 60, 4) RGBA: four coloured quadrants, alpha falling from 255 to 55 down the rows."""
    img = np.zeros((40, 60, 4), np.uint8)
    for (r0, c0), colour in zip(((0, 0), (0, 30), (20, 0), (20, 30)), QUADRANTS):
        img[r0 : r0 + 20, c0 : c0 + 30, :3] = colour
    img[:, :, 3] = np.linspace(255, 55, 40).astype(np.uint8)[:, None]
    return img


def photo() -> np.ndarray:
    """(48, 96, 3) RGB: smooth gradients and a disc, as a photograph has."""
    y, x = np.mgrid[0:48, 0:96]
    img = np.stack([x * 255 / 95, y * 255 / 47, 128 + 100 * np.sin(x / 9.0) * np.cos(y / 7.0)], axis=-1)
    img[(x - 60) ** 2 + (y - 24) ** 2 < 144] = (255, 255, 255)
    return img.astype(np.uint8)


@pytest.fixture(scope="module")
def lab(tmp_path_factory, web_lab):
    from PIL import Image

    folder = tmp_path_factory.mktemp("pictures")
    (folder / "pics").mkdir()
    Image.fromarray(quadrants(), "RGBA").save(folder / "pics" / "quadrants.png")
    Image.fromarray(photo(), "RGB").save(folder / "pics" / "photo.jpg", quality=85)
    spec = folder / "pictures.ejs.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    return folder, web_lab(spec)


PICTURES = """() => {
  const E = window.__ejs2d;
  const p = E && Object.values(E.panels).find((q) => q.canvas && q.canvas.isConnected && q.frame);
  if (!p || !p.images) return null;
  const out = [];
  for (const im of Object.values(p.images)) {
    if (!im.complete || !im.naturalWidth) return null;
    const c = new OffscreenCanvas(im.naturalWidth, im.naturalHeight);
    const g = c.getContext("2d");
    g.drawImage(im, 0, 0);
    out.push({w: c.width, h: c.height, rgba: Array.from(g.getImageData(0, 0, c.width, c.height).data)});
  }
  return out.length === 3 ? out : null;
}"""


def pictures(page, until) -> dict[tuple[int, int], np.ndarray]:
    """The 2D panel's pictures as the browser decoded them, by (height, width): (H, W, 3) ints."""
    page.wait_for_selector("canvas.ejs2d-c[data-drawn]", timeout=120_000)
    got = until(page, PICTURES, timeout=60.0)
    return {(p["h"], p["w"]): np.array(p["rgba"], dtype=int).reshape(p["h"], p["w"], 4)[:, :, :3] for p in got}


def test_the_page_shows_the_served_pictures_of_png_jpeg_and_array_images(page, browser_context, lab, until) -> None:
    from PIL import Image

    folder, (_site, url, app_dir) = lab
    page.goto(url)
    web = pictures(page, until)
    assert page.evaluate("ejsWeb.failed") is None
    served_page = browser_context.new_page()
    try:
        with serving(app_dir) as (_app, served_url):
            served_page.goto(served_url)
            served = pictures(served_page, until)
    finally:
        served_page.close()
    assert sorted(web) == sorted(served) == [(8, 8), (40, 60), (48, 96)]
    for size in served:
        assert np.array_equal(web[size], served[size]), f"the {size} picture differs from the served one"
    # independent decoders: Pillow reads the PNG exactly (alpha dropped, as the panel drops it) ...
    png = np.asarray(Image.open(folder / "pics" / "quadrants.png").convert("RGB")).astype(int)
    assert np.array_equal(web[(40, 60)], png)
    # ... and the JPEG as any decoder does, within rounding (the picture is the photo, not noise)
    jpeg = np.asarray(Image.open(folder / "pics" / "photo.jpg").convert("RGB")).astype(int)
    assert np.abs(web[(48, 96)] - jpeg).mean() < 1.0 and np.abs(web[(48, 96)] - jpeg).max() <= 16
    assert np.abs(web[(48, 96)] - photo()).mean() < 4.0
    # the array expression, written out in NumPy: a 4 x 4 checkerboard of 2 x 2 pixel squares, grey
    board = np.kron((np.indices((4, 4)).sum(axis=0) % 2) * 255, np.ones((2, 2), int))
    assert np.array_equal(web[(8, 8)], np.repeat(board[:, :, None], 3, axis=2))
    # and the canvas shows the PNG where its position and size put it: each quadrant's colour at
    # its centre (x 0..3, y 0..2 of the panel's 9 x 2 window, equal aspect, centred)
    shot = np.asarray(Image.open(io.BytesIO(page.locator("canvas.ejs2d-c").first.screenshot())).convert("RGB")).astype(int)
    h, w = shot.shape[:2]
    s = min(w / 9.0, h / 2.0)
    for (qx, qy), colour in zip(((0.75, 1.5), (2.25, 1.5), (0.75, 0.5), (2.25, 0.5)), QUADRANTS):
        col, row = int(w / 2 + (qx - 4.5) * s), int(h / 2 - (qy - 1.0) * s)
        assert np.abs(shot[row, col] - colour).max() <= 2, (qx, qy, shot[row, col].tolist(), colour)


def test_a_page_build_leaves_the_image_files_out_and_ships_their_decoded_pictures(lab) -> None:
    import json
    import struct

    from ejsrl.view._image_file import WEB_COPY, decode_copy

    folder, (site, _url, _app_dir) = lab
    bundle = (site.out / "python" / "lab.bin").read_bytes()
    n = struct.unpack("<I", bundle[:4])[0]
    index = json.loads(bundle[4 : 4 + n])
    names = [name for name, _size in index]
    assert "pics/quadrants.png" not in names and "pics/photo.jpg" not in names
    at = 4 + n
    files = {}
    for name, size in index:
        files[name] = bundle[at : at + size]
        at += size
    import cv2

    for rel in ("pics/quadrants.png", "pics/photo.jpg"):
        shipped = decode_copy(files[rel + WEB_COPY])
        bgr = cv2.imread(str(folder / rel), cv2.IMREAD_COLOR)  # what the served app shows
        assert np.array_equal(shipped, bgr[:, :, ::-1])
        # the copy is a PNG any decoder reads to the same pixels
        assert np.array_equal(cv2.imdecode(np.frombuffer(files[rel + WEB_COPY], np.uint8), cv2.IMREAD_COLOR), bgr)
