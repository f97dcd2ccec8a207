"""Compile the spec's ``metrics:`` (per-run results of a sweep) into methods of the model.

Each ``name: expression`` becomes a method ``_metric_<name>(self)``, checked like every
expression of the spec (unknown names are errors at ``FILE:LINE:COL``), and one method
``_ejs_metrics(self)`` lists them by name: a sweep (``ejsrl.app.sweep_worker``) calls them
on the state at the end of each run. A spec without metrics gets neither method.
"""

from __future__ import annotations

import keyword
from typing import TYPE_CHECKING

from ejsgen.errors import SpecError
from ejsgen.plan import Line

if TYPE_CHECKING:
    from ejsgen.compiler import Compiler

__all__ = ["compile_metrics", "RESERVED_METRIC_NAMES"]

#: the summary table's own columns (ejsrl.app.sweep_table.SUMMARY_COLUMNS)
RESERVED_METRIC_NAMES = ("run", "status", "error", "seconds")


def compile_metrics(c: Compiler) -> None:
    """Add ``_metric_<name>`` for each metric and ``_ejs_metrics`` listing them (errors go to ``c.errors``)."""
    entries: list[str] = []
    for name in c.spec.metrics:
        path = ("metrics", name)
        loc = c.doc.key_loc(path)
        if not name.isidentifier() or keyword.iskeyword(name) or name.startswith("_"):
            c.errors.append(SpecError(loc, f"'{name}' is not a valid metric name", "use letters, digits and _ (not starting with a digit or _); it names a column of the sweep's summary"))
            continue
        if name in RESERVED_METRIC_NAMES:
            c.errors.append(SpecError(loc, f"the metric '{name}' has the name of a column the sweep's summary already has ({', '.join(RESERVED_METRIC_NAMES)})", f"rename it, e.g. '{name}_'"))
            continue
        if name in c.var_decls:
            c.errors.append(SpecError(loc, f"the metric '{name}' has the name of a variable", f"rename it (e.g. 'final_{name}'), or record the variable itself with --vars"))
            continue
        method = c.expr_method(path, f"_metric_{name}", f"metric '{name}'", f"Metric '{name}': evaluated on the state at the end of a sweep's run.")
        if method is not None:
            entries.append(f"{name!r}: self.{method},")
    lines = [Line("return {")] + [Line(f"    {e}") for e in entries] + [Line("}")]
    c.add_method("_ejs_metrics", "self", "The spec's metrics by name (a sweep evaluates them at the end of each run).", lines)
