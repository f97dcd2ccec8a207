"""Each core example runs headless and its CSV obeys the physics it models.

References are independent of the app: closed forms (elliptic-integral period, impact
times, normal modes) or SciPy's solvers at tight tolerance.
"""

from __future__ import annotations

import io
from math import pi, sqrt

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk

from testkit import run_app


def csv_columns(text: str) -> dict[str, np.ndarray]:
    data = np.genfromtxt(io.StringIO(text), delimiter=",", names=True, deletechars="")
    return {name: np.atleast_1d(data[name]) for name in data.dtype.names}


def crossings(t: np.ndarray, x: np.ndarray, direction: int = 1) -> np.ndarray:
    """Times where x crosses zero (upwards for +1), by linear interpolation."""
    s = np.sign(x)
    idx = np.flatnonzero((s[:-1] < 0) & (s[1:] >= 0)) if direction > 0 else np.flatnonzero((s[:-1] > 0) & (s[1:] <= 0))
    return t[idx] - x[idx] * (t[idx + 1] - t[idx]) / (x[idx + 1] - x[idx])


def headless(app, *args: str) -> dict[str, np.ndarray]:
    r = run_app(app, "--headless", "--csv", "-", *args)
    assert r.returncode == 0, r.stderr
    return csv_columns(r.stdout)


def test_pendulum_period_matches_the_elliptic_integral(built) -> None:
    theta0, L, g = 0.8, 1.5, 9.81
    d = headless(built("pendulum"), "--duration", "12", "--set", "b=0", "--set", f"theta={theta0}", "--set", f"L={L}", "--vars", "t,theta,E")
    ups = crossings(d["t"], d["theta"])
    period = np.diff(ups).mean()
    exact = 4 * sqrt(L / g) * ellipk(np.sin(theta0 / 2) ** 2)
    assert period == pytest.approx(exact, rel=2e-5)
    # without damping the energy is conserved (RK4, dt = 0.01)
    assert np.ptp(d["E"]) / d["E"][0] < 1e-6
    assert d["theta"][0] == theta0  # first row: the state after init and the fixed relations


def test_pendulum_energy_decays_with_damping(built) -> None:
    b = 0.1
    d = headless(built("pendulum"), "--duration", "10", "--set", f"b={b}", "--set", "theta=0.2", "--vars", "t,E")
    # small oscillations: E(t) ~ E0 exp(-b t) on average over a period
    ratio = d["E"][-1] / d["E"][0]
    assert ratio == pytest.approx(np.exp(-b * 10), rel=0.1)
    peaks = d["E"][:: 100]
    assert np.all(np.diff(peaks) <= 1e-12)


def test_bouncing_ball_impacts_match_the_closed_form(built) -> None:
    h, g, e = 1.0, 9.81, 0.9
    d = headless(built("bouncing_ball"), "--duration", "8", "--vars", "t,y,bounces,last_impact")
    n = d["bounces"].astype(int)
    new = np.flatnonzero(np.diff(n) > 0) + 1
    impacts = d["last_impact"][new]
    v1 = sqrt(2 * g * h)
    expected = sqrt(2 * h / g) + np.concatenate(([0.0], np.cumsum([2 * v1 * e**k / g for k in range(1, len(impacts))])))
    assert len(impacts) >= 20
    assert np.max(np.abs(impacts - expected)) < 1e-6
    assert d["y"].min() > -1e-9  # never below the floor


def test_bouncing_ball_with_restitution_zero_stops_on_the_zeno_guard(built) -> None:
    r = run_app(built("bouncing_ball"), "--headless", "--duration", "5", "--set", "restitution=0", timeout=60)
    assert r.returncode == 1
    assert "bouncing_ball.ejs.yaml:" in r.stderr and "Zeno" in r.stderr
    assert "Traceback" not in r.stderr


def test_lorenz_matches_scipy_at_tight_tolerance(built) -> None:
    d = headless(built("lorenz"), "--duration", "2", "--vars", "t,x,y,z", "--every", "100")
    sigma, rho, beta = 10.0, 28.0, 8.0 / 3.0
    ref = solve_ivp(lambda t, s: [sigma * (s[1] - s[0]), s[0] * (rho - s[2]) - s[1], s[0] * s[1] - beta * s[2]],
                    (0, d["t"][-1]), [1.0, 1.0, 1.0], method="DOP853", rtol=1e-12, atol=1e-12, t_eval=d["t"])
    got = np.vstack([d["x"], d["y"], d["z"]])
    assert np.max(np.abs(got - ref.y)) < 1e-4


def test_van_der_pol_stiff_period_matches_scipy(built) -> None:
    d = headless(built("van_der_pol"), "--duration", "3500", "--vars", "t,x")
    ups = crossings(d["t"], d["x"], direction=-1)
    mu = 1000.0
    ref = solve_ivp(lambda t, s: [s[1], mu * (1 - s[0] ** 2) * s[1] - s[0]], (0, 3500), [2.0, 0.0], method="LSODA", rtol=1e-10, atol=1e-10, dense_output=True)
    ref_down = crossings(d["t"], ref.sol(d["t"])[0], direction=-1)  # same sampling, same interpolation
    assert len(ups) >= 2 and len(ref_down) == len(ups)
    assert np.max(np.abs(ups - ref_down)) < 0.05
    period = np.diff(ups).mean()
    assert period == pytest.approx((3 - 2 * np.log(2)) * mu, rel=0.01)  # the asymptotic relaxation period


@pytest.mark.parametrize("n", [30, 10])
def test_mass_spring_chain_first_mode_period(built, n: int) -> None:
    k, m = 100.0, 0.1
    d = headless(built("mass_spring_chain"), "--duration", "5", "--set", f"N={n}", "--vars", f"t,x,E")
    middle = d[f"x[{n // 2}]"]
    ups = crossings(d["t"], middle)
    omega1 = 2 * sqrt(k / m) * np.sin(pi / (2 * (n + 1)))
    assert np.diff(ups).mean() == pytest.approx(2 * pi / omega1, rel=1e-4)
    assert np.ptp(d["E"]) / d["E"][0] < 1e-6
    assert sum(1 for name in d if name.startswith("x[")) == n
