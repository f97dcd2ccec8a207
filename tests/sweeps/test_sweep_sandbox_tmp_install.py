"""``ejsgen sweep --sandbox`` with ejsgen installed editable from a checkout under ``/tmp``.

The sandbox shows an empty ``/tmp``; an editable install finds its packages through a finder
of its own (not ``sys.path``), so a checkout under ``/tmp`` used to be hidden and every
sandboxed step ended with only "No module named ejsgen". The test makes that install: a
copy of this checkout's ejsgen and ejsrl in a checkout folder under ``/tmp`` (not on ``sys.path``), found
by a setuptools-like editable finder from ``sitecustomize`` on ``PYTHONPATH`` that never
falls back to the installed copy. The sweep must run and give the unsandboxed rows.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from testkit import ROOT
from testkit.sweeps import SPECS, read

FINDER = '''\
import importlib.util, sys
from pathlib import Path

MAPPING = {mapping!r}


class EditableFinder:
    """As setuptools' editable finder: the mapped packages, from their checkout only."""

    @classmethod
    def find_spec(cls, fullname, path=None, target=None):
        for pkg in sorted(MAPPING, key=len, reverse=True):
            if fullname == pkg or fullname.startswith(pkg + "."):
                rest = fullname[len(pkg):].lstrip(".")
                base = Path(MAPPING[pkg], *rest.split(".")) if rest else Path(MAPPING[pkg])
                for candidate in (base / "__init__.py", base.with_suffix(".py")):
                    if candidate.exists():
                        return importlib.util.spec_from_file_location(fullname, candidate)
                if "." not in fullname:
                    raise ModuleNotFoundError(f"No module named {{fullname!r}}", name=fullname)
                return None
        return None


sys.meta_path.insert(0, EditableFinder)
'''


def _sweep(args: list[str], env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-P", "-m", "ejsgen", *args], capture_output=True, text=True, timeout=600, env=env, check=False)


def test_a_sandboxed_sweep_runs_with_ejsgen_from_a_checkout_under_tmp(tmp_path: Path) -> None:
    with tempfile.TemporaryDirectory(prefix="ejsgen-checkout-", dir="/tmp") as tmp:
        checkout = Path(tmp)
        # the checkout's layout (pyproject.toml's package-dir), as an editable install maps it
        layout = {"ejsgen": "ejsgen", "ejsgen.templates": "templates", "ejsgen.specs": "specs", "ejsrl": "runtime/ejsrl"}
        for folder in layout.values():
            if not (checkout / folder).exists():
                shutil.copytree(ROOT / folder, checkout / folder, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        site = checkout / "site"
        site.mkdir()
        mapping = {name: str(checkout / folder) for name, folder in layout.items()}
        (site / "sitecustomize.py").write_text(FINDER.format(mapping=mapping), encoding="utf-8")
        env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1", PYTHONPATH=str(site))
        where = subprocess.run([sys.executable, "-P", "-c", "import ejsgen, ejsrl; print(ejsgen.__file__); print(ejsrl.__file__)"],
                               capture_output=True, text=True, env=env, timeout=120, check=False)
        assert where.stdout.split() == [str(checkout / "ejsgen" / "__init__.py"), str(checkout / "runtime" / "ejsrl" / "__init__.py")], where
        spec = SPECS / "springs.ejs.yaml"
        out = tmp_path / "runs.csv"
        r = _sweep(["sweep", str(spec), "--sandbox", "--values", "k=2,4", "--duration", "0.5", "--quiet", "--out", str(out)], env)
        assert r.returncode == 0, r.stderr
        assert "No module named" not in r.stderr
        plain = tmp_path / "plain.csv"
        r = _sweep(["sweep", str(spec), "--values", "k=2,4", "--duration", "0.5", "--workers", "0", "--quiet", "--out", str(plain)], env)
        assert r.returncode == 0, r.stderr
        mine, theirs = read(out), read(plain)
        assert len(mine["t"]) > 2 and {name: mine[name] for name in theirs} == theirs
