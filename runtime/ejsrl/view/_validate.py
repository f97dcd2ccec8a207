"""Validation of the values a browser sends for a control, before they reach the model.

A client may send anything: a string where a number belongs, ``NaN``, a value far outside
the control's range, a 1 MB text, an option that the dropdown never offered. Every value
goes through :func:`validate_control` first; it returns the value to apply (clamped,
rounded, quantised) or a refusal with a message for the user. Nothing the client sends is
ever evaluated as code.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ejsrl.view.elements import Checkbox, Control, Dropdown, Number, Slider, Text

__all__ = ["Checked", "validate_control", "MAX_TEXT_LENGTH", "option_label"]

#: the longest text a text field accepts
MAX_TEXT_LENGTH = 10_000


@dataclass(frozen=True)
class Checked:
    """The outcome of validating one value.

    ``ok``: the value may be applied; ``value``: what to apply (possibly clamped);
    ``message``: why the value was refused (``ok`` False) or how it was changed
    (clamped, rounded), else ``""``.
    """

    ok: bool
    value: Any = None
    message: str = ""


def _refuse(control: Control, why: str) -> Checked:
    name = control.title
    return Checked(False, None, f"{name}: {why}; the value was not applied.")


def option_label(option: Any) -> str:
    """The text a dropdown shows for one of its options."""
    return option if isinstance(option, str) else repr(option) if isinstance(option, float) else str(option)


def _as_number(raw: Any) -> float | None:
    """``raw`` as a finite float, or None if it is not a finite real number.

    Accepts ints and floats (not bools) and numeric strings written as plain decimals.
    """
    if isinstance(raw, bool):
        return None
    if isinstance(raw, (int, float)):
        try:
            x = float(raw)
        except (OverflowError, ValueError):
            return None
    elif isinstance(raw, str):
        text = raw.strip()
        if not text or len(text) > 64:
            return None
        try:
            x = float(text)  # float() parses numerals only; no code is evaluated
        except ValueError:
            return None
    else:
        try:
            import numpy as np

            if isinstance(raw, np.generic) and np.issubdtype(type(raw), np.number):
                x = float(raw)
            else:
                return None
        except Exception:  # pragma: no cover - numpy is a hard dependency
            return None
    return x if math.isfinite(x) else None


def _numeric(control: Control, raw: Any, lo: float | None, hi: float | None, step: float | None,
             text: bool = True) -> Checked:
    """``text``: a numeral in a string is read (a number field, a text field bound to a
    number); a slider's value is never text."""
    x = None if isinstance(raw, str) and not text else _as_number(raw)
    if x is None:
        return _refuse(control, f"{_show(raw)} is not a finite number")
    note = ""
    # clamped first: 1e308 - min over a step of 0.01 is no finite number to round
    if lo is not None and x < lo:
        x, note = float(lo), f"clamped to the minimum {lo:g}"
    if hi is not None and x > hi:
        x, note = float(hi), f"clamped to the maximum {hi:g}"
    if step is not None and step > 0 and lo is not None and math.isfinite((x - lo) / step):
        q = lo + round((x - lo) / step) * step
        # keep the decimals of the step (0.1 stays 0.1, not 0.30000000000000004)
        digits = max(0, -math.floor(math.log10(step)) + 3) if step < 1 else 0
        q = round(q, digits) if digits else q
        x = q
    if lo is not None and x < lo:
        x, note = float(lo), f"clamped to the minimum {lo:g}"
    if hi is not None and x > hi:
        x, note = float(hi), f"clamped to the maximum {hi:g}"
    if control.vtype == "int":
        x = int(round(x))
        if lo is not None and x < lo:
            x = int(math.ceil(lo))
        if hi is not None and x > hi:
            x = int(math.floor(hi))
        return Checked(True, x, note)
    return Checked(True, float(x), note)


def _show(raw: Any) -> str:
    text = repr(raw)
    return text if len(text) <= 40 else text[:37] + "..."


def validate_control(control: Control, raw: Any) -> Checked:
    """Check a value sent by the browser for ``control``.

    Numbers (sliders, number fields, or any control whose ``vtype`` is ``float``/``int``)
    must be finite; they are clamped to ``[min, max]``, quantised to a slider's ``step``
    and rounded for ``int`` variables. Checkboxes take a real bool. Text fields take a
    str of at most :data:`MAX_TEXT_LENGTH` characters. A dropdown takes one of its options
    (or the text shown for one). Anything else is refused with a message.
    """
    if isinstance(control, Dropdown):
        options = list(control.options)
        for opt in options:
            if type(raw) is type(opt) and raw == opt:
                return Checked(True, opt)
        if isinstance(raw, str):
            for opt in options:
                if option_label(opt) == raw:
                    return Checked(True, opt)
        return _refuse(control, f"{_show(raw)} is not one of the options")
    if isinstance(control, Checkbox) or (control.vtype == "bool" and not isinstance(control, (Slider, Number))):
        if isinstance(raw, bool):
            return Checked(True, raw)
        try:
            import numpy as np

            if isinstance(raw, np.bool_):
                return Checked(True, bool(raw))
        except Exception:  # pragma: no cover
            pass
        return _refuse(control, f"{_show(raw)} is not true or false")
    if control.vtype == "str" or (isinstance(control, Text) and control.vtype not in ("float", "int")):
        if not isinstance(raw, str):
            return _refuse(control, f"{_show(raw)} is not text")
        if len(raw) > MAX_TEXT_LENGTH:
            return _refuse(control, f"the text is {len(raw)} characters long (at most {MAX_TEXT_LENGTH})")
        return Checked(True, raw)
    if isinstance(control, Slider):
        return _numeric(control, raw, control.min, control.max, control.step, text=False)
    if isinstance(control, Number):
        return _numeric(control, raw, control.min, control.max, None)
    if control.vtype in ("float", "int"):
        return _numeric(control, raw, None, None, None)
    return _refuse(control, f"cannot accept a value for a variable of type {control.vtype!r}")
