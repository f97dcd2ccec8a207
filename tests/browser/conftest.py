"""Real-browser tests: Debian's Chromium driven by Python Playwright (no browser download).

The browser and the ``page`` fixture live in ``tests/conftest.py``: one Chromium a session,
shared by every folder's browser tests (a second Playwright in the same worker fails:
"Sync API inside the asyncio loop"). Screenshots go to ``test-artifacts/``.
"""
