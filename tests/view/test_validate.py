"""Values from the browser are checked, clamped or refused before they reach the model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ejsrl.view._validate import MAX_TEXT_LENGTH, validate_control
from ejsrl.view.elements import Checkbox, Dropdown, Number, Slider, Text


def _get(m):
    return 0


def _set(m, v):
    raise AssertionError("validation must never write the model")


def slider(**kw):
    return Slider("L", _get, _set, label="Length", **kw)


def test_slider_clamps_to_its_range():
    s = slider(min=0.1, max=2.0, step=0.1)
    assert validate_control(s, 5.0).value == 2.0
    assert validate_control(s, -3.0).value == pytest.approx(0.1)
    assert "clamped" in validate_control(s, 5.0).message


def test_slider_quantises_to_its_step_without_float_noise():
    s = slider(min=0.0, max=1.0, step=0.1)
    assert validate_control(s, 0.3000001).value == 0.3
    assert validate_control(s, 0.26).value == 0.3


@pytest.mark.parametrize("raw", [math.nan, math.inf, -math.inf, "nan", "inf", None, [1.0], {"a": 1}, True])
def test_non_finite_or_non_numbers_are_refused(raw):
    out = validate_control(slider(min=0.0, max=1.0), raw)
    assert not out.ok and out.value is None
    assert "Length" in out.message and "not applied" in out.message


def test_code_sent_as_a_number_is_refused_not_evaluated():
    out = validate_control(Number("n", _get, _set, vtype="int"), "__import__('os').system('true')")
    assert not out.ok


def test_numeric_strings_are_parsed_as_numerals_only():
    assert validate_control(Number("x", _get, _set), " 2.5 ").value == 2.5
    assert not validate_control(Number("x", _get, _set), "2+3").ok


def test_int_variables_are_rounded_and_clamped():
    n = Number("n", _get, _set, vtype="int", min=0, max=10)
    assert validate_control(n, 3.7).value == 4 and isinstance(validate_control(n, 3.7).value, int)
    assert validate_control(n, 99).value == 10
    assert validate_control(n, np.float64(2.2)).value == 2


def test_number_without_bounds_keeps_any_finite_value():
    assert validate_control(Number("x", _get, _set), -1e300).value == -1e300


def test_checkbox_takes_only_booleans():
    c = Checkbox("on", _get, _set, vtype="bool")
    assert validate_control(c, True).value is True
    assert validate_control(c, np.bool_(False)).value is False
    for raw in ("false", 0, 1, None):
        assert not validate_control(c, raw).ok


def test_text_must_be_a_bounded_string():
    t = Text("name", _get, _set, vtype="str")
    assert validate_control(t, "hello").value == "hello"
    assert not validate_control(t, 12).ok
    assert validate_control(t, "x" * MAX_TEXT_LENGTH).ok
    too_long = validate_control(t, "x" * (MAX_TEXT_LENGTH + 1))
    assert not too_long.ok and "characters" in too_long.message


def test_dropdown_takes_only_its_options():
    d = Dropdown("mode", _get, _set, vtype="str", options=["slow", "fast"])
    assert validate_control(d, "fast").value == "fast"
    assert not validate_control(d, "warp").ok


def test_dropdown_maps_shown_text_back_to_numeric_options():
    d = Dropdown("k", _get, _set, vtype="int", options=[1, 2, 5])
    out = validate_control(d, "5")
    assert out.ok and out.value == 5 and isinstance(out.value, int)
    assert not validate_control(d, "3").ok


def test_a_text_field_bound_to_a_number_takes_numerals_only():
    t = Text("x", _get, _set, vtype="float")
    assert validate_control(t, "2.5").value == 2.5
    assert not validate_control(t, "two").ok


def test_a_refusal_names_a_control_whose_label_changes_by_its_variable():
    from ejsrl.view.elements import Dynamic

    s = Slider("q[2]", _get, _set, label=Dynamic(lambda m: "q3 = 0.5", "q3 = {q[2]}"), min=0.0, max=1.0)
    message = validate_control(s, "abc").message
    assert message.startswith("q[2]: ") and "Dynamic" not in message
    assert validate_control(slider(), "abc").message.startswith("Length: ")


def test_a_slider_takes_no_text_and_clamps_the_largest_floats():
    """Issue #30: "2.0" was cast by a slider, and 1e308 refused (its distance to min over the
    step overflowed) instead of clamped like 1e300."""
    s = slider(min=0.0, max=2.0, step=0.01)
    assert not validate_control(s, "2.0").ok
    for huge, end in ((1e308, 2.0), (-1.7976931348623157e308, 0.0), (1e300, 2.0)):
        out = validate_control(s, huge)
        assert out.ok and out.value == end and "clamped" in out.message
