"""The runs of a sweep: parameter grids, lists of values, tables and random / Latin-hypercube samples.

Every run is a list of ``NAME=VALUE`` settings with the meaning of a headless run's
``--set`` (:func:`ejsrl.app.cli.parse_set`): the design only writes the text, each run
parses it against the model's variables exactly as ``app.py --headless --set`` would.

The runs are the product of the sources: the rows of ``--table``, each ``--values`` list
and each ``--grid`` axis (or, with ``--samples N``, the N points drawn from the ``--grid``
ranges), in that order; ``--set`` settings apply to every run.
"""

from __future__ import annotations

import ast
import csv
import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["Run", "SweepDesignError", "GridAxis", "parse_grid", "parse_values", "read_table", "design", "display_value"]


class SweepDesignError(ValueError):
    """A parameter option the user wrote wrongly; the message says what and how to fix it."""


@dataclass(frozen=True)
class Run:
    """One run of a sweep: its number and its ``NAME=VALUE`` settings (``--set`` text), in order."""

    run: int
    settings: tuple[tuple[str, str], ...]

    @property
    def params(self) -> dict[str, str]:
        return dict(self.settings)

    def set_args(self) -> list[str]:
        """The settings as ``--set`` arguments of a headless run."""
        return [f"{name}={text}" for name, text in self.settings]


@dataclass
class GridAxis:
    """``--grid NAME=start:stop:count`` (``count`` may be left out with ``--samples``)."""

    name: str
    start: float
    stop: float
    count: int | None = None
    text: str = field(default="", compare=False)


def _split_assignment(option: str, text: str) -> tuple[str, str]:
    if "=" not in text:
        raise SweepDesignError(f"{option} takes NAME=..., got {text!r}")
    name, rest = (s.strip() for s in text.split("=", 1))
    if not name.isidentifier():
        raise SweepDesignError(f"{option} {text!r}: {name!r} is not a variable name")
    return name, rest


def parse_grid(text: str, *, need_count: bool = True) -> GridAxis:
    """``NAME=start:stop:count``: ``count`` evenly spaced values from start to stop, both included."""
    name, rest = _split_assignment("--grid", text)
    parts = rest.split(":")
    if len(parts) not in (2, 3) or (need_count and len(parts) != 3):
        form = "NAME=start:stop:count" + (" (or NAME=start:stop with --samples)" if need_count else "")
        raise SweepDesignError(f"--grid {text!r}: expected {form}, e.g. L=0.5:2:4")
    try:
        start, stop = float(parts[0]), float(parts[1])
    except ValueError:
        raise SweepDesignError(f"--grid {text!r}: start and stop must be numbers") from None
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise SweepDesignError(f"--grid {text!r}: start and stop must be finite")
    count = None
    if len(parts) == 3:
        try:
            count = int(parts[2])
        except ValueError:
            raise SweepDesignError(f"--grid {text!r}: count must be a whole number, got {parts[2]!r}") from None
        if count < 1:
            raise SweepDesignError(f"--grid {text!r}: count must be at least 1")
    return GridAxis(name, start, stop, count, text)


def split_top_level(text: str) -> list[str]:
    """Split on commas that are not inside brackets or quotes: ``[0,1],[2,3]`` is two items."""
    items, depth, quote, cur = [], 0, "", []
    for ch in text:
        if quote:
            cur.append(ch)
            if ch == quote:
                quote = ""
            continue
        if ch in "'\"":
            quote = ch
        elif ch in "[(":
            depth += 1
        elif ch in "])":
            depth -= 1
        elif ch == "," and depth == 0:
            items.append("".join(cur).strip())
            cur = []
            continue
        cur.append(ch)
    items.append("".join(cur).strip())
    return items


def parse_values(text: str) -> tuple[str, list[str]]:
    """``NAME=a,b,c``: the values as ``--set`` text (lists keep their commas: ``q0=[0,0],[1,1]``)."""
    name, rest = _split_assignment("--values", text)
    items = split_top_level(rest)
    if not rest or any(not item for item in items):
        raise SweepDesignError(f"--values {text!r}: expected NAME=a,b,c with no empty value")
    return name, items


def read_table(path: str | Path) -> tuple[list[str], list[list[str]]]:
    """A CSV file of runs: a header of variable names, then one row of ``--set`` values per run."""
    path = Path(path)
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = [row for row in csv.reader(fh) if any(cell.strip() for cell in row)]
    except OSError as exc:
        raise SweepDesignError(f"--table: cannot read {path}: {exc.strerror or exc}") from None
    if not rows:
        raise SweepDesignError(f"--table {path}: the file is empty; its first line names the variables")
    header = [h.strip() for h in rows[0]]
    for h in header:
        if not h.isidentifier():
            raise SweepDesignError(f"{path}:1: {h!r} is not a variable name (the first line names the variables)")
    if len(set(header)) != len(header):
        raise SweepDesignError(f"{path}:1: a variable is named twice in the header")
    body = []
    for i, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise SweepDesignError(f"{path}:{i}: {len(row)} values for {len(header)} variables")
        body.append([cell.strip() for cell in row])
    if not body:
        raise SweepDesignError(f"--table {path}: no runs (only a header)")
    return header, body


def _number_text(value: float, kind: str, name: str) -> str:
    if kind == "int":
        if value != round(value):
            raise SweepDesignError(f"'{name}' is an integer variable; {value:g} is not a whole number (choose a count that gives whole numbers)")
        return str(int(round(value)))
    return repr(float(value))


def _samples(axes: list[GridAxis], n: int, seed: int | None, method: str) -> np.ndarray:
    """``n`` points in the unit cube, one column per axis."""
    if method == "lhs":
        from scipy.stats import qmc

        return qmc.LatinHypercube(d=len(axes), seed=seed).random(n)
    if method == "random":
        return np.random.default_rng(seed).random((n, len(axes)))
    raise SweepDesignError(f"--sampling {method!r}: expected lhs or random")


def design(
    types: dict[str, str],
    *,
    grid: Sequence[str] = (),
    values: Sequence[str] = (),
    table: str | Path | None = None,
    samples: int | None = None,
    seed: int | None = None,
    sampling: str = "lhs",
    fixed: Sequence[str] = (),
) -> list[Run]:
    """The runs, numbered from 0. ``types`` are the model's ``VARIABLES`` (name -> type).

    Raises :class:`SweepDesignError` for an option written wrongly or a name that is not a
    variable (with a suggestion). The values themselves are checked by ``parse_set``.
    """
    axes_settings: list[list[tuple[tuple[str, str], ...]]] = []
    names: list[str] = []

    def claim(name: str, option: str) -> None:
        if name not in types:
            from ejsrl._suggest import did_you_mean

            raise SweepDesignError(f"{option}: unknown variable '{name}'{did_you_mean(name, types)}")
        if name in names:
            raise SweepDesignError(f"{option}: '{name}' is already a parameter of this sweep")
        names.append(name)

    if table is not None:
        header, body = read_table(table)
        for h in header:
            claim(h, f"--table {table}")
        axes_settings.append([tuple(zip(header, row)) for row in body])
    for text in values:
        name, items = parse_values(text)
        claim(name, "--values")
        axes_settings.append([((name, item),) for item in items])
    axes = [parse_grid(text, need_count=samples is None) for text in grid]
    for ax in axes:
        claim(ax.name, "--grid")
        if types[ax.name] not in ("float", "int", "auto"):
            raise SweepDesignError(f"--grid {ax.text!r}: '{ax.name}' is {_kind_words(types[ax.name])}; a grid takes a number variable (use --values)")
    if samples is not None:
        if samples < 1:
            raise SweepDesignError("--samples must be at least 1")
        if not axes:
            raise SweepDesignError("--samples draws points from the --grid ranges: give at least one --grid NAME=start:stop")
        unit = _samples(axes, samples, seed, sampling)
        points = []
        for row in unit:
            point = []
            for ax, u in zip(axes, row):
                v = ax.start + float(u) * (ax.stop - ax.start)
                if types[ax.name] == "int":
                    v = float(round(v))
                point.append((ax.name, _number_text(v, types[ax.name], ax.name)))
            points.append(tuple(point))
        axes_settings.append(points)
    else:
        if seed is not None:
            raise SweepDesignError("--seed goes with --samples")
        for ax in axes:
            assert ax.count is not None
            grid_values = np.linspace(ax.start, ax.stop, ax.count) if ax.count > 1 else np.array([ax.start])
            axes_settings.append([((ax.name, _number_text(float(v), types[ax.name], ax.name)),) for v in grid_values])
    fixed_settings: list[tuple[str, str]] = []
    for text in fixed:
        name, rest = _split_assignment("--set", text)
        claim(name, "--set")
        fixed_settings.append((name, rest))
    if not axes_settings:
        axes_settings.append([()])  # one run with the spec's own values
    runs = []
    for i, combo in enumerate(itertools.product(*axes_settings)):
        settings = tuple(s for part in combo for s in part) + tuple(fixed_settings)
        runs.append(Run(i, settings))
    return runs


def _kind_words(kind: str) -> str:
    return {"bool": "a boolean", "str": "text", "array": "an array", "object": "an object"}.get(kind, f"of type {kind}")


def display_value(text: str, kind: str) -> Any:
    """A parameter's value for the results table: a number, boolean or text (lists stay text)."""
    if kind == "str":
        try:
            value = ast.literal_eval(text)
            return value if isinstance(value, str) else text
        except (ValueError, SyntaxError):
            return text
    if kind == "bool":
        return text.lower() in ("true", "1", "yes", "on")
    try:
        value = ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text
    if isinstance(value, bool):
        return value
    if isinstance(value, int):
        return value if kind == "int" else float(value)
    if isinstance(value, float):
        return value
    return text
