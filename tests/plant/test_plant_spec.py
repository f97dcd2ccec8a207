"""The spec's plant: section: build errors at FILE:LINE:COL, and no credential in the app."""

from __future__ import annotations

from pathlib import Path

import pytest

from ejsgen.errors import SpecErrors

SPEC = """\
ejs: 1
title: plant link
model:
  variables:
    t: 0.0
    q: {expr: "np.zeros(5)"}
    q_meas: {expr: "np.zeros(5)"}
    grip: 1.0
    lag: 0.0
  evolution:
    - code: t = t + 0.02
plant:
  port: 1883
  commands:
    q: {to: joints, unit: deg, min: -90, max: [90, 90, 90, 90, 90], max_speed: 45}
    grip: {to: gripper}
  measurements:
    q_meas: {from: joints}
    lag: {from: latency, unit: ms}
view:
  - label: {text: "{lag}"}
"""


def _errors(tmp_path: Path, text: str) -> tuple[Path, list[str]]:
    from ejsgen.cli import build

    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(text, encoding="utf-8")
    with pytest.raises(SpecErrors) as info:
        build(spec, tmp_path / "out")
    return spec, [str(e) for e in info.value.errors]


def _at(spec: Path, needle: str) -> str:
    for k, line in enumerate(spec.read_text().splitlines(), 1):
        if needle in line:
            return f"{spec}:{k}:{line.index(needle) + 1}"
    raise AssertionError(needle)


def test_a_good_plant_section_builds_with_limits_in_radians(tmp_path: Path) -> None:
    from ejsgen.cli import build

    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(SPEC)
    out = build(spec, tmp_path / "out")
    app = (out / "app.py").read_text()
    assert "PlantCommand('q', 'joints', scale=0.017453292519943295" in app
    assert "q_min=[-1.5707963267948966," in app and "max_speed=0.7853981633974483" in app
    assert "paho-mqtt" in (out / "requirements.txt").read_text()


def test_an_unknown_variable_is_named_with_a_suggestion(tmp_path: Path) -> None:
    spec, errs = _errors(tmp_path, SPEC.replace("    q_meas: {from: joints}", "    q_mesa: {from: joints}"))
    assert errs == [f"{_at(spec, 'q_mesa')}: error: 'q_mesa' is not a model variable; did you mean 'q_meas'?"]


def test_limits_must_match_the_joints(tmp_path: Path) -> None:
    spec, errs = _errors(tmp_path, SPEC.replace("max: [90, 90, 90, 90, 90]", "max: [90, 90]"))
    assert len(errs) == 1 and errs[0].startswith(f"{_at(spec, '[90, 90]')}: error: max gives 2 limits for 5 joints")


def test_a_latency_in_degrees_is_refused(tmp_path: Path) -> None:
    spec, errs = _errors(tmp_path, SPEC.replace("{from: latency, unit: ms}", "{from: latency, unit: deg}"))
    assert len(errs) == 1 and "'deg' is not a unit of latency" in errs[0] and errs[0].startswith(f"{spec}:")


def test_credentials_in_the_spec_are_refused(tmp_path: Path) -> None:
    spec, errs = _errors(tmp_path, SPEC.replace("  port: 1883\n", "  port: 1883\n  password: hunter2\n"))
    assert len(errs) == 1
    assert errs[0].startswith(f"{spec}:13:") and "EJSRL_PLANT_PASSWORD" in errs[0]


def test_credentials_from_the_environment_never_reach_the_app(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from ejsgen.cli import build

    secret = "env-s3cret-never-in-app"
    monkeypatch.setenv("EJSRL_PLANT_PASSWORD", secret)
    monkeypatch.setenv("EJSRL_PLANT_USERNAME", "lab")
    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(SPEC)
    out = build(spec, tmp_path / "out")
    for f in out.rglob("*"):
        if f.is_file():
            assert secret.encode() not in f.read_bytes(), f


def test_a_video_section_builds_and_its_errors_are_located(tmp_path: Path) -> None:
    from ejsgen.cli import build

    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(SPEC.replace("  measurements:\n", "  video: {stale: 0.8, rate: 12}\n  measurements:\n    age: {from: video_age, unit: ms}\n")
                    .replace("    lag: 0.0\n", "    lag: 0.0\n    age: 0.0\n"))
    app = (build(spec, tmp_path / "out") / "app.py").read_text()
    assert "video_stale=0.8, video_rate=12.0" in app and "PlantMeasurement('age', 'video_age', scale=0.001)" in app
    spec, errs = _errors(tmp_path, SPEC.replace("  measurements:\n", "  video: {stale: 0}\n  measurements:\n"))
    assert len(errs) == 1 and errs[0].startswith(f"{_at(spec, '0}')}: error:") and "greater than 0" in errs[0], errs
    spec, errs = _errors(tmp_path, SPEC.replace("  measurements:\n", "  video: {stale: 1, fps: 3}\n  measurements:\n"))
    assert len(errs) == 1 and errs[0].startswith(f"{_at(spec, 'fps: 3')}:") and "fps" in errs[0], errs
    spec, errs = _errors(tmp_path, SPEC.replace("{from: latency, unit: ms}", "{from: video_age}"))
    assert len(errs) == 1 and "'rad' is not a unit of video_age" in errs[0] and "unit: ms" in errs[0], errs
