"""A lab with nothing to step (no evolution, no programs) shows Reset but no Play or Step,
which would change nothing; a lab that evolves shows all three."""

from __future__ import annotations

from pathlib import Path

import pytest

from ejsgen.cli import build
from ejsrl.app import load_app
from ejsrl.view.viser_view import ViserView, make_server

STILL = """\
ejs: 1
title: Still
model:
  variables:
    a: 1.0
view:
  - slider: {bind: a, min: 0, max: 2}
"""

MOVING = STILL.replace("    a: 1.0\n", "    a: 1.0\n  evolution:\n    - code: |\n        a = a * 0.5\n")


@pytest.mark.parametrize(("spec", "bar"), [(STILL, ["Reset"]), (MOVING, ["Play", "Step", "Reset"])], ids=["still", "moving"])
def test_the_control_bar_offers_only_what_can_change_the_lab(tmp_path: Path, spec: str, bar: list[str]) -> None:
    file = tmp_path / "lab.ejs.yaml"
    file.write_text(spec)
    app = load_app(build(file, tmp_path / "app"))
    server, _url = make_server("127.0.0.1", 0)
    try:
        panel = ViserView(app, server).panel
        shown = [b.label for b in (panel.play_button, panel.step_button, panel.reset_button) if b is not None]
        assert shown == bar
        app.model.a = 0.25
        panel.reset_button._impl.update_cb[0](None)  # Reset still puts the declared value back
        assert app.model.a == 1.0
    finally:
        server.stop()
