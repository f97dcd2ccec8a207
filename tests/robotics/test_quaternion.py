"""``UnitQuaternion`` against spatialmath's (recorded by
fixtures/make_quaternion_spatialmath.py): construction from roll-pitch-yaw, products,
rotating a vector, the inverse, SLERP, back to RPY and angle-axis; q and -q are equal."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from ejsrl.robotics import SE3, UnitQuaternion

from testkit.robotics import FIXTURES

REF = json.loads((FIXTURES / "quaternion_spatialmath.json").read_text())


def same_rotation(q: np.ndarray, ref: list[float]) -> bool:
    return abs(abs(float(np.dot(q, ref))) - 1.0) < 1e-12


@pytest.mark.parametrize("row", REF["rows"], ids=lambda r: f"{r['a']}*{r['b']}")
def test_unit_quaternion_equals_spatialmath(row) -> None:  # type: ignore[no-untyped-def]
    qa, qb = UnitQuaternion.RPY(row["a"]), UnitQuaternion.RPY(row["b"])
    assert same_rotation(qa.vec, row["qa"])
    np.testing.assert_allclose(qa.R, row["Ra"], atol=1e-12)
    assert same_rotation((qa * qb).vec, row["ab"])
    np.testing.assert_allclose(qa * np.array(REF["vec"]), row["rot"], atol=1e-12)
    assert same_rotation(qa.inv().vec, row["inv"])
    assert same_rotation(qa.interp(qb, 0.3).vec, row["interp"])
    np.testing.assert_allclose(UnitQuaternion.RPY(qa.rpy()).R, qa.R, atol=1e-12)  # the same rotation
    th, ax = qa.angvec()
    # spatialmath loses digits near pi (3.1416034 for a yaw of 3.14159); ours is exact there
    assert th == pytest.approx(row["angvec"][0], abs=2e-5)
    if row["a"][:2] == [0.0, 0.0]:
        assert th == pytest.approx(row["a"][2], abs=1e-12)
    np.testing.assert_allclose(UnitQuaternion.AngVec(th, ax).R, qa.R, atol=1e-12)


def test_unit_quaternion_algebra() -> None:
    q = UnitQuaternion.Rz(0.7) * UnitQuaternion.Rx(-0.3)
    assert q == UnitQuaternion(-q.vec)  # q and -q: one rotation
    assert UnitQuaternion(-q.vec).s >= 0
    assert (q * q.inv()) == UnitQuaternion()
    np.testing.assert_allclose(UnitQuaternion(q.R).R, q.R, atol=1e-15)
    np.testing.assert_allclose(q.SE3().A[:3, :3], q.R, atol=1e-15)
    assert isinstance(q.SE3(), SE3)
    assert q.angdist(q * UnitQuaternion.Ry(0.25)) == pytest.approx(0.25, abs=1e-12)
    np.testing.assert_allclose((q**3).R, q.R @ q.R @ q.R, atol=1e-14)
    assert UnitQuaternion.EulerVec([0, 0, math.pi / 2]) == UnitQuaternion.Rz(90, unit="deg")
    with pytest.raises(ValueError, match="not a rotation"):
        UnitQuaternion(np.diag([1.0, 1.0, -1.0]))
