"""OdePage.of packs the model's states once per layout and reuses the vector it loaded while
the model still holds it: changes made to the model between steps (in place, by a new value,
by a new shape) must still be what the next step integrates from."""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.sim import OdePage

H = 0.1
RK4_DECAY = 1 - H + H**2 / 2 - H**3 / 6 + H**4 / 24  # one RK4 step of y' = -y multiplies y by this


class Box:
    """A bare model: the page reads and writes plain attributes."""

    def __init__(self, **values: object) -> None:
        self.__dict__.update(values)


def decay_page(model: Box, names: list[str]) -> OdePage:
    return OdePage.of(model, "page", "t", names, lambda: [-np.asarray(getattr(model, n)) for n in names], method="rk4", step=H)


def test_an_in_place_change_of_an_array_state_between_steps_is_integrated_from() -> None:
    m = Box(t=0.0, x=np.array([1.0, 2.0, 3.0]), v=np.array([4.0, 5.0]))
    page = decay_page(m, ["x", "v"])
    page.run()
    m.x[1] = 10.0  # the model's array is a view of the page's last vector
    m.v *= 2.0
    page.run()
    np.testing.assert_allclose(m.x, [RK4_DECAY**2, 10.0 * RK4_DECAY, 3.0 * RK4_DECAY**2], rtol=1e-14)
    np.testing.assert_allclose(m.v, [8.0 * RK4_DECAY**2, 10.0 * RK4_DECAY**2], rtol=1e-14)
    assert m.t == pytest.approx(2 * H)


def test_a_new_value_or_a_new_shape_between_steps_is_integrated_from() -> None:
    m = Box(t=0.0, x=np.array([1.0, 2.0]), v=np.array([1.0]))
    page = decay_page(m, ["x", "v"])
    page.run()
    m.x = np.array([5.0, 6.0])  # same shape, new array
    page.run()
    np.testing.assert_allclose(m.x, [5.0 * RK4_DECAY, 6.0 * RK4_DECAY], rtol=1e-14)
    m.x = np.array([1.0, 2.0, 3.0, 4.0])  # new shape: a new layout
    page.run()
    np.testing.assert_allclose(m.x, np.arange(1.0, 5.0) * RK4_DECAY, rtol=1e-14)
    np.testing.assert_allclose(m.v, [RK4_DECAY**3], rtol=1e-14)


def test_numbers_and_arrays_of_any_shape_in_one_page() -> None:
    m = Box(t=0.0, a=2.0, grid=np.arange(6.0).reshape(2, 3), x=np.array([1.0]))
    page = decay_page(m, ["a", "grid", "x"])
    for _ in range(3):
        page.run()
    m.grid[0, 0] = 7.0
    m.a = 4.0
    page.run()
    assert isinstance(m.a, float) and m.a == pytest.approx(4.0 * RK4_DECAY, rel=1e-14)
    expected = np.arange(6.0).reshape(2, 3) * RK4_DECAY**4
    expected[0, 0] = 7.0 * RK4_DECAY
    assert m.grid.shape == (2, 3)
    np.testing.assert_allclose(m.grid, expected, rtol=1e-14)
    np.testing.assert_allclose(m.x, [RK4_DECAY**4], rtol=1e-14)


def test_the_packed_state_is_a_copy_the_caller_may_change() -> None:
    m = Box(t=0.0, x=np.array([1.0, 2.0]), v=np.array([3.0]))
    page = decay_page(m, ["x", "v"])
    page.run()
    t, y = page.state()
    y[:] = 0.0
    np.testing.assert_allclose(m.x, [RK4_DECAY, 2.0 * RK4_DECAY], rtol=1e-14)
    assert page.state()[1][2] == pytest.approx(3.0 * RK4_DECAY, rel=1e-14)


@pytest.mark.parametrize("names", [["x", "v"], ["x"], ["x", "v", "w"]])
def test_a_rate_of_the_wrong_shape_is_refused(names: list[str]) -> None:
    m = Box(t=0.0, x=np.ones(3), v=np.ones(2), w=np.ones(2))
    page = OdePage.of(m, "page", "t", names, lambda: [np.ones(4)] + [0.0] * (len(names) - 1), method="rk4", step=H)
    with pytest.raises(ValueError, match="broadcast"):
        page.run()


def test_a_number_rate_fills_an_array_state() -> None:
    m = Box(t=0.0, x=np.zeros(3), v=np.zeros(2))
    page = OdePage.of(m, "page", "t", ["x", "v"], lambda: [1.0, np.array([2.0, 3.0])], method="rk4", step=H)
    page.run()
    np.testing.assert_allclose(m.x, [H] * 3, rtol=1e-14)
    np.testing.assert_allclose(m.v, [2 * H, 3 * H], rtol=1e-14)
