"""The distribution maps every package folder on disk, and ships the templates."""

from __future__ import annotations

import tomllib
from pathlib import Path

from testkit import ROOT


def test_every_package_folder_is_listed_in_pyproject() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(config["packages"])
    dirs = config["package-dir"]
    on_disk = set()
    for package, folder in dirs.items():
        base = ROOT / folder
        for init in base.rglob("__init__.py"):
            rel = init.parent.relative_to(base)
            if "__pycache__" in rel.parts:
                continue
            on_disk.add(".".join((package, *rel.parts)) if rel.parts else package)
    assert on_disk == listed


def test_templates_are_package_data() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert "*.j2" in config["package-data"]["ejsgen.templates"]
    assert sorted(p.name for p in (ROOT / "templates").glob("*.j2")) == ["README.md.j2", "app.py.j2", "bundle_main.py.j2", "requirements.txt.j2"]


def test_readme_starts_with_the_two_commands_and_ci_runs_the_second() -> None:
    lines = (ROOT / "README.md").read_text().splitlines()
    block = lines[lines.index("```") + 1 : lines.index("```") + 3]
    assert "ejsgen run examples/" in block[0]
    second = block[1].split("#")[0].strip()
    assert second in (ROOT / ".ci" / "run").read_text()


def test_the_suite_imports_the_installed_package() -> None:
    """ejsgen and ejsrl come from the installed distribution, templates and documents included.

    CI installs the wheel (``scripts/setup.sh`` without ``--editable``) and runs ``python3 -P``:
    then neither package may be read from this checkout, so the suite tests what students get.
    With an editable install (``direct_url.json`` says so) the packages resolve into the checkout;
    either way the templates and documents must be reachable as package resources.
    """
    import json
    from importlib import metadata, resources

    import ejsgen
    import ejsrl

    assert resources.files("ejsgen.templates").joinpath("app.py.j2").is_file()
    assert resources.files("ejsgen.specs").joinpath("language.md").is_file()
    origin = json.loads(metadata.distribution("ejsgen").read_text("direct_url.json") or "{}")
    if not origin.get("dir_info", {}).get("editable", False):
        for module in (ejsgen, ejsrl):
            where = Path(module.__file__).resolve()
            assert not where.is_relative_to(ROOT), f"{module.__name__} was imported from the checkout: {where}"
