"""``python -m ejsgen`` is the ``ejsgen`` command, also from the root of a source checkout.

From the checkout's root, ``python3 -m ejsgen`` imports the checkout's ``ejsgen/`` (the
current folder comes first on ``sys.path``), whatever was installed: a wheel, which carries
``ejsgen.templates``, ``ejsgen.specs`` and ``ejsrl`` inside it, or nothing. The checkout
keeps those in ``templates/``, ``specs/`` and ``runtime/ejsrl`` (``pyproject.toml`` maps them
into the distribution), so they are mapped here the same way, and the checkout's code runs
as one piece instead of failing with ``No module named 'ejsgen.templates'``.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path


def _map_checkout() -> None:
    """Map a checkout's ``templates/``, ``specs/`` and ``runtime/ejsrl`` as the wheel does, when needed."""
    import ejsgen

    here = Path(ejsgen.__file__).resolve().parent
    root = here.parent
    if (here / "templates").is_dir() or not (root / "templates" / "__init__.py").is_file():
        return  # an installed package: it carries its templates
    if importlib.util.find_spec("ejsgen.templates") is not None:
        return  # an editable install maps them already
    for name, folder in (("ejsgen.templates", root / "templates"), ("ejsgen.specs", root / "specs")):
        spec = importlib.util.spec_from_file_location(name, folder / "__init__.py", submodule_search_locations=[str(folder)])
        if spec is None or spec.loader is None:
            continue
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        setattr(ejsgen, name.rsplit(".", 1)[1], module)
    runtime = root / "runtime"
    if (runtime / "ejsrl" / "__init__.py").is_file() and "ejsrl" not in sys.modules:
        sys.path.insert(0, str(runtime))  # the checkout's runtime, in step with its compiler


_map_checkout()

from ejsgen.cli import main  # noqa: E402 - after the checkout's folders are mapped

sys.exit(main())
