"""``SE3``/``SO3`` value classes against spatialmath (recorded in fixtures/se3_spatialmath.json
by fixtures/make_se3_spatialmath.py) and hand-worked cases."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ejsrl.robotics import SE3, SO3, models
from testkit.robotics import FIXTURES

REF = json.loads((FIXTURES / "se3_spatialmath.json").read_text())
PTS = np.array([[1.0, 0.0, -2.0], [2.0, 1.0, 0.5], [3.0, -1.0, 0.0]])


def _a() -> SE3:
    return SE3(0.5, -0.2, 0.3) * SE3.RPY(10, 20, 30, unit="deg")


def _b() -> SE3:
    return SE3.Rx(0.3) * SE3(1, 2, 3) * SE3.Eul(0.4, -0.5, 0.6)


def _r() -> SO3:
    return SO3.Rz(30, unit="deg") * SO3.Ry(-0.7) * SO3.AngVec(0.9, [1, 2, 3])


def test_se3_matches_spatialmath() -> None:
    a, b, r = _a(), _b(), _r()
    close = lambda got, key: np.testing.assert_allclose(np.asarray(got), REF[key], atol=1e-12, err_msg=key)  # noqa: E731
    close(a, "a")
    close(b.A, "b")
    close(r.R, "r")
    close(a * b, "ab")
    close(a.inv(), "a_inv")
    close(a / b, "a_div_b")
    close(a.rpy(unit="deg"), "a_rpy_deg")
    close(b.eul(unit="deg"), "b_eul_deg")
    close(r.rpy(), "r_rpy")
    close(r.eul(unit="deg"), "r_eul_deg")
    close(a.interp(b, 0.3), "interp_ab_03")
    close([x.A for x in a.interp(b, [0.0, 0.25, 1.0])], "interp_ab_list")
    close(SO3().interp(r, 0.7), "r_interp_07")
    close(a * PTS, "a_pts")
    close(a * PTS[:, 0], "a_pt")
    close(r * PTS, "r_pts")
    assert a.strline() == REF["a_printline"]


def test_se3_by_hand_and_printing(capsys) -> None:
    T = SE3(1, 2, 3) * SE3.Rz(90, unit="deg")
    np.testing.assert_allclose(T * [1.0, 0.0, 0.0], [1.0, 3.0, 3.0], atol=1e-15)  # x turns into y, then moves
    np.testing.assert_allclose((T.inv() * T).A, np.eye(4), atol=1e-15)
    assert T.x == 1.0 and T.y == 2.0 and T.z == 3.0
    np.testing.assert_allclose(T.t, [1, 2, 3])
    assert T == SE3.Rt(SO3.Rz(np.pi / 2), [1, 2, 3])
    assert T != SE3(1, 2, 3)
    np.testing.assert_allclose((SE3.Tx(1) ** 3).t, [3, 0, 0])
    print(SE3.Tx(0.5))
    T.printline()
    out = capsys.readouterr().out.splitlines()
    assert out[:4] == ["    1    0    0  0.5", "    0    1    0    0", "    0    0    1    0", "    0    0    0    1"]
    assert out[4] == "t = 1, 2, 3; rpy/zyx = 0°, 0°, 90°"
    assert repr(SO3()).startswith("SO3(np.array([[1.")


def test_se3_works_where_arrays_do_and_refuses_non_poses() -> None:
    robot = models.puma560()
    q = np.array([0.1, 0.5, -0.3, 0.2, 0.4, -0.1])
    T = SE3(robot.fkine(q))
    np.testing.assert_allclose(np.asarray(SE3.Tz(0.1) * robot.fkine(q)), SE3.Tz(0.1).A @ robot.fkine(q), atol=1e-15)
    sol = robot.ikine(T, q0=q + 0.05)  # a value goes where a (4, 4) array does
    assert sol.success
    np.testing.assert_allclose(robot.fkine(sol.q), T.A, atol=1e-9)
    with pytest.raises(ValueError, match="not a rigid transform"):
        SE3(np.diag([2.0, 1, 1, 1]))
    with pytest.raises(ValueError, match="not a rotation"):
        SO3(np.diag([1.0, 1, -1]))
    with pytest.raises(AttributeError, match="immutable"):
        T.t = [0, 0, 0]  # type: ignore[misc]
    with pytest.raises(ValueError, match="unit must be 'rad' or 'deg'"):
        SO3.Rx(1.0, unit="degrees")
    with pytest.raises(TypeError):
        _ = SE3() * SO3()
