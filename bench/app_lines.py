"""Lines of each example's spec and of the app.py ejsgen generates from it, and their ratio.

    python bench/app_lines.py            # every example: examples/*.ejs.yaml, paper/, tutorial/
    python bench/app_lines.py --max 2.0  # exit 1 if any app is more than twice its spec

Generated apps should read like their spec (issue 11: at most 2.0x its lines). The app text is
rendered in memory (nothing is written) with the ejsgen that Python imports.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


def example_specs() -> list[Path]:
    """Every example spec: the core examples, the paper labs and the tutorial steps."""
    return sorted(EXAMPLES.glob("*.ejs.yaml")) + sorted((EXAMPLES / "paper").glob("*.ejs.yaml")) + sorted((EXAMPLES / "tutorial").glob("*.ejs.yaml"))


def measure(spec: Path) -> tuple[int, int]:
    """(spec lines, app.py lines) of one example."""
    from ejsgen.cli import load_plan
    from ejsgen.generate import render_app

    text = render_app(load_plan(spec))
    return len(spec.read_text(encoding="utf-8").splitlines()), len(text.splitlines())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max", type=float, default=None, help="fail if an app is more than this many times its spec")
    args = parser.parse_args(argv)
    worst = 0.0
    print(f"{'example':34} {'spec':>5} {'app.py':>6} {'ratio':>6}")
    for spec in example_specs():
        name = str(spec.relative_to(EXAMPLES)).removesuffix(".ejs.yaml")
        try:
            n_spec, n_app = measure(spec)
        except Exception as exc:  # noqa: BLE001 - a spec this ejsgen cannot build (e.g. an older ejsgen)
            print(f"{name:34} does not build: {str(exc).splitlines()[0][-60:]}")
            continue
        ratio = n_app / n_spec
        worst = max(worst, ratio)
        print(f"{name:34} {n_spec:5d} {n_app:6d} {ratio:6.2f}")
    print(f"{'largest ratio':34} {'':5} {'':6} {worst:6.2f}")
    return 1 if args.max is not None and worst > args.max else 0


if __name__ == "__main__":
    sys.exit(main())
