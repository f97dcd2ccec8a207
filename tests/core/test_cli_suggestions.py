"""A mistyped name on a built app's command line gets the suggestion a user meant."""

from __future__ import annotations

import pytest

from testkit import run_app


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--set", "l=2"], "--set: unknown variable 'l'; did you mean 'L'?"),  # only the case differs
        (["--set", "Lx=2"], "--set: unknown variable 'Lx'; did you mean 'L'?"),  # not 'x'
        (["--vars", "t,thta"], "--vars: unknown variable 'thta'; did you mean 'theta'?"),
        (["--set", "zzz=1"], "--set: unknown variable 'zzz'"),
    ],
)
def test_unknown_names_on_the_command_line_get_the_closest_variable(built, args: list[str], expected: str) -> None:
    r = run_app(built("pendulum"), "--headless", "--duration", "0.05", "--csv", "-", *args)
    assert r.returncode != 0
    assert expected in r.stderr, r.stderr
    if "did you mean" not in expected:
        assert "did you mean" not in r.stderr


def test_a_sweep_names_a_bad_value_as_a_parameter_not_as_set(built) -> None:
    r = run_app(built("pendulum"), "--sweep", "--values", "b=x,y", "--duration", "0.05", "--workers", "0")
    assert r.returncode != 0
    assert "parameter b: 'x' is not a number" in r.stderr, r.stderr
    assert "--set" not in r.stderr


def test_a_sweep_suggests_the_variable_a_grid_meant(built) -> None:
    r = run_app(built("pendulum"), "--sweep", "--grid", "l=0.5:2:4", "--duration", "0.05", "--workers", "0")
    assert r.returncode != 0
    assert "--grid: unknown variable 'l'; did you mean 'L'?" in r.stderr, r.stderr
