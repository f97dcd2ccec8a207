"""Robotics labs built with ``--web``: a trajectory lab (examples/paper/path_planning_434), the
six-axis arm's kinematics (a ``robot`` element: its links' meshes made by trimesh in the page,
a wrist camera rendered by NumPy on 32-bit WebAssembly), the six-axis arm example, a SciPy
lab (examples/mobile_prm_laser: ``scipy.linalg``, ``scipy.spatial``) and the UR5 from its URDF file
(examples/urdf_arm: yourdfpy on the page's lxml). Each page shows the
served panel and computes the native app's numbers to 1e-12."""

from __future__ import annotations

import pytest

from testkit.csvcompare import assert_same_csv, native_csv

pytestmark = pytest.mark.browser


@pytest.mark.parametrize("name", ["paper/path_planning_434", "paper/six_axis_kinematics", "six_axis_arm",
                                  "mobile_prm_laser", "urdf_arm"])
def test_robotics_page_runs_the_native_numbers(page, web_lab, name: str) -> None:
    _site, url, app_dir = web_lab(name)
    # every text the loader shows, as the student reads it
    page.add_init_script("""window.__loaderTexts = [];
      new MutationObserver(() => { const el = document.getElementById("ejsweb-loading");
        if (el && window.__loaderTexts.at(-1) !== el.textContent) window.__loaderTexts.push(el.textContent); })
        .observe(document, {subtree: true, childList: true, characterData: true});""")
    page.goto(url)
    page.get_by_role("button", name="Play").wait_for(state="visible", timeout=120_000)
    texts = page.evaluate("window.__loaderTexts")
    # after the bytes, the loader says what it does, not a frozen "28.6 of 28.6 MB"
    assert any("Loading the lab…" in t for t in texts), texts  # under the lab's title
    for stage in ("Starting Python", "Drawing the lab…"):
        assert any(stage in t for t in texts), (stage, texts)
    assert page.evaluate("ejsWeb.failed") is None
    state = page.evaluate("ejsWeb.call('state')")
    assert state["error"] is None, state["error"]
    got = page.evaluate("ejsWeb.call('headless', {duration: 2})")
    assert got["status"] == 0
    assert_same_csv(got["csv"], native_csv(app_dir, 2), more_rows_than=10)
    if name == "urdf_arm":
        _lit_as_served(page, app_dir)
    if name == "urdf_arm":  # its page got lxml's Python (the browser's Python has lxml compiled in) and yourdfpy's
        import json
        import struct
        import zipfile

        with zipfile.ZipFile(_site.out / "python" / "python315.zip") as z:
            assert "lxml/__init__.pyc" in z.namelist()
        bundle = (_site.out / "python" / "lab.bin").read_bytes()
        index = {rel for rel, _size in json.loads(bundle[4 : 4 + struct.unpack("<I", bundle[:4])[0]])}
        assert {"yourdfpy/urdf.pyc", "ejsrl/robotics/data/ur5/ur5.urdf"} <= index, sorted(index)[:20]
    if name == "paper/six_axis_kinematics":
        # the wrist camera's picture (rendered by the runtime's NumPy rasterizer, 240 x 180) reaches
        # the panel as an image the browser decodes (PNG: the page has no OpenCV)
        page.wait_for_function("[...document.images].some((i) => i.complete && i.naturalWidth === 240"
                               " && i.naturalHeight === 180)", timeout=60_000)


def _arm_brightness(page) -> float:
    """The mean grey of the 3D view's non-background pixels (the arm and its shadow), from a screenshot."""
    import cv2
    import numpy as np

    page.wait_for_timeout(3000)  # the meshes drawn (the view's first frames after Play shows)
    png = page.locator("canvas").first.screenshot()
    img = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_GRAYSCALE).astype(float)
    drawn = img < 225  # the grid's white floor and the sky are the background
    assert drawn.sum() > 2000, drawn.sum()
    return float(img[drawn].mean())


def _lit_as_served(page, app_dir) -> None:
    """On software WebGL the page leaves viser's environment map out (its prefiltering was most of a
    start's CPU) and lights the scene with a hemisphere light instead: the UR5 is drawn about as
    bright as the served app draws it in the same browser (it was near-black: session 11's second trial)."""
    from testkit.browser import serving

    assert page.evaluate("ejsWeb.software") is True  # headless Chromium: SwiftShader
    in_page = _arm_brightness(page)
    with serving(app_dir) as (_app, served_url):
        served = page.context.new_page()
        try:
            served.goto(served_url)
            served.get_by_role("button", name="Play").wait_for(state="visible", timeout=120_000)
            on_server = _arm_brightness(served)
        finally:
            served.close()
    assert abs(in_page - on_server) < 0.12 * on_server, (in_page, on_server)
