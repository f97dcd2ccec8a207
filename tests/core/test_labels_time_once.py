"""The panel shows the time under Play/Step/Reset: no example's label repeats it (a student saw
``t = 920`` twice, one under the other)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from testkit import EXAMPLES

SPECS = sorted(EXAMPLES.rglob("*.ejs.yaml"))


def _label_texts(node) -> list[str]:
    if isinstance(node, dict):
        out = [node["label"]["text"]] if isinstance(node.get("label"), dict) and "text" in node["label"] else []
        return out + [t for v in node.values() for t in _label_texts(v)]
    if isinstance(node, list):
        return [t for v in node for t in _label_texts(v)]
    return []


@pytest.mark.parametrize("spec", SPECS, ids=lambda p: str(p.relative_to(EXAMPLES)))
def test_no_label_repeats_the_time_the_panel_shows(spec: Path) -> None:
    doc = yaml.safe_load(spec.read_text(encoding="utf-8"))
    texts = _label_texts(doc.get("view", []))
    repeated = [t for t in texts if re.search(r"\{\s*t\s*(?::[^}]*)?\}", t)]  # every example's time is t
    assert not repeated, f"{spec.name}: a label shows t, which the panel already shows: {repeated}"


def test_the_check_sees_the_labels() -> None:
    assert len(SPECS) >= 15
    assert sum(len(_label_texts(yaml.safe_load(s.read_text(encoding="utf-8")).get("view", []))) for s in SPECS) > 30
