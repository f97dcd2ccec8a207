"""ODE methods of ejsrl.sim.ode against exact solutions and an independent library (LSODA)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ejsrl.sim._explicit import AdaptiveRK, make_fixed_step, rk_trial
from ejsrl.sim._tableaus import TABLEAUS
from ejsrl.sim.ode import ADAPTIVE, FIXED_STEP, IMPLICIT, METHODS, OdeIntegrator


def forced_decay(t: float, y: np.ndarray) -> np.ndarray:
    """y' = -y + sin t."""
    return -y + math.sin(t)


def forced_decay_exact(t: float) -> float:
    """Solution of y' = -y + sin t with y(0) = 1."""
    return 1.5 * math.exp(-t) + 0.5 * (math.sin(t) - math.cos(t))


def oscillator(t: float, y: np.ndarray) -> np.ndarray:
    """x'' = -x as (x, v)."""
    return np.array([y[1], -y[0]])


class Counter:
    """Wraps rates and counts their evaluations."""

    def __init__(self, f):
        self.f = f
        self.n = 0
        self.times: list[float] = []

    def __call__(self, t, y):
        self.n += 1
        self.times.append(t)
        return self.f(t, y)


def run(integ: OdeIntegrator, y0: np.ndarray, h: float, t_end: float) -> tuple[float, np.ndarray]:
    t, y = 0.0, y0
    for _ in range(int(round(t_end / h))):
        r = integ.step(t, y, h)
        t, y = r.t, r.y
    return t, y


def test_method_lists_are_consistent():
    assert set(METHODS) == FIXED_STEP | ADAPTIVE | IMPLICIT
    assert len(METHODS) == 10
    assert set(TABLEAUS) == FIXED_STEP | ADAPTIVE


@pytest.mark.parametrize(("method", "order"), [("euler", 1), ("euler_richardson", 2), ("rk4", 4)])
def test_fixed_step_methods_converge_at_their_order(method, order):
    errors = []
    for h in (0.1, 0.05, 0.025):
        t, y = run(OdeIntegrator(forced_decay, method), np.array([1.0]), h, 3.0)
        assert t == pytest.approx(3.0, abs=1e-12)
        errors.append(abs(y[0] - forced_decay_exact(t)))
    observed = [math.log2(errors[i] / errors[i + 1]) for i in range(2)]
    assert observed == pytest.approx([order, order], abs=0.15)


@pytest.mark.parametrize(
    ("method", "order", "h"),
    [("bogacki_shampine", 3, 0.1), ("cash_karp", 5, 0.2), ("fehlberg", 4, 0.2), ("dopri5", 5, 0.2), ("dop853", 8, 0.5)],
)
def test_adaptive_pairs_propagate_a_formula_of_their_order(method, order, h):
    step = make_fixed_step(TABLEAUS[method])
    errors = []
    for hh in (h, h / 2):
        t, y = 0.0, np.array([1.0, 0.0])
        for _ in range(int(round(8.0 / hh))):
            y = step(oscillator, t, y, hh, None)
            t += hh
        errors.append(abs(y[0] - math.cos(t)) + abs(y[1] + math.sin(t)))
    assert math.log2(errors[0] / errors[1]) == pytest.approx(order, abs=0.3)


@pytest.mark.parametrize(("method", "est_order"), [("bogacki_shampine", 2), ("cash_karp", 4), ("fehlberg", 4), ("dopri5", 4)])
def test_embedded_error_estimate_matches_the_true_local_error_of_the_lower_formula(method, est_order):
    """The estimate shrinks like h^(q+1) and has the size of the embedded formula's error."""
    tab = TABLEAUS[method]
    y0 = np.array([1.0, 0.0])
    estimates = []
    for h in (0.2, 0.1):
        _, K = rk_trial(oscillator, tab, 0.0, y0, h, oscillator(0.0, y0))
        err = h * (tab.e @ K)
        estimates.append(float(np.linalg.norm(err)))
        if method != "fehlberg":  # these propagate the higher order: the estimate ~ error of the lower one
            y_low_err = float(np.linalg.norm(err))
            exact = np.array([math.cos(h), -math.sin(h)])
            y_high, _ = rk_trial(oscillator, tab, 0.0, y0, h, oscillator(0.0, y0))
            lower = y_high - err
            assert float(np.linalg.norm(lower - exact)) == pytest.approx(y_low_err, rel=0.1)
    assert math.log2(estimates[0] / estimates[1]) == pytest.approx(est_order + 1, abs=0.25)


@pytest.mark.parametrize("method", sorted(ADAPTIVE))
def test_adaptive_local_error_of_every_step_is_within_tolerance(method):
    """Start every internal step on the exact solution: the true local error of an
    accepted step, in the controller's norm, is at most about 1."""
    tol = 1e-6
    rk = AdaptiveRK(oscillator, TABLEAUS[method], atol=tol, rtol=tol, max_step=math.inf)
    t, worst, steps = 0.0, 0.0, 0
    while t < 10.0:
        y = np.array([math.cos(t), -math.sin(t)])
        t1, y1, _ = rk.advance(t, y, oscillator(t, y), 10.0)
        exact = np.array([math.cos(t1), -math.sin(t1)])
        scale = tol + tol * np.maximum(np.abs(y), np.abs(exact))
        worst = max(worst, float(np.sqrt(np.mean(((y1 - exact) / scale) ** 2))))
        t, steps = t1, steps + 1
    assert steps > 5
    assert worst < 1.5


# Global error after 8 periods: per-step control lets local errors accumulate, so the
# bound is a multiple of the tolerance that depends on the pair (about the number of
# steps times the local error of the propagated formula).
GLOBAL_BOUND = {"bogacki_shampine": 300, "cash_karp": 100, "fehlberg": 2000, "dopri5": 50, "dop853": 20}
SCIPY_TWIN = {"bogacki_shampine": "RK23", "dopri5": "RK45", "dop853": "DOP853"}


@pytest.mark.parametrize("method", sorted(ADAPTIVE))
def test_adaptive_methods_honour_tolerance_and_loosen_with_it(method):
    calls = {}
    for tol in (1e-5, 1e-9):
        t, y = run(OdeIntegrator(oscillator, method, tolerance=tol), np.array([1.0, 0.0]), 0.5, 50.0)
        error = max(abs(y[0] - math.cos(t)), abs(y[1] + math.sin(t)))
        assert error < GLOBAL_BOUND[method] * tol, (tol, error)
        f = Counter(oscillator)
        one = OdeIntegrator(f, method, tolerance=tol).step(0.0, np.array([1.0, 0.0]), 50.0).y
        if method in SCIPY_TWIN:  # same pair in an established library: same accuracy
            ref = solve_ivp(oscillator, (0.0, 50.0), [1.0, 0.0], method=SCIPY_TWIN[method], rtol=tol, atol=tol)
            ref_error = max(abs(ref.y[0, -1] - math.cos(50.0)), abs(ref.y[1, -1] + math.sin(50.0)))
            one_error = max(abs(one[0] - math.cos(50.0)), abs(one[1] + math.sin(50.0)))
            assert ref_error / 2 < one_error < 2 * ref_error
        calls[tol] = f.n
    assert calls[1e-5] < calls[1e-9] / 2


@pytest.mark.parametrize("method", sorted(ADAPTIVE | IMPLICIT))
def test_steps_land_exactly_on_t_plus_h(method):
    integ = OdeIntegrator(forced_decay, method)
    t, y = 0.3, np.array([0.7])
    for h in (0.1, 0.37, 1e-3, 2.5):
        r = integ.step(t, y, h)
        assert r.t == t + h
        t, y = r.t, r.y


def test_adaptive_step_size_is_remembered_between_small_display_steps():
    f = Counter(oscillator)
    integ = OdeIntegrator(f, "dopri5", tolerance=1e-8)
    run(integ, np.array([1.0, 0.0]), 0.001, 1.0)
    # one clipped internal step per call: 6 new stages (FSAL); re-choosing the initial
    # step every call would cost 2 more evaluations each time
    assert f.n <= 6 * 1000 + 10


def test_max_step_is_honoured():
    f = Counter(lambda t, y: np.zeros(1))  # error-free: the controller alone would take one step
    integ = OdeIntegrator(f, "dopri5", max_step=0.01)
    integ.step(0.0, np.array([1.0]), 1.0)
    times = np.unique(f.times)
    assert np.diff(times).max() <= 0.01 + 1e-12
    unlimited = Counter(lambda t, y: np.zeros(1))
    OdeIntegrator(unlimited, "dopri5").step(0.0, np.array([1.0]), 1.0)
    assert np.diff(np.unique(unlimited.times)).max() > 0.1


def van_der_pol(mu: float):
    def f(t, y):
        return np.array([y[1], mu * (1.0 - y[0] ** 2) * y[1] - y[0]])

    return f


@pytest.mark.parametrize("method", ["radau", "bdf"])
def test_implicit_methods_solve_stiff_van_der_pol(method):
    ref = solve_ivp(van_der_pol(1000.0), (0.0, 3000.0), [2.0, 0.0], method="LSODA", rtol=1e-10, atol=1e-10)
    f = Counter(van_der_pol(1000.0))
    integ = OdeIntegrator(f, method, tolerance=1e-6)
    t, y = run(integ, np.array([2.0, 0.0]), 10.0, 3000.0)
    assert t == pytest.approx(3000.0)
    assert y[0] == pytest.approx(ref.y[0, -1], abs=2e-3)
    assert f.n < 20_000
    # an explicit method is limited by stability, not accuracy: count dopri5 on [0, 5]
    g = Counter(van_der_pol(1000.0))
    OdeIntegrator(g, "dopri5", tolerance=1e-6).step(0.0, np.array([2.0, 0.0]), 5.0)
    explicit_estimate = g.n * 3000.0 / 5.0
    assert explicit_estimate > 1e6
    assert explicit_estimate > 200 * f.n


@pytest.mark.parametrize("method", ["radau", "bdf"])
def test_implicit_solver_is_kept_between_calls(method):
    """Many short display steps cost the same rate evaluations as one long step."""
    long = Counter(van_der_pol(1000.0))
    OdeIntegrator(long, method).step(0.0, np.array([2.0, 0.0]), 1000.0)
    short = Counter(van_der_pol(1000.0))
    run(OdeIntegrator(short, method), np.array([2.0, 0.0]), 1.0, 1000.0)
    assert short.n <= 1.1 * long.n + 20


@pytest.mark.parametrize("method", sorted(ADAPTIVE | IMPLICIT))
def test_a_changed_state_restarts_from_the_given_state(method):
    integ = OdeIntegrator(oscillator, method, tolerance=1e-8)
    r = integ.step(0.0, np.array([1.0, 0.0]), 0.5)
    other = np.array([0.0, 2.0])  # the user edited the state: (t, y) differ from what step returned
    r2 = integ.step(r.t, other, 0.5)
    fresh = OdeIntegrator(oscillator, method, tolerance=1e-8).step(r.t, other, 0.5)
    exact = [2 * math.sin(0.5), 2 * math.cos(0.5)]
    np.testing.assert_allclose(r2.y, exact, atol=1e-6)
    if method in IMPLICIT:  # a new solver object: the same as starting afresh
        np.testing.assert_allclose(r2.y, fresh.y, rtol=0, atol=1e-12)
    else:  # explicit pairs keep only their step size, which the controller re-adapts
        np.testing.assert_allclose(r2.y, fresh.y, rtol=0, atol=1e-7)


def test_reset_forgets_the_step_size():
    integ = OdeIntegrator(oscillator, "dopri5")
    integ.step(0.0, np.array([1.0, 0.0]), 1.0)
    assert integ._rk.h is not None
    integ.reset()
    assert integ._rk.h is None


@pytest.mark.parametrize("method", METHODS)
def test_inputs_are_not_written_and_outputs_are_not_reused(method):
    y0 = np.array([1.0, 0.0])
    y0.flags.writeable = False
    integ = OdeIntegrator(oscillator, method)
    r1 = integ.step(0.0, y0, 0.1)
    kept = r1.y.copy()
    r2 = integ.step(r1.t, r1.y, 0.1)
    integ.step(r2.t, r2.y, 0.1)
    np.testing.assert_array_equal(r1.y, kept)
    assert r1.y is not y0 and r2.y is not r1.y
    assert r1.y.dtype == np.float64 and r1.y.shape == (2,)


@pytest.mark.parametrize("method", METHODS)
def test_exceptions_of_the_rates_propagate_unchanged(method):
    boom = ZeroDivisionError("division by zero in rate of x")

    def rates(t, y):
        if t > 0.05:
            raise boom
        return -y

    with pytest.raises(ZeroDivisionError) as info:
        run(OdeIntegrator(rates, method), np.array([1.0]), 0.1, 1.0)
    assert info.value is boom


def test_unknown_method_suggests_the_closest():
    with pytest.raises(ValueError, match="did you mean 'dopri5'"):
        OdeIntegrator(oscillator, "dopri45")


def test_a_stiff_problem_in_an_explicit_method_reports_instead_of_hanging():
    integ = OdeIntegrator(lambda t, y: np.array([math.nan]) if t > 0.5 else -y, "dopri5")
    with pytest.raises(RuntimeError, match="step size became too small"):
        integ.step(0.0, np.array([1.0]), 1.0)


def test_adaptive_rk_rejects_a_tableau_without_error_estimate():
    with pytest.raises(ValueError):
        AdaptiveRK(oscillator, TABLEAUS["rk4"], atol=1e-6, rtol=1e-6, max_step=math.inf)
