"""Zero-crossing events of ejsrl.sim.ode against closed-form event times."""

from __future__ import annotations

import math
import re
import time

import numpy as np
import pytest

from ejsrl.sim.ode import EventDef, OdeIntegrator, ZenoError

G = 9.81


def falling(t: float, y: np.ndarray) -> np.ndarray:
    """Ball (height, velocity) under gravity."""
    return np.array([y[1], -G])


def floor(e: float, **kw) -> EventDef:
    """The ball reaches the floor going down; it bounces back with restitution e."""
    return EventDef("floor", lambda t, y: y[0], -1, lambda t, y: np.array([y[0], -e * y[1]]), **kw)


def impact_times(e: float, height: float, n: int) -> list[float]:
    """Closed form: t_1 = sqrt(2h/g), then flights of 2 e^k v_1 / g."""
    v1 = math.sqrt(2 * G * height)
    times = [v1 / G]
    for k in range(1, n):
        times.append(times[-1] + 2 * v1 * e**k / G)
    return times


def simulate(integ: OdeIntegrator, y0, h: float, t_end: float):
    t, y = 0.0, np.asarray(y0, dtype=float)
    fired: list[tuple[str, float]] = []
    while t < t_end - 1e-9:
        r = integ.step(t, y, h)
        t, y = r.t, r.y
        fired += r.fired
    return t, y, fired


@pytest.mark.parametrize(
    ("method", "h", "tolerance"), [("rk4", 0.01, 1e-6), ("dopri5", 0.01, 1e-9), ("radau", 0.01, 1e-10)]
)
def test_bouncing_ball_impacts_match_the_closed_form(method, h, tolerance):
    integ = OdeIntegrator(falling, method, tolerance=tolerance, events=[floor(0.9)])
    t, y, fired = simulate(integ, [1.0, 0.0], h, 7.6)
    exact = impact_times(0.9, 1.0, len(fired))
    assert len(fired) >= 20
    assert [name for name, _ in fired] == ["floor"] * len(fired)
    assert max(abs(ft - et) for (_, ft), et in zip(fired, exact)) < 1e-6
    assert all(isinstance(ft, float) for _, ft in fired)
    # the ball never went through the floor
    assert y[0] > -1e-9


def test_action_gets_the_state_just_before_the_crossing():
    seen = []

    def action(t, y):
        seen.append((t, y.copy()))
        return None

    ev = EventDef("line", lambda t, y: y[0] - 0.3, +1, action)
    r = OdeIntegrator(lambda t, y: np.array([1.0]), "rk4", events=[ev]).step(0.0, np.array([0.0]), 1.0)
    (t_star, y_star), = seen
    assert abs(t_star - 0.3) <= 1e-12 * 1.3
    assert y_star[0] <= 0.3  # g is still on its "before" side
    assert r.fired == [("line", t_star)]
    assert r.t == 1.0 and r.y[0] == pytest.approx(1.0)


@pytest.mark.parametrize("method", ["rk4", "dop853", "bdf"])
def test_direction_filters_crossings(method):
    """x = sin t: up crossings at 2k pi, down at (2k+1) pi; the start at x = 0 is no crossing."""

    def osc(t, y):
        return np.array([y[1], -y[0]])

    def events(direction):
        return [EventDef("zero", lambda t, y: y[0], direction, lambda t, y: None)]

    times = {}
    for direction in (+1, -1, 0):
        integ = OdeIntegrator(osc, method, tolerance=1e-10, events=events(direction))
        times[direction] = [ft for _, ft in simulate(integ, [0.0, 1.0], 0.05, 13.0)[2]]
    np.testing.assert_allclose(times[+1], [2 * math.pi, 4 * math.pi], atol=1e-6)
    np.testing.assert_allclose(times[-1], [math.pi, 3 * math.pi], atol=1e-6)
    np.testing.assert_allclose(times[0], [math.pi, 2 * math.pi, 3 * math.pi, 4 * math.pi], atol=1e-6)


@pytest.mark.parametrize("method", ["rk4", "dopri5", "radau"])
def test_two_events_in_one_step_fire_in_time_order(method):
    moving = lambda t, y: np.array([1.0])  # noqa: E731
    late = EventDef("late", lambda t, y: y[0] - 0.7, +1, lambda t, y: None)
    early = EventDef("early", lambda t, y: y[0] - 0.3, +1, lambda t, y: None)
    r = OdeIntegrator(moving, method, events=[late, early]).step(0.0, np.array([0.0]), 1.0)
    assert [name for name, _ in r.fired] == ["early", "late"]
    np.testing.assert_allclose([ft for _, ft in r.fired], [0.3, 0.7], atol=1e-9)


@pytest.mark.parametrize("method", ["rk4", "dopri5", "bdf"])
def test_stop_returns_at_the_event_and_the_next_step_goes_on(method):
    moving = lambda t, y: np.array([1.0])  # noqa: E731
    pause = EventDef("pause", lambda t, y: y[0] - 0.3, +1, lambda t, y: None, stop=True)
    integ = OdeIntegrator(moving, method, events=[pause])
    r = integ.step(0.0, np.array([0.0]), 1.0)
    assert r.stop
    assert r.t == pytest.approx(0.3, abs=1e-9) and r.y[0] == pytest.approx(0.3, abs=1e-9)
    assert r.fired == [("pause", r.t)]
    # resuming from the returned state does not stop at the same crossing again
    r2 = integ.step(r.t, r.y, 0.5)
    assert not r2.stop and r2.fired == []
    assert r2.t == r.t + 0.5


@pytest.mark.parametrize("method", ["rk4", "dopri5", "radau"])
def test_an_action_that_does_not_turn_the_motion_back_fires_once(method):
    """Counting or braking at a line: one firing per crossing, not one per tolerance."""
    counted = []
    brake = EventDef("brake", lambda t, y: y[0] - 0.5, +1, lambda t, y: np.array([y[0], 0.5 * y[1]]))
    count = EventDef("count", lambda t, y: y[0] - 1.0, 0, lambda t, y: counted.append(t))
    integ = OdeIntegrator(lambda t, y: np.array([y[1], 0.0]), method, events=[brake, count])
    t, y, fired = simulate(integ, [0.0, 1.0], 0.1, 2.0)
    assert [name for name, _ in fired] == ["brake", "count"]
    assert y[0] == pytest.approx(0.5 + 0.5 * 1.5, abs=1e-9)
    assert counted == [pytest.approx(1.5, abs=1e-9)]


@pytest.mark.parametrize("method", ["rk4", "dopri5", "radau"])
def test_restitution_zero_is_reported_as_zeno_promptly(method):
    integ = OdeIntegrator(falling, method, events=[floor(0.0)])
    start = time.perf_counter()
    with pytest.raises(ZenoError, match=r"event 'floor' fired .* t=0\.4515.*Zeno"):
        simulate(integ, [1.0, 0.0], 0.01, 2.0)
    assert time.perf_counter() - start < 1.0


def test_accumulating_bounces_stop_with_zeno_after_more_than_100_in_a_step():
    integ = OdeIntegrator(falling, "rk4", events=[floor(0.9)])
    t_inf = impact_times(0.9, 1.0, 1)[0] + 2 * math.sqrt(2 * G) * 0.9 / (G * 0.1)  # accumulation point
    with pytest.raises(ZenoError, match="more than 100 times") as info:
        simulate(integ, [1.0, 0.0], 0.01, 20.0)
    reported = float(re.search(r"t=([0-9.]+)", str(info.value)).group(1))
    assert reported == pytest.approx(t_inf, abs=0.01)


@pytest.mark.parametrize("method", ["dopri5", "bogacki_shampine", "radau", "bdf"])
def test_a_state_changing_action_restarts_the_solver(method):
    """Integrating through a kick equals integrating the two pieces with fresh solvers."""
    osc = lambda t, y: np.array([y[1], -4.0 * y[0]])  # noqa: E731
    kick = lambda t, y: np.array([y[0], y[1] + 3.0])  # noqa: E731
    tol = 1e-4  # loose: a solver that kept its memory across the kick would differ visibly
    whole = OdeIntegrator(osc, method, tolerance=tol, events=[EventDef("kick", lambda t, y: y[0], -1, kick)])
    r = whole.step(0.0, np.array([1.0, 0.0]), 2.0)
    first = OdeIntegrator(
        osc, method, tolerance=tol, events=[EventDef("kick", lambda t, y: y[0], -1, kick, stop=True)]
    ).step(0.0, np.array([1.0, 0.0]), 2.0)
    assert first.stop and r.fired == first.fired
    second = OdeIntegrator(osc, method, tolerance=tol).step(first.t, first.y, 2.0 - first.t)
    np.testing.assert_allclose(r.y, second.y, rtol=0, atol=1e-9)
    # and the kick really happened at x = 0 going down (t = pi/4)
    assert first.t == pytest.approx(math.pi / 4, abs=1e-3)


def test_several_events_share_one_step_with_a_bounce():
    """A bounce inside a step is followed by a later crossing of another event in the same step."""
    high = EventDef("high", lambda t, y: y[0] - 0.12, +1, lambda t, y: None)
    integ = OdeIntegrator(falling, "rk4", events=[floor(1.0), high])
    r = integ.step(0.0, np.array([0.1, -1.0]), 0.2)
    names = [n for n, _ in r.fired]
    assert names == ["floor", "high"]
    # closed form: floor when 0.1 - t - g t^2/2 = 0, then up with speed v1
    t1 = (-1.0 + math.sqrt(1.0 + 2 * G * 0.1)) / G
    v1 = 1.0 + G * t1
    t2 = t1 + (v1 - math.sqrt(v1**2 - 2 * G * 0.12)) / G
    np.testing.assert_allclose([ft for _, ft in r.fired], [t1, t2], atol=1e-6)


def counting(name: str, direction: int, g, counts: dict[str, list[float]], then=None) -> EventDef:
    """An event on ``g`` that records its firing times (and then runs ``then``, if given)."""

    def action(t, y):
        counts.setdefault(name, []).append(t)
        return None if then is None else then(t, y)

    return EventDef(name, g, direction, action)


@pytest.mark.parametrize("method", ["rk4", "dopri5", "radau"])
@pytest.mark.parametrize("bounce_first", [True, False])
def test_events_on_the_same_crossing_each_fire_once_per_crossing(method, bounce_first):
    """down (the bounce) + both + up on the ball's height: down and both fire at every impact,
    in either order in the list; up never does, since the ball never goes below the floor."""
    times: dict[str, list[float]] = {}
    height = lambda t, y: y[0]  # noqa: E731
    bounce = counting("down", -1, height, times, then=lambda t, y: np.array([y[0], -0.9 * y[1]]))
    others = [counting("both", 0, height, times), counting("up", +1, height, times)]
    events = [bounce, *others] if bounce_first else [*others, bounce]
    integ = OdeIntegrator(falling, method, tolerance=1e-10, events=events)
    t, y, fired = simulate(integ, [1.0, 0.0], 0.01, 5.0)
    exact = [te for te in impact_times(0.9, 1.0, 40) if te < t]
    assert len(exact) == 8
    np.testing.assert_allclose(times["down"], exact, atol=1e-6)
    assert times["both"] == times["down"]  # the same instant, once each
    assert "up" not in times
    order = ["down", "both"] if bounce_first else ["both", "down"]
    assert [name for name, _ in fired] == order * len(exact)


@pytest.mark.parametrize("method", ["rk4", "dop853", "bdf"])
def test_counting_events_up_down_and_both_on_one_expression_match_sin_zeros(method):
    """x = sin t, three counters on x: down at odd multiples of pi, up at even ones, both at all."""
    times: dict[str, list[float]] = {}
    x = lambda t, y: y[0]  # noqa: E731
    events = [counting("down", -1, x, times), counting("both", 0, x, times), counting("up", +1, x, times)]
    integ = OdeIntegrator(lambda t, y: np.array([y[1], -y[0]]), method, tolerance=1e-10, events=events)
    simulate(integ, [0.0, 1.0], 0.05, 13.0)
    np.testing.assert_allclose(times["down"], [math.pi, 3 * math.pi], atol=1e-6)
    np.testing.assert_allclose(times["up"], [2 * math.pi, 4 * math.pi], atol=1e-6)
    np.testing.assert_allclose(times["both"], [k * math.pi for k in (1, 2, 3, 4)], atol=1e-6)
