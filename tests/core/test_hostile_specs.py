"""Hostile specs are refused where they are, quickly, in one line.

A few hundred bytes of YAML aliases that expand to 10^9 values, brackets nested 100,000
deep, an expression of 100,000 terms, an array of 10^8 numbers in a CSV: each is refused
(or left out) with FILE:LINE:COL or the variable's name, in well under the time and memory
it took before (2.6 GB and a hang; a 3,000-line RecursionError; MemoryError after 18 s).
"""

from __future__ import annotations

import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import pytest

from ejsgen._yaml_bounds import MAX_ALIAS_VALUES, MAX_DEPTH
from ejsgen.errors import SpecError
from ejsgen.yamlload import load_yaml
from testkit import EXAMPLES, run_app

BALL = (EXAMPLES / "bouncing_ball.ejs.yaml").read_text(encoding="utf-8")


def laughs(levels: int = 10) -> str:
    """The classic: each anchor holds nine aliases of the one before (9^levels strings)."""
    lines = ["ejs: 1", "title: Laughs", 'l0: &a0 ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    for i in range(1, levels):
        lines.append(f"l{i}: &a{i} [" + ",".join([f"*a{i - 1}"] * 9) + "]")
    return "\n".join(lines) + "\n"


def ejsgen(*args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "ejsgen", *args], capture_output=True, text=True, timeout=timeout)


def test_billion_laughs_is_refused_at_its_alias_in_under_a_second_with_little_memory() -> None:
    text = laughs()
    assert len(text.encode()) < 700
    tracemalloc.start()
    t0 = time.perf_counter()
    with pytest.raises(SpecError) as info:
        load_yaml("laughs.ejs.yaml", text=text)
    elapsed = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    err = info.value
    assert elapsed < 1.0, elapsed
    assert peak < 20e6, peak
    # 9 + 81 + 729 + ... : the alias that takes the count past the bound is on line 8 (l5: 9^6 values)
    line = err.where.line
    assert 4 <= line <= 9 and text.splitlines()[line - 1][err.where.col - 1] == "*", err.format()
    assert f"{MAX_ALIAS_VALUES:,} values" in err.message and "billion laughs" in err.message


def test_billion_laughs_on_the_command_line_is_one_line_and_status_1(tmp_path: Path) -> None:
    spec = tmp_path / "laughs.ejs.yaml"
    spec.write_text(laughs(), encoding="utf-8")
    for command in ("validate", "build"):
        r = ejsgen(command, str(spec), *(["-o", str(tmp_path / "out")] if command == "build" else []), timeout=60)
        assert r.returncode == 1, r.stderr
        assert r.stderr.startswith(f"{spec}:") and "billion laughs" in r.stderr
        assert "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not (tmp_path / "out").exists()


def test_an_alias_inside_its_own_anchor_is_refused_not_looped() -> None:
    with pytest.raises(SpecError) as info:
        load_yaml("lab.ejs.yaml", text="ejs: 1\nx: &loop [1, [2, *loop]]\n")
    assert (info.value.where.line, info.value.where.col) == (2, 18)
    assert "refers to the value that contains it" in info.value.message


def test_a_few_honest_aliases_still_load_as_copies() -> None:
    doc = load_yaml("lab.ejs.yaml", text="style: &s {color: red, width: 2}\na: *s\nb: [*s, *s]\n")
    assert doc.data["a"] == doc.data["b"][0] == doc.data["b"][1] == {"color": "red", "width": 2}


def test_deep_brackets_are_refused_at_the_first_one_past_the_bound(tmp_path: Path) -> None:
    text = "ejs: 1\ntitle: Deep\nx: " + "[" * 100_000 + "]" * 100_000 + "\n"
    t0 = time.perf_counter()
    with pytest.raises(SpecError) as info:
        load_yaml("deep.ejs.yaml", text=text)
    assert time.perf_counter() - t0 < 1.0
    assert (info.value.where.line, info.value.where.col) == (3, 3 + MAX_DEPTH)  # the mapping is level 1, the first bracket (column 4) level 2
    assert f"more than {MAX_DEPTH} levels deep" in info.value.message
    spec = tmp_path / "deep.ejs.yaml"
    spec.write_text(text, encoding="utf-8")
    r = ejsgen("validate", str(spec))
    assert r.returncode == 1 and "RecursionError" not in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr[-2000:]
    assert r.stderr.startswith(f"{spec}:3:{3 + MAX_DEPTH}: error: ")


def test_deep_block_mappings_are_refused_too() -> None:
    text = "".join(" " * i + f"k{i}:\n" for i in range(200)) + " " * 200 + "v: 1\n"
    with pytest.raises(SpecError) as info:
        load_yaml("deep.ejs.yaml", text=text)
    assert info.value.where.line == MAX_DEPTH + 1 and "levels deep" in info.value.message


@pytest.mark.parametrize("terms", [400, 100_000])
def test_an_expression_of_thousands_of_terms_is_refused_at_its_line(tmp_path: Path, terms: int) -> None:
    spec = tmp_path / "chain.ejs.yaml"
    text = BALL.replace("    y = h0\n", "    y = " + " + ".join(["h0"] * terms) + "\n")
    spec.write_text(text, encoding="utf-8")
    line = text.splitlines().index("    y = " + " + ".join(["h0"] * terms)) + 1
    r = ejsgen("build", str(spec), "-o", str(tmp_path / "out"))
    assert r.returncode == 1 and "RecursionError" not in r.stderr, r.stderr[-3000:]
    assert r.stderr.startswith(f"{spec}:{line}:5: error: the code in model.init nests more than 200 levels deep"), r.stderr[-500:]


def test_a_long_but_ordinary_expression_still_builds_and_runs(tmp_path: Path) -> None:
    spec = tmp_path / "sum.ejs.yaml"
    spec.write_text(BALL.replace("    y = h0\n", "    y = (" + " + ".join(["h0"] * 150) + ") / 150\n"), encoding="utf-8")
    r = ejsgen("build", str(spec), "-o", str(tmp_path / "out"))
    assert r.returncode == 0, r.stderr
    run = run_app(tmp_path / "out", "--headless", "--duration", "0", "--csv", "-", "--vars", "y", timeout=120)
    assert run.returncode == 0 and run.stdout.splitlines()[1] == "1.0", run.stderr


BIG = """\
ejs: 1
title: Big
model:
  variables:
    t: 0.0
    dt: 0.1
    x: 1.0
    big: [0.0]
  init: |
    big = np.zeros(10**8)
  evolution:
    - ode:
        equations:
          x: -x
view: []
"""


@pytest.fixture(scope="module")
def big_app(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from ejsgen.cli import build

    spec = tmp_path_factory.mktemp("big") / "big.ejs.yaml"
    spec.write_text(BIG, encoding="utf-8")
    return build(spec, spec.parent / "app")


def test_an_array_of_1e8_values_is_left_out_of_the_default_csv_and_said(big_app: Path) -> None:
    t0 = time.perf_counter()
    r = run_app(big_app, "--headless", "--duration", "0.3", "--csv", "-", timeout=120)
    assert time.perf_counter() - t0 < 15
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == "t,dt,x" and len(lines) >= 4 and all(len(line.split(",")) == 3 for line in lines)
    assert "note: 'big' (100,000,000 values) is left out of the CSV" in r.stderr


def test_an_array_of_1e8_values_named_in_vars_is_refused_in_plain_words(big_app: Path, tmp_path: Path) -> None:
    out = tmp_path / "b.csv"
    t0 = time.perf_counter()
    r = run_app(big_app, "--headless", "--duration", "0.3", "--csv", str(out), "--vars", "x,big", timeout=120)
    assert time.perf_counter() - t0 < 15
    assert r.returncode == 2 and "Traceback" not in r.stderr and "MemoryError" not in r.stderr
    assert "error: 'big' is an array of 100,000,000 values" in r.stderr and "--vars" in r.stderr
    assert not out.exists()
