"""Calls that may kill the interpreter, run in child interpreters that report each call."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Callable


def run_surviving_crashes(items: set[tuple], command: Callable[[set[tuple]], list[str]]) -> dict[tuple, dict]:
    """Run ``command(pending)`` (a child interpreter that prints one JSON line per call, first
    ``{"item": [...], "started": true}`` and then ``{"item": [...], ...its result}``) until every
    item has a record. A child that dies inside a call leaves ``{"crashed": exit code, "stderr":
    its end}`` for that item, and the next child goes on with the items left."""
    out: dict[tuple, dict] = {}
    pending = set(items)
    while pending:
        r = subprocess.run(command(pending), capture_output=True, text=True, timeout=600)
        started = None
        for line in r.stdout.splitlines():
            rec = json.loads(line)
            key = tuple(rec["item"])
            if rec.get("started"):
                started = key
            else:
                out[key], started = rec, None
        if started is not None:  # the child died inside this call
            out[started] = {"crashed": r.returncode, "stderr": r.stderr[-400:]}
        elif r.returncode != 0:
            raise AssertionError(f"the child failed outside a call: {r.stderr[-2000:]}")
        left = {k for k in pending if k not in out}
        if left == pending:
            raise AssertionError(f"the child reported none of its calls: {r.stdout[-500:]} {r.stderr[-500:]}")
        pending = left
    return out
