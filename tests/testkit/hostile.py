"""Specs a careless or hostile author writes, shared by the tests that check each is handled."""

from __future__ import annotations

#: an ``init:`` that never ends (spec lines 11-12 loop)
ENDLESS_INIT = """\
ejs: 1
title: Endless
model:
  variables:
    t: 0.0
    dt: 0.1
    x: 1.0
    n: 0
  init: |
    x = 1.0
    while x > 0:
        n = n + 1
  evolution:
    - ode:
        equations:
          x: -x
view: []
"""
