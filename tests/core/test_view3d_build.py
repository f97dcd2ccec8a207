"""A scene's ``view`` (the 3D view's camera) and ``set_view()``: what a build accepts and refuses.

Each refused spec is reported at the FILE:LINE:COL of the offending key, in plain words,
with a hint where one helps; a headless run of code that calls ``set_view`` changes the
camera the world asks for, and a bad call fails with a message that says why.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ejsgen.cli import main

HEAD = """\
ejs: 1
title: Camera
model:
  variables:
    t: 0.0
    dt: 0.1
    x: 0.0
  evolution:
    - code: |
        t = t + dt
        x = t
view:
"""


def refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], view: str) -> list[str]:
    spec = tmp_path / "cam.ejs.yaml"
    spec.write_text(HEAD + view)
    assert main(["validate", str(spec)]) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return [line.removeprefix(f"{spec}:") for line in err.splitlines() if line.startswith(str(spec))]


SCENE = "  - scene:\n      - sphere: {name: bob, position: [x, 0, 0]}\n"


@pytest.mark.parametrize(
    ("line", "expect"),
    [
        ("      - view: {preset: frnt}\n", "15:24: error: unknown preset 'frnt' (presets: front, back, right, left, top, bottom, iso, xz, yz, xy); did you mean 'front'?"),
        ("      - view: {follow: bobb}\n", "15:24: error: the view follows 'bobb', but the scene has no object of that name; did you mean 'bob'?"),
        ("      - view: {preset: front, up: [0, 1, 0]}\n", "15:35: error: up is parallel to the direction the camera looks in, so no direction on screen is up (it looks along [0, 1, 0]); e.g. up: [0, 0, 1]"),
        ("      - view: {position: [0, 0, 3], target: [0, 0, 0]}\n", "15:15: error: up is parallel"),
        ("      - view: {position: [1, 2, 3], target: [1, 2, 3]}\n", "15:45: error: the camera's target is its position: it looks nowhere; move the target or the position"),
        ("      - view: {preset: top, position: [0, 0, 3]}\n", "15:24: error: give a view either a position or a preset, not both"),
        ("      - view: {fov: 200}\n", "15:21: error: fov is the vertical field of view in degrees, 1 to 170; got 200"),
        ("      - view: {up: [0, 0, 0]}\n", "15:20: error: up must not be [0, 0, 0]"),
        ("      - view: {rotation: [0, 0, 1]}\n", "15:26: error: a view has no rotation: the camera turns to its target; give position, target and up"),
        ("      - view: {follow_offset: true}\n", "15:31: error: follow_offset needs follow"),
        ("      - view: {preset: top}\n      - view: {preset: front}\n", "16:15: error: a scene has one camera: this is its second 'view'; merge the two into one view element"),
    ],
    ids=["preset", "follow", "up-preset", "up-default", "on-target", "preset-and-position", "fov", "up-zero", "rotation",
         "offset-alone", "two-views"],
)
def test_a_bad_view_is_refused_at_its_place(tmp_path, capsys, line, expect):
    errors = refused(tmp_path, capsys, SCENE + line)
    assert errors and errors[0].startswith(expect), errors


def test_a_default_up_along_the_view_is_refused_where_the_view_is(tmp_path, capsys):
    # the camera straight above its target, looking down, with the default up [0, 0, 1]
    errors = refused(tmp_path, capsys, SCENE + "      - view: {position: [0, 0, 3], target: [0, 0, 0]}\n")
    assert errors[0] == "15:15: error: up is parallel to the direction the camera looks in, so no direction on screen is up (it looks along [0, 0, -3]); e.g. up: [0, 1, 0]", errors


def test_a_good_view_builds_and_set_view_moves_the_camera_in_a_headless_run(tmp_path):
    from ejsrl.app import load_app
    from ejsrl.view._camera import resolve
    from ejsrl.world.view3d import view_node

    spec = tmp_path / "cam.ejs.yaml"
    spec.write_text(HEAD.replace("        x = t\n", "        x = t\n        if t > 0.25 and t < 0.35:\n            set_view(preset='top', fov=30)\n")
                    + SCENE + "      - view: {position: [x, -4, 1], target: [x, 0, 0], fov: 40}\n")
    assert main(["build", str(spec), "-o", str(tmp_path / "app")]) == 0
    app = load_app(tmp_path / "app")
    with app.lock:
        app.scene.update(app.model, app.safe_value, first=True)
        node = view_node(app.world)
        pose = resolve(app.world, node, spec_position=True)
    assert np.allclose(pose.position, [0, -4, 1]) and np.allclose(pose.look_at, [0, 0, 0])
    assert pose.fov == pytest.approx(np.radians(40))
    for _ in range(4):
        app.step_once()
    assert app.error is None
    with app.lock:
        pose = resolve(app.world, node, spec_position=True)
    assert node.props["commanded"] == {"preset": "top", "fov": 30.0}
    d = pose.look_at - pose.position
    assert d[2] < 0 and np.allclose(d[:2], 0, atol=1e-12)  # straight down, at the followed... target [x, 0, 0]
    assert pose.fov == pytest.approx(np.radians(30)) and np.allclose(pose.up, [0, 1, 0])


@pytest.mark.parametrize(
    ("call", "message"),
    [
        ("set_view(preset='frnt')", "unknown preset 'frnt'"),
        ("set_view(follow='bobb')", "did you mean 'bob'"),
        ("set_view(fov=0)", "1 to 170"),
        ("set_view(position=[0, 0])", "three finite numbers"),
        ("set_view(position=[0, 0, 1], preset='top')", "either a position or a preset"),
    ],
)
def test_a_bad_set_view_call_stops_the_run_with_the_reason(tmp_path, call, message):
    from ejsrl.app import load_app

    spec = tmp_path / "cam.ejs.yaml"
    spec.write_text(HEAD.replace("        x = t\n", f"        x = t\n        {call}\n") + SCENE)
    assert main(["build", str(spec), "-o", str(tmp_path / "app")]) == 0
    app = load_app(tmp_path / "app")
    app.step_once()
    assert app.error is not None and message in str(app.error), app.error


def test_a_view_may_follow_a_robots_link(tmp_path, capsys):
    spec = tmp_path / "arm.ejs.yaml"
    spec.write_text(
        "ejs: 1\ntitle: Arm\nimports:\n  - from ejsrl.robotics import models\nmodel:\n  variables:\n    q: [0.0, 0.3, 0.2, 0.0, 0.0, 0.0]\n"
        "view:\n  - scene:\n      - robot: {name: arm, model: \"models.puma560()\", q: q}\n"
        "      - view: {preset: front, follow: arm.link6, follow_offset: true}\n"
    )
    assert main(["validate", str(spec)]) == 0
    spec.write_text(spec.read_text().replace("follow: arm.link6", "follow: arn.link6"))
    assert main(["validate", str(spec)]) == 1
    assert "11:39: error: the view follows 'arn.link6', but the scene has no object of that name; did you mean 'arm.link6'?" \
        in capsys.readouterr().err
