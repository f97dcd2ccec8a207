"""Controllers against analytic results (pure pursuit's steady steering on a circle, the
pose a move-to-pose run reaches, the line a line follower converges to), ``SE2`` against
matrix algebra, and covariance ellipses against their quadratic form and scipy's chi-squared."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import chi2

from ejsrl import mobile as M


def test_pure_pursuit_on_a_circle_steers_atan_L_over_R() -> None:
    R, L = 5.0, 1.2
    t = np.linspace(0, 4 * math.pi, 2000)
    path = np.column_stack((R * np.cos(t), R * np.sin(t)))
    car = M.Bicycle(L=L, dt=0.01, x0=(R + 0.5, 0.0, math.pi / 2))  # off the path, heading along it
    steer = []
    for _ in range(3000):
        u = M.pure_pursuit(car.x, path, lookahead=1.0, v=1.0, L=L)
        car.step(u)
        steer.append(u[1])
    assert abs(math.hypot(car.x[0], car.x[1]) - R) < 5e-3  # back on the circle
    assert np.mean(steer[-500:]) == pytest.approx(math.atan(L / R), abs=2e-3)


@pytest.mark.parametrize("goal", [(5.0, 5.0, math.pi / 2), (-4.0, 3.0, 0.0), (6.0, -2.0, -2.5), (-6.0, -6.0, -1.0)])
def test_move_to_pose_reaches_the_pose(goal) -> None:  # type: ignore[no-untyped-def]
    car = M.Bicycle(L=1.0, steer_max=1.2, dt=0.01)
    for _ in range(3000):
        car.step(M.move_to_pose(car.x, goal, L=1.0))
    assert math.hypot(car.x[0] - goal[0], car.x[1] - goal[1]) < 1e-3
    assert abs(M.angdiff(car.x[2], goal[2])) < 1e-3


def test_move_to_point_and_follow_line_converge() -> None:
    car = M.Bicycle(L=1.0, dt=0.01)
    for _ in range(3000):
        car.step(M.move_to_point(car.x, (4.0, -3.0)))
    assert math.hypot(car.x[0] - 4.0, car.x[1] + 3.0) < 0.05
    line = (1.0, -2.0, 4.0)  # x - 2y + 4 = 0, direction atan2(-1, -2)... i.e. towards -x
    car = M.Bicycle(L=1.0, dt=0.01, x0=(0.0, -3.0, 0.0))
    for _ in range(4000):
        car.step(M.follow_line(car.x, line, v=1.0, Kd=0.5, Kh=1.0))
    d = (line[0] * car.x[0] + line[1] * car.x[1] + line[2]) / math.hypot(line[0], line[1])
    assert abs(d) < 1e-3
    assert abs(M.angdiff(car.x[2], math.atan2(-line[0], line[1]))) < 1e-3


def test_se2_is_matrix_algebra() -> None:
    a = M.SE2(1.0, 2.0, 0.3)
    b = M.SE2(-0.5, 0.7, -1.2)
    np.testing.assert_allclose((a * b).A, a.A @ b.A, atol=1e-15)
    np.testing.assert_allclose(a.inv().A, np.linalg.inv(a.A), atol=1e-15)
    np.testing.assert_allclose((a * a.inv()).A, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(a * np.array([1.0, 0.0]), [1 + math.cos(0.3), 2 + math.sin(0.3)], atol=1e-15)
    np.testing.assert_allclose((a * b).xyt(), [*(a * b.t), M.angdiff(0.3 - 1.2)], atol=1e-15)
    assert M.SE2(90, 0, 90, unit="deg").theta == pytest.approx(math.pi / 2)
    np.testing.assert_allclose(a.interp(b, 0.5).xyt(), [0.25, 1.35, -0.45], atol=1e-15)
    with pytest.raises(ValueError, match="rotation"):
        M.SE2(np.diag([2.0, 1.0, 1.0]))


def test_ellipse_points_lie_on_the_confidence_contour() -> None:
    P = np.array([[0.5, 0.2, 0.0], [0.2, 0.3, 0.0], [0.0, 0.0, 0.1]])
    c = np.array([2.0, -1.0])
    pts = M.ellipse_points(P, c, confidence=0.95, n=50)
    assert pts.shape == (51, 2) and np.array_equal(pts[0], pts[-1])
    d = pts - c
    q = np.einsum("ij,jk,ik->i", d, np.linalg.inv(P[:2, :2]), d)
    np.testing.assert_allclose(q, chi2.ppf(0.95, 2), rtol=1e-12)
    assert M.chi2_2dof(0.99) == pytest.approx(chi2.ppf(0.99, 2), rel=1e-12)
    # scale=1: the 1-sigma ellipse; a singular P degenerates to a segment
    seg = M.ellipse_points(np.diag([1.0, 0.0]), scale=2.0)
    assert np.abs(seg[:, 1]).max() == 0.0 and seg[:, 0].max() == pytest.approx(2.0)
