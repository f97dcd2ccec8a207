"""The URDF arm example (examples/urdf_arm.ejs.yaml) in a real browser (Debian's Chromium).

A student opens it and sees the UR5 drawn with its own meshes; ticks *Demo path* and
presses Play: the arm follows the mstraj path on screen and the readouts change.

With ``EJSGEN_GALLERY=1`` the screenshot is also written, at 640x400, to
``examples/gallery/urdf_arm.png`` (the picture of ``examples/README.md``).
"""

from __future__ import annotations

import io
import os

import numpy as np
import pytest
from PIL import Image
from testkit import ROOT
from testkit.browser import ARTIFACTS, canvas_pixels, serving, wait_until


@pytest.fixture
def served(built):
    with serving(built("urdf_arm")) as (app, url):
        yield app, url


@pytest.mark.browser
def test_the_urdf_arm_is_drawn_with_its_meshes_and_follows_the_demo_path(served, page):
    app, url = served
    page.goto(url)
    page.wait_for_selector("canvas", state="attached", timeout=45_000)
    page.get_by_role("button", name="Play").first.wait_for(timeout=45_000)
    assert page.get_by_text("UR5 from its URDF file", exact=True).first.is_visible()
    wait_until(lambda: (page.locator("canvas").first.bounding_box() or {"width": 0})["width"] > 300, timeout=60,
               what="the 3D view to be laid out")
    # the links are the URDF's STL meshes (hundreds of triangles each), not automatic rods
    assert all(len(app.world[f"ur5.link{i}"].parts()[0].faces) > 300 for i in range(7))
    before = canvas_pixels(page)
    wrist = app.world["ur5.link6"].T_world().copy()

    page.get_by_role("checkbox").first.check()
    wait_until(lambda: app.model.demo, what="the demo checkbox to reach the model")
    page.get_by_role("button", name="Play").first.click()
    wait_until(lambda: app.model.k > 40, timeout=90, what="40 samples of the demo path")
    assert app.error is None
    np.testing.assert_allclose(app.model.q_deg, app.model.path[app.model.k], atol=1e-9)
    assert np.linalg.norm(app.world["ur5.link6"].T_world()[:3, 3] - wrist[:3, 3]) > 0.05
    wait_until(lambda: np.mean(np.abs(canvas_pixels(page) - before).sum(axis=2) > 30) > 0.002, timeout=20,
               what="the arm to move on screen")
    page.get_by_role("button", name="Pause").first.click()
    wait_until(lambda: not app.is_playing(), what="Pause")
    buttons = page.locator(".mantine-Notification-closeButton")  # the GPU-less browser's WebGL notice
    for i in range(buttons.count()):
        try:
            buttons.nth(i).click(timeout=2_000)
        except Exception:  # noqa: BLE001 - it may close by itself meanwhile
            pass
    wait_until(lambda: page.locator(".mantine-Notification-root").count() == 0, timeout=10, what="the notices to close")
    png = page.screenshot()
    ARTIFACTS.mkdir(exist_ok=True)
    (ARTIFACTS / "lab_urdf_arm.png").write_bytes(png)
    if os.environ.get("EJSGEN_GALLERY"):
        Image.open(io.BytesIO(png)).convert("RGB").resize((640, 400), Image.LANCZOS).save(
            ROOT / "examples" / "gallery" / "urdf_arm.png", optimize=True)
