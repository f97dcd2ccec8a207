"""Headless runs as issue #24's trial found them wanting: ``--vars`` takes array elements
as the CSV header names them (``q[0]``, ``m[1][2]``, slices), and a lab with no
independent variable runs for ``--steps N`` (or, if it does not evolve at all, writes the
row after ``init``) instead of being refused."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest

from testkit import run_app

ARRAYS = """\
ejs: 1
title: Arrays in columns
model:
  variables:
    t: 0.0
    dt: 0.5
    q: [1.0, 2.0, 3.0, 4.0]
    m: {expr: "np.arange(6.0).reshape(2, 3)"}
  evolution:
    - code: |
        t = t + dt
        q = q + 10.0
        m = m * 2.0
view:
  - label: {text: "{t}"}
"""

COUNTER = """\
ejs: 1
title: A counter with no time
model:
  variables:
    n: 0
    total: 0.0
  evolution:
    - code: |
        n = n + 1
  fixed_relations: |
    total = n * 2.5
view:
  - label: {text: "{n}"}
"""

STILL = """\
ejs: 1
title: A calculation
model:
  variables:
    g: 9.81
    h: 0.0
  init: |
    h = g * 2.0
view:
  - label: {text: "{h}"}
"""


def _build(tmp: Path, name: str, text: str) -> Path:
    from ejsgen.cli import build

    spec = tmp / f"{name}.ejs.yaml"
    spec.write_text(text, encoding="utf-8")
    return build(spec, tmp / name)


@pytest.fixture(scope="module")
def apps(tmp_path_factory) -> dict[str, Path]:
    tmp = tmp_path_factory.mktemp("trial24")
    return {name: _build(tmp, name, text) for name, text in (("arrays", ARRAYS), ("counter", COUNTER), ("still", STILL))}


def table(stdout: str) -> list[list[str]]:
    return list(csv.reader(io.StringIO(stdout)))


def test_vars_array_elements_write_exactly_those_columns(apps) -> None:
    r = run_app(apps["arrays"], "--headless", "--duration", "1", "--csv", "-", "--vars", "q[0],t", timeout=60)
    assert r.returncode == 0, r.stderr
    rows = table(r.stdout)
    assert rows[0] == ["q[0]", "t"]
    # after init, then after each of 2 steps of 0.5: q[0] gains 10 a step
    assert [[float(v) for v in row] for row in rows[1:]] == [[1.0, 0.0], [11.0, 0.5], [21.0, 1.0]]


def test_vars_headers_match_the_default_csv(apps) -> None:
    full = run_app(apps["arrays"], "--headless", "--duration", "1", "--csv", "-", timeout=60)
    assert full.returncode == 0, full.stderr
    everything = table(full.stdout)
    picks = "q[-1],m[1][2],q[1:3],m[0][::2]"
    r = run_app(apps["arrays"], "--headless", "--duration", "1", "--csv", "-", "--vars", picks, timeout=60)
    assert r.returncode == 0, r.stderr
    rows = table(r.stdout)
    assert rows[0] == ["q[3]", "m[1][2]", "q[1]", "q[2]", "m[0][0]", "m[0][2]"]
    # each column is the default CSV's column of that name, row for row
    where = {name: i for i, name in enumerate(everything[0])}
    for got, ref in zip(rows[1:], everything[1:], strict=True):
        assert got == [ref[where[name]] for name in rows[0]]
    assert float(rows[-1][1]) == 5.0 * 4  # m[1][2] = 5, doubled twice


@pytest.mark.parametrize(
    ("pick", "says"),
    [("q[4]", "index 4 is out of range"), ("q[0][1]", "has 2 indices, but 'q' has 1"), ("p[0]", "unknown variable 'p'"),
     ("q[a]", "is not an index"), ("t[0]", "not an array"), ("q[2:2]", "selects no element")],
)
def test_bad_element_is_refused_before_any_row(apps, tmp_path: Path, pick: str, says: str) -> None:
    out = tmp_path / "out.csv"
    r = run_app(apps["arrays"], "--headless", "--duration", "1", "--csv", str(out), "--vars", pick, timeout=60)
    assert r.returncode == 2
    assert says in r.stderr and "Traceback" not in r.stderr
    assert not out.exists() or out.read_text() == ""


def test_no_independent_variable_runs_for_steps(apps) -> None:
    r = run_app(apps["counter"], "--headless", "--steps", "4", "--csv", "-", timeout=60)
    assert r.returncode == 0, r.stderr
    rows = table(r.stdout)
    assert rows[0] == ["n", "total"]
    assert [[float(v) for v in row] for row in rows[1:]] == [[n, n * 2.5] for n in range(5)]
    r = run_app(apps["counter"], "--headless", "--steps", "6", "--every", "3", "--csv", "-", "--vars", "n", timeout=60)
    assert r.returncode == 0, r.stderr
    assert table(r.stdout) == [["n"], ["0"], ["3"], ["6"]]


@pytest.mark.parametrize("args", [("--duration", "1"), ()])
def test_no_independent_variable_says_to_give_steps(apps, args: tuple[str, ...]) -> None:
    r = run_app(apps["counter"], "--headless", *args, "--csv", "-", timeout=60)
    assert r.returncode == 2
    assert "no independent variable" in r.stderr and "--steps N" in r.stderr
    assert r.stdout == ""


def test_model_that_does_not_evolve_writes_its_row_after_init(apps) -> None:
    r = run_app(apps["still"], "--headless", "--csv", "-", timeout=60)
    assert r.returncode == 0, r.stderr
    assert table(r.stdout) == [["g", "h"], ["9.81", repr(9.81 * 2.0)]]


def test_steps_with_a_time_variable_and_none_at_all(apps) -> None:
    r = run_app(apps["arrays"], "--headless", "--steps", "3", "--csv", "-", "--vars", "t", timeout=60)
    assert r.returncode == 0, r.stderr
    assert table(r.stdout) == [["t"], ["0.0"], ["0.5"], ["1.0"], ["1.5"]]
    r = run_app(apps["arrays"], "--headless", "--csv", "-", timeout=60)
    assert r.returncode == 2 and "--duration T" in r.stderr and "--steps N" in r.stderr


TALKER = """\
ejs: 1
title: A lab that talks
model:
  variables:
    t: 0.0
    dt: 0.05
    x: 1.0
  init: |
    print("init says hello")
    alert("init alert")
  evolution:
    - code: |
        t = t + dt
        x = x * 0.99
view:
  - label: {text: "{x}"}
"""


@pytest.mark.parametrize(("args", "before"), [(("--processes", "2"), 0), (("--processes", "1"), 0), (("--shared",), 1)])
def test_start_up_measurement_prints_nothing(tmp_path: Path, args: tuple[str, ...], before: int) -> None:
    """Served per tab, the lab's start-up apps (the template, the cost measurement) print
    nothing (the trial saw init's line four times before "serving on"); the tab's own
    session still prints its init once. ``--shared``: the one simulation prints it once."""
    from testkit.guard_client import Client, run_async
    from testkit.served import Served

    app = _build(tmp_path, "talker", TALKER)
    served = Served(app, tmp_path, *args)
    try:
        text = served.out.read_text()
        assert text.count("init says hello") == before, text
        assert "init alert" not in text + served.err.read_text()

        async def open_tab() -> None:
            client = await Client.open(served.port)
            try:
                await client.until(lambda: "init says hello" in served.out.read_text(), "the session's init to print", 60.0)
                await client.settle(0.5)
            finally:
                await client.ws.close()

        run_async(open_tab())
        final = served.out.read_text()
        assert final.count("init says hello") == 1, final
        assert "init alert" not in final
    finally:
        served.stop()


def test_ejsgen_run_passes_steps_to_the_app(tmp_path: Path) -> None:
    """``ejsgen run --headless --steps 2 SPEC``: 2 is --steps' value, not the spec."""
    import subprocess
    import sys

    spec = tmp_path / "counter.ejs.yaml"
    spec.write_text(COUNTER, encoding="utf-8")
    r = subprocess.run([sys.executable, "-m", "ejsgen", "run", "--headless", "--steps", "2", str(spec), "--csv", "-",
                        "--vars", "n"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert table(r.stdout) == [["n"], ["0"], ["1"], ["2"]]
