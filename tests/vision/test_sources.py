"""Real image sources: a video file and an image sequence the test writes (with OpenCV's own
writer), read frame by frame through the vision pipeline; a missing camera and file say so;
a built app reads a video listed under its assets."""

from __future__ import annotations

import textwrap
from pathlib import Path

import cv2
import numpy as np
import pytest

from ejsrl.vision import Pipeline, centroid
from ejsrl.vision.sources import ImageSource
from testkit.labs import headless
from testkit.video import FPS, H, N, W, frame, true_x, write_video


@pytest.fixture()
def video(tmp_path: Path) -> Path:
    return write_video(tmp_path / "clip.avi")


def _x_of(rgb: np.ndarray) -> float:
    mask = Pipeline("gray", ("threshold", {"level": 128}))(rgb).image
    return float(centroid(mask)[0])


def test_a_video_file_goes_through_the_pipeline_frame_by_frame(video: Path) -> None:
    src = ImageSource(video)
    assert (src.kind, src.fps, src.frame_count) == ("video", FPS, N)
    xs = []
    for _ in range(N):
        rgb = src.read()
        assert rgb.shape == (H, W, 3) and rgb.dtype == np.uint8
        xs.append(_x_of(rgb))
    np.testing.assert_allclose(xs, [true_x(i) for i in range(N)], atol=0.3)
    # RGB, not OpenCV's BGR: the background is blue
    assert tuple(int(c) for c in src.read()[5, 5]) == pytest.approx((10, 20, 90), abs=6)
    # it looped: that last read was frame 0 again; frame_at follows the clock (12 fps)
    assert _x_of(src.frame_at(1.0)) == pytest.approx(true_x(12), abs=0.3)
    assert _x_of(src.frame_at(0.25)) == pytest.approx(true_x(3), abs=0.3)
    assert _x_of(src.frame_at(2.5)) == pytest.approx(true_x(30 % N), abs=0.3)
    # each source reads on its own (one per session): a second one starts at frame 0
    other = ImageSource(video, loop=False, size=(80, 60))
    assert other.read().shape == (60, 80, 3)
    assert _x_of(src.read()) == pytest.approx(true_x(7), abs=0.3)  # src went on from frame 6
    for _ in range(N - 1):
        other.read()
    with pytest.raises(EOFError, match="has no more frames"):
        other.read()


def test_an_image_sequence_reads_in_name_order(tmp_path: Path) -> None:
    folder = tmp_path / "frames"
    folder.mkdir()
    for i in (3, 0, 2, 1):  # written out of order
        cv2.imwrite(str(folder / f"f{i:03d}.png"), frame(i))
    (folder / "notes.txt").write_text("not an image")
    for src in (ImageSource(folder), ImageSource(str(folder / "*.png"))):
        assert src.kind == "images" and src.frame_count == 4
        assert [_x_of(src.read()) for _ in range(5)] == pytest.approx([true_x(i) for i in (0, 1, 2, 3, 0)], abs=1e-9)


def test_missing_devices_and_files_say_what_to_do(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="cannot open camera 97: there is no such camera on this machine"):
        ImageSource(97)
    with pytest.raises(ValueError, match="no such file or folder .*list it under assets"):
        ImageSource(tmp_path / "nope.mp4")
    bad = tmp_path / "bad.mp4"
    bad.write_bytes(b"this is not a video")
    with pytest.raises(ValueError, match="cannot read the video"):
        ImageSource(bad)
    with pytest.raises(ValueError, match="has no images"):
        ImageSource(tmp_path)


def test_a_built_app_reads_its_video_asset_each_step(video: Path, tmp_path: Path) -> None:
    from ejsgen.cli import build

    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(textwrap.dedent("""
        ejs: 1
        title: Video source
        imports:
          - from ejsrl import vision
        assets: [clip.avi]
        model:
          variables:
            t: 0.0
            dt: {expr: 1/12}
            src: {expr: "vision.ImageSource('clip.avi')"}
            x: 0.0
          evolution:
            - code: |
                rgb = src.frame_at(t)
                x = float(vision.centroid(vision.threshold(vision.to_gray(rgb), 128))[0])
                t = t + dt
        view:
          - image: {source: "src.frame_at(t)"}
        """).lstrip())
    app = build(spec, tmp_path / "app")
    d = headless(app, 1.0, vars="t,x")
    frames = np.rint(d["t"][1:] * FPS).astype(int) - 1  # row 0 is the start; x is measured before t advances
    assert len(frames) == 12
    np.testing.assert_allclose(d["x"][1:], [true_x(i % N) for i in frames], atol=0.3)
    # served, every tab's session is an App made as the classroom makes them: each reads its own source
    from ejsrl.app import load_app

    first = load_app(app)
    second = type(first)(first.model_cls, first.view, sim=first.sim, meta=first.meta, base_dir=first.base_dir)
    assert first.model.src is not second.model.src
    for _ in range(5):
        first.step_once()
    second.step_once()
    assert first.model.x == pytest.approx(true_x(4), abs=0.3) and second.model.x == pytest.approx(true_x(0), abs=0.3)
    assert first.model.src.index == 5 and second.model.src.index == 1  # the next frame each would read
