"""``nofriction`` means what it means in Robotics Toolbox: ``coulomb=True`` removes the
Coulomb friction, ``viscous=True`` the viscous friction (default: Coulomb only). Ported
calls are compared with RTB 1.5's answers (fixture puma560_rtb_ik_friction.json)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ejsrl.robotics import models

from testkit.robotics import FIXTURES

CASES = json.loads((FIXTURES / "puma560_rtb_ik_friction.json").read_text())["nofriction"]


@pytest.mark.parametrize("case", CASES, ids=lambda c: f"coulomb={c['coulomb']}-viscous={c['viscous']}")
def test_nofriction_rne_equals_the_toolbox(case):
    p = models.puma560()
    # the ported line: p.nofriction(coulomb=..., viscous=...).rne(q, qd, qdd)
    tau = p.nofriction(coulomb=case["coulomb"], viscous=case["viscous"]).rne(case["q"], case["qd"], case["qdd"])
    np.testing.assert_allclose(tau, case["rne"], rtol=1e-9, atol=1e-9)


def test_nofriction_default_keeps_viscous_friction():
    p = models.puma560()
    qd = np.array([0.5, -0.3, 0.2, 0.1, -0.4, 0.6])
    nf = p.nofriction()
    np.testing.assert_allclose(nf.friction(qd), -np.array([k.G**2 * k.B for k in p.links]) * qd, rtol=1e-12)
    assert np.all(nf.nofriction(viscous=True).friction(qd) == 0.0)
