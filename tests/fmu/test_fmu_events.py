"""One event engine: a state event of an FMU and one of the spec's own ``events:`` are
located by the same code (ejsrl.sim._events), so the Reference BouncingBall as a
model-exchange FMU and the same ball written as an ODE page with an event bounce at the
same instants, to the location tolerance; and the ejsrl.fmi package does not import the
model (the model drives it)."""

from __future__ import annotations

import io
import textwrap

import numpy as np
from testkit import run_app

from test_reference_fmus import bounce_times, reference

AS_FMU = """\
ejs: 1
title: The Reference ball as an FMU
model:
  variables: {t: 0.0, dt: 0.01, h: 1.0, v: 0.0, speeds: 0}
  evolution:
    - ode:
        method: dopri5
        tolerance: 1.0e-10
        equations: {speeds: "abs(v)"}
fmus:
  ball:
    file: BouncingBall.fmu
    kind: model_exchange
    outputs: {h: h, v: v}
"""

AS_SPEC = """\
ejs: 1
title: The same ball as an ODE page with an event
model:
  variables: {t: 0.0, dt: 0.01, h: 1.0, v: 0.0, speeds: 0.0, g: -9.81, restitution: 0.7, v_min: 0.1}
  evolution:
    - ode:
        method: dopri5
        tolerance: 1.0e-10
        equations: {speeds: "abs(v)", h: v, v: g}
        events:
          - name: impact
            when: h
            direction: down
            action: |
              h = 0.0
              v = -restitution * v
              if v < v_min:
                  v = 0.0
                  g = 0.0
"""


def test_an_fmus_state_events_and_the_specs_own_are_located_alike(tmp_path):
    from ejsgen.cli import build

    (tmp_path / "BouncingBall.fmu").write_bytes(reference(2, "BouncingBall").read_bytes())
    runs = []
    for name, text in (("fmu", AS_FMU), ("spec", AS_SPEC)):
        spec = tmp_path / f"{name}.ejs.yaml"
        spec.write_text(textwrap.dedent(text))
        app = build(spec, tmp_path / name)
        r = run_app(app, "--headless", "--duration", "2.5", "--csv", "-", "--vars", "t,h,v")
        assert r.returncode == 0, r.stderr
        runs.append(np.genfromtxt(io.StringIO(r.stdout), delimiter=",", names=True))
    fmu, own = runs
    a, b = bounce_times(fmu["t"], fmu["h"], fmu["v"]), bounce_times(own["t"], own["h"], own["v"])
    assert len(a) == len(b) >= 5
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)
    np.testing.assert_allclose(fmu["h"], own["h"], rtol=0, atol=1e-8)


def test_the_fmi_package_does_not_import_the_model():
    """The model imports ejsrl.fmi (lazily, when a spec has FMUs); nothing there imports the model."""
    import ast

    from testkit import ROOT

    for path in sorted((ROOT / "runtime" / "ejsrl" / "fmi").glob("*.py")):
        tree = ast.parse(path.read_text())
        imported = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)} | {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        assert "ejsrl.sim.model" not in imported, path.name
