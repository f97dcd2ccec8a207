"""The view tree is validated by pydantic in one pass (ejsgen._view_union), discriminated on
each element's key, and every problem is reported at its FILE:LINE:COL in the old words."""

from __future__ import annotations

from pathlib import Path

import pytest
from pydantic import ValidationError

from ejsgen._view_union import SCENE_ELEMENT, VIEW_ELEMENT, view_adapter
from ejsgen.cli import main

HEAD = "ejs: 1\ntitle: V\nmodel:\n  variables:\n    x: 0.0\nview:\n"


def _errors(tmp_path: Path, capsys: pytest.CaptureFixture[str], view: str) -> list[str]:
    spec = tmp_path / "v.ejs.yaml"
    spec.write_text(HEAD + view)
    assert main(["validate", str(spec)]) == 1
    return [line.removeprefix(f"{spec}:") for line in capsys.readouterr().err.splitlines() if line.startswith(str(spec))]


def test_an_unknown_key_deep_in_the_tree_is_found_at_its_place(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    view = (
        "  - folder:\n"
        "      children:\n"
        "        - tabs:\n"
        "            tabs:\n"
        "              One:\n"
        "                - scene:\n"
        "                    - group:\n"
        "                        children:\n"
        "                          - sphere: {radius: 0.1, radiuss: 2}\n"
    )
    assert _errors(tmp_path, capsys, view) == ["15:51: error: unknown key 'radiuss'; did you mean 'radius'?"]


def test_each_kind_of_misplaced_item_keeps_its_words(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    view = (
        "  - scene:\n"
        "      - slider: {bind: x, min: 0, max: 1}\n"  # 8: a GUI element in a scene
        "      - box:\n"  # 9: no properties
        "      - 5\n"  # 10: not a mapping
        "  - scene: 3\n"  # 11: not a list
        "  - sphere: {}\n"  # 12: a 3D element outside
        "  - folder:\n"
        "      children:\n"
        "        - lable: {text: hi}\n"  # 15: a typo
    )
    assert _errors(tmp_path, capsys, view) == [
        "8:9: error: 'slider' is a GUI element and cannot stand in a scene",
        "9:13: error: expected a mapping of properties, got nothing (null)",
        "10:9: error: each 3D element is a one-key mapping 'kind: {properties}'; kinds: "
        "box, sphere, cylinder, arrow, line, trail, points, frame, grid, text3d, mesh, group, robot, camera, gizmo, view, "
        "vehicle, laser, occupancy, path, ellipse, particles",
        "11:12: error: expected a list of 3D elements, got 3",
        "12:5: error: 'sphere' is a 3D element and cannot stand outside a scene",
        "15:11: error: unknown view element kind 'lable'; did you mean 'label'?",
    ]


def test_problems_inside_an_element_with_problems_are_reported_too(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The whole tree is checked at once: a folder's bad label does not hide its children's errors."""
    view = "  - folder:\n      label: [1]\n      children:\n        - slider: {bind: x, min: 0}\n"
    assert _errors(tmp_path, capsys, view) == [
        "8:14: error: 'label' must be text (an expression), got a list; write an expression as text in quotes, e.g. \"[x, 0, y]\"",
        "10:19: error: missing required key 'max'",
    ]


def test_the_adapter_discriminates_on_the_element_key() -> None:
    items = view_adapter.validate_python([{"scene": [{"box": {"size": [1, 2, 3]}}]}, {"label": {"text": "hi"}}])
    assert [type(i).__name__ for i in items] == ["SceneItem", "LabelItem"]
    assert type(items[0].scene[0].box).__name__ == "BoxEl" and items[0].scene[0].box.size == [1, 2, 3]
    with pytest.raises(ValidationError) as err:
        view_adapter.validate_python([{"box": {}}, {"scene": [{"label": {"text": "x"}}]}])
    assert [(e["type"], e["loc"]) for e in err.value.errors()] == [(VIEW_ELEMENT, (0,)), (SCENE_ELEMENT, (1, "scene", "scene", 0))]
