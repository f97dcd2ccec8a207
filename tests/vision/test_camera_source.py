"""A scene's camera element reading a real source (``source:``) instead of rendering the scene:
a video the test writes with OpenCV's writer is what ``capture`` gives, frame for frame at the
simulation's time, in a built app, per session; an image folder, the build's checks of bad
sources (FILE:LINE:COL, a hint) and a missing camera's message, with the app still serving."""

from __future__ import annotations

import textwrap
from pathlib import Path

import cv2
import numpy as np
import pytest

from ejsgen.cli import build
from ejsgen.errors import SpecErrors
from ejsrl.app import load_app
from testkit.labs import headless
from testkit.video import FPS, N, W, frame, true_x, write_video


def _lab(folder: Path, source: str, resolution: str = "[160, 120]") -> Path:
    spec = folder / "lab.ejs.yaml"
    spec.write_text(textwrap.dedent(f"""
        ejs: 1
        title: Camera source
        imports:
          - from ejsrl import vision
        model:
          variables:
            t: 0.0
            dt: {{expr: 1/12}}
            x: 0.0
            w: 0
          evolution:
            - code: |
                rgb = capture("cam")
                w = rgb.shape[1]
                x = float(vision.centroid(vision.threshold(vision.to_gray(rgb), 128))[0])
                t = t + dt
        view:
          - image: {{source: 'capture("cam")', label: What the camera sees}}
          - scene:
              - camera: {{name: cam, source: {source}, resolution: {resolution}, position: [0, 0, 1]}}
        """).lstrip())
    return spec


def test_a_camera_element_reads_a_video_at_the_simulation_time_in_each_session(tmp_path: Path) -> None:
    write_video(tmp_path / "clip.avi")
    app = build(_lab(tmp_path, "clip.avi"), tmp_path / "app")
    assert (tmp_path / "app" / "clip.avi").is_file()  # the video travels with the app
    d = headless(app, 1.0, vars="t,x,w")
    frames = np.rint(d["t"][1:] * FPS).astype(int) - 1  # x is measured before t advances
    assert len(frames) == 12 and (d["w"][1:] == W).all()
    np.testing.assert_allclose(d["x"][1:], [true_x(i) for i in frames], atol=0.3)
    # served: every tab's session (an App as the classroom makes them) reads its own video
    first = load_app(app)
    second = type(first)(first.model_cls, first.view, sim=first.sim, meta=first.meta, base_dir=first.base_dir)
    for _ in range(6):
        first.step_once()
    second.step_once()
    assert first.error is None and second.error is None
    assert first.model.x == pytest.approx(true_x(5), abs=0.3) and second.model.x == pytest.approx(true_x(0), abs=0.3)
    assert first._camera_sources is not second._camera_sources
    # the camera's frame is what the image element shows; a real source has no depth image
    np.testing.assert_array_equal(first.capture("cam"), cv2.cvtColor(_decoded(tmp_path / "clip.avi", 6), cv2.COLOR_BGR2RGB))
    with pytest.raises(ValueError, match="real source .* no depth image"):
        first.capture_depth("cam")


def _decoded(path: Path, i: int) -> np.ndarray:
    cap = cv2.VideoCapture(str(path))
    cap.set(cv2.CAP_PROP_POS_FRAMES, i)
    ok, frame = cap.read()
    cap.release()
    assert ok
    return frame


def test_an_image_folder_resized_to_the_cameras_resolution(tmp_path: Path) -> None:
    (tmp_path / "frames").mkdir()
    for i in range(N):
        cv2.imwrite(str(tmp_path / "frames" / f"f{i:03d}.png"), frame(i))
    app = build(_lab(tmp_path, "frames", "[320, 240]"), tmp_path / "app")
    d = headless(app, 0.5, vars="t,x,w")
    # an image sequence runs at 30 frames a second: x is measured at t - dt, in frame floor(30 (t - dt))
    frames = np.floor((d["t"][1:] - 1 / 12) * 30 + 1e-6).astype(int)
    assert (d["w"][1:] == 320).all()
    np.testing.assert_allclose(d["x"][1:], [true_x(i % N, 2.0) for i in frames], atol=0.6)


@pytest.mark.parametrize(("source", "message"), [
    ("clp.avi", r"lab.ejs.yaml:20:\d+: error: the source of camera 'cam': the file 'clp.avi' does not exist.*did you mean 'clip.avi'"),
    ("notes.txt", r"lab.ejs.yaml:20:\d+: error: the source of camera 'cam': 'notes.txt' is neither a video nor an image"),
    ("-1", r"lab.ejs.yaml:20:\d+: error: the source of camera 'cam' is -1: a camera index is a whole number >= 0"),
    ("rtps://host/live", r"lab.ejs.yaml:20:\d+: error: .*no 'rtps://' stream.*did you mean 'rtsp://'"),
    ("'frames/*.png'", r"lab.ejs.yaml:20:\d+: error: .*no image files match 'frames/\*.png'"),
])
def test_bad_sources_are_build_errors_at_their_place(tmp_path: Path, source: str, message: str) -> None:
    write_video(tmp_path / "clip.avi")
    (tmp_path / "notes.txt").write_text("not a video")
    with pytest.raises(SpecErrors, match=message):
        build(_lab(tmp_path, source), tmp_path / "app")


def test_a_missing_camera_pauses_the_lab_with_a_message_and_the_app_keeps_serving(tmp_path: Path) -> None:
    app = load_app(build(_lab(tmp_path, "97"), tmp_path / "app"))
    app.step_once()
    assert app.error is not None
    assert "camera 'cam' (source 97): cannot open camera 97: there is no such camera" in app.error.message
    # said at the camera element, whose source: is what to change (not at the code that captured),
    # and what to do said as that element is written
    spec = (tmp_path / "lab.ejs.yaml").read_text().splitlines()
    line = next(i for i, text in enumerate(spec, 1) if "- camera:" in text)
    assert app.error.where.startswith(f"lab.ejs.yaml:{line}:"), app.error.where
    assert "source: clip.mp4" in app.error.message and "ImageSource" not in app.error.message
    assert not app.playing
    # the session lives on: a reset clears the message, another step says it again
    app.reset()
    assert app.error is None
    app.step_once()
    assert "no such camera" in app.error.message


@pytest.mark.browser
def test_a_missing_camera_is_a_message_in_the_page_and_the_lab_keeps_serving(tmp_path: Path, page) -> None:
    from testkit.browser import serving, wait_until

    with serving(build(_lab(tmp_path, "97"), tmp_path / "app")) as (app, url):
        page.goto(url)
        page.wait_for_selector("canvas", state="attached", timeout=45_000)
        page.get_by_role("button", name="Play").click()
        wait_until(lambda: app.error is not None, what="the capture's error to be recorded")
        box = page.locator("b", has_text="Error")
        box.first.wait_for(timeout=30_000)
        page.get_by_text("cannot open camera 97: there is no such camera", exact=False).first.wait_for(timeout=30_000)
        assert not app.is_playing()
        # the server keeps serving: a reload shows the lab and its message again
        page.reload()
        page.wait_for_selector("canvas", state="attached", timeout=45_000)
        page.get_by_text("no such camera", exact=False).first.wait_for(timeout=30_000)
