"""Running a generated app: in the browser (viser) or headless.

- ``ejsrl.app._loop``: ``App`` (the model, one lock, one loop: stepping, realtime pacing,
  changes from the view, serving), ``SimConfig``, ``AppMeta``, ``load_app``;
- ``ejsrl.app._sessions``: ``Classroom``, serving a simulation per browser tab (sessions
  kept for a reload, a limit, a slow tab dropped), stepped by ``ejsrl.app._scheduler``'s
  bounded, fair pool of stepper threads;
- ``ejsrl.app.headless``: ``run_headless`` and the CSV columns;
- ``ejsrl.app._assets``: ``app_assets(__file__)``, the ``asset(name)`` of a generated app
  (the files its spec lists under ``assets:``, wherever it runs; a ``.pyz``'s extracted
  once into a per-user cache by ``bundle_assets``);
- ``ejsrl.app.cli``: ``main(Model, VIEW, ...)``, what a generated ``app.py`` calls: the
  command line of the language's last section (``--host``, ``--port``, ``--shared``,
  ``--max-sessions N``, ``--grace SECONDS``, ``--headless
  --duration T [--csv FILE] [--vars a,b,q] [--every N] [--set NAME=VALUE ...]``), and
  stopping cleanly on SIGINT/SIGTERM.
"""

from __future__ import annotations

from ejsrl.app._assets import app_assets, bundle_assets
from ejsrl.app._loop import App, AppMeta, SimConfig, load_app
from ejsrl.app.cli import main, parse_set
from ejsrl.app.headless import csv_columns

__all__ = ["App", "SimConfig", "AppMeta", "main", "parse_set", "csv_columns", "load_app", "app_assets", "bundle_assets"]
