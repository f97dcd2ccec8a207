"""What the user reads when an FMU fails or stops: the FMU's own log (logging on, its
warnings and errors only, the last few, each cut to a readable length), the FMU, the call
and the spec line; an FMU that ends the run itself is information, not an error."""

from __future__ import annotations

import numpy as np
import pytest
from testkit import run_app

from test_reference_fmus import reference


def instance(version: int, name: str, kind: str = "model_exchange"):  # noqa: ANN201
    from ejsrl.fmi import FmuInstance, read_description, unpacked

    folder = unpacked(reference(version, name))
    return FmuInstance(folder, read_description(folder), kind, "ball")


@pytest.mark.parametrize("version", [2, 3])
def test_a_refused_call_shows_the_fmus_own_reason_and_names_the_call(version):
    from ejsrl.fmi import FmuError

    inst = instance(version, "BouncingBall")
    try:
        inst.initialize(0.0, lambda: None, lambda: None)  # now in continuous-time mode
        with pytest.raises(FmuError) as err:
            inst.set_values(["e"], [0.5], "setting parameters")  # a tunable parameter outside event mode
        setter = "fmi2SetReal" if version == 2 else "fmi3SetFloat64"
        assert str(err.value) == f"FMU 'ball': setting parameters: {setter} returned error: Variable e can only be set after instantiation, in initialization mode or event mode."
        assert err.value.log == ["Variable e can only be set after instantiation, in initialization mode or event mode."]
    finally:
        inst.free()


def test_the_fmus_log_keeps_warnings_and_errors_the_last_few_each_cut():
    from ejsrl.fmi._instance import LOG_CHARS, LOG_SHOWN

    inst = instance(2, "Dahlquist", "co_simulation")
    try:
        start = len(inst.log)
        inst._logger_text(0, b"logEvents", b"fmi2DoStep(...)")  # a call trace: dropped
        for k in range(8):
            inst._logger_text(1 if k % 2 else 3, b"logStatusError", f"problem {k}: ".encode() + b"x" * 1000)
        said = inst.said(start)
        assert len(said) == LOG_SHOWN == 5
        assert [s.split(":")[0] for s in said] == [f"problem {k}" for k in range(3, 8)]
        assert all(len(s) <= LOG_CHARS for s in said) and said[0].endswith("…")
        assert not any("fmi2DoStep" in m for m in inst.log)
    finally:
        inst.free()


@pytest.mark.parametrize("version", [2, 3])
def test_an_fmu_that_ends_the_run_is_information_not_an_error(tmp_path, version):
    """Stair stops itself at t = 9 (co-simulation): the run pauses there, exit status 0, and
    the FMU's end is told as an alert, not as an error."""
    from ejsgen.cli import build

    (tmp_path / "Stair.fmu").write_bytes(reference(version, "Stair").read_bytes())
    spec = tmp_path / "stair.ejs.yaml"
    spec.write_text(
        "ejs: 1\ntitle: Stair\nmodel:\n  variables: {t: 0.0, n: 0, dt: 0.3, counter: 0}\n  evolution:\n    - code: |\n        n = n + 1\n        t = n * dt\n"
        "fmus:\n  stair:\n    file: Stair.fmu\n    outputs: {counter: counter}\n"
    )
    r = run_app(build(spec, tmp_path / "app"), "--headless", "--duration", "12", "--csv", "-", "--vars", "t,counter")
    assert r.returncode == 0, r.stderr
    assert "alert: FMU 'stair' ended the simulation at t = 9" in r.stderr
    assert "stopped at t = 9 (the simulation paused itself)" in r.stderr
    assert "error" not in r.stderr
    rows = np.genfromtxt(r.stdout.splitlines(), delimiter=",", names=True)
    assert rows["t"][-1] == pytest.approx(9.0) and rows["counter"][-1] == 10
