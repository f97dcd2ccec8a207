"""``--plot out.png``: a summary column against one or two parameters (matplotlib, imported lazily).

One parameter: the column against it. Two: one curve per value of the second parameter
when it takes a few values (at most 8), else points coloured by the column. By default the
parameter with the most values is along x. Failed runs are left out.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ejsrl.app.sweep_table import Table

__all__ = ["PlotError", "MATPLOTLIB_HINT", "check_matplotlib", "plot_summary", "default_y"]

MATPLOTLIB_HINT = "--plot needs matplotlib: pip install 'ejsgen[plot]' (or: pip install matplotlib)"


class PlotError(ValueError):
    """The plot asked for cannot be drawn (an unknown column, no parameter, ...)."""


def check_matplotlib() -> str | None:
    """None if matplotlib can be imported, else the install hint."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return MATPLOTLIB_HINT
    return None


def default_y(summary: Table, params: Sequence[str]) -> str:
    """The first metric, else the final value of the first recorded number that is not a parameter."""
    fixed = {"run", "status", "error", "seconds", *params}
    numeric = [n for n, c in summary.columns.items() if n not in fixed and c.kind in ("float", "int")]
    metrics = [n for n in numeric if "." not in n]
    finals = [n for n in numeric if n.endswith(".final")]
    for choice in metrics + finals[1:] + finals[:1]:  # skip the time column's final if there is another
        return choice
    raise PlotError("the summary has no numeric column to plot")


def plot_summary(summary: Table, params: Sequence[str], out: str | Path, *, y: str | None = None, x: str | None = None) -> None:
    """Draw ``y`` (a summary column) against the parameters ``x`` ("P" or "P,Q") into ``out``."""
    hint = check_matplotlib()
    if hint:
        raise PlotError(hint)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if x:
        xs = [s.strip() for s in x.split(",")]
    else:  # the parameter with the most values along x, the next one as curves
        present = [p for p in params if p in summary.columns]
        counts = {p: len(set(summary.to_pydict()[p])) for p in present}
        xs = sorted(present, key=lambda p: -counts[p])[:2]
    if not xs:
        raise PlotError("the sweep has no parameter to plot against (give --grid, --values or --table)")
    for name in xs:
        if name not in summary.columns:
            raise PlotError(f"'{name}' is not a parameter of this sweep (parameters: {', '.join(params) or 'none'})")
    y = y or default_y(summary, params)
    if y not in summary.columns:
        from ejsrl._suggest import did_you_mean

        raise PlotError(f"'{y}' is not a column of the summary{did_you_mean(y, summary.columns)}")
    data = summary.to_pydict()
    ok = [s != "error" and data[y][i] is not None for i, s in enumerate(data["status"])]
    yv = np.array([v for v, k in zip(data[y], ok) if k], dtype=float)
    fig, ax = plt.subplots(figsize=(6.4, 4.4), dpi=100)
    x0 = np.array([v for v, k in zip(data[xs[0]], ok) if k], dtype=float)
    if len(xs) == 1:
        order = np.argsort(x0, kind="stable")
        ax.plot(x0[order], yv[order], "o-")
    else:
        x1 = [v for v, k in zip(data[xs[1]], ok) if k]
        levels = list(dict.fromkeys(x1))
        if len(levels) <= 8:
            for level in levels:
                sel = np.array([v == level for v in x1])
                order = np.argsort(x0[sel], kind="stable")
                ax.plot(x0[sel][order], yv[sel][order], "o-", label=f"{xs[1]} = {_fmt(level)}")
            ax.legend(fontsize="small")
        else:
            points = ax.scatter(x0, np.array(x1, dtype=float), c=yv, cmap="viridis")
            fig.colorbar(points, ax=ax, label=y)
            ax.set_ylabel(xs[1])
    ax.set_xlabel(xs[0])
    if len(xs) == 1 or ax.get_legend() is not None:
        ax.set_ylabel(y)
    failed = len(ok) - sum(ok)
    ax.set_title(f"{y} over {len(ok)} runs" + (f" ({failed} failed, not shown)" if failed else ""))
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


def _fmt(v: Any) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)
