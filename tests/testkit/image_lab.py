"""A lab whose image element shows a picture that changes every frame (the image element's tests:
tests/view/test_image_reveal.py, tests/browser/test_image_console.py)."""

from __future__ import annotations

#: the spec: a 64 x 48 picture whose green changes with u (du/dt = 1), a 3D scene, playing from the start
CHANGING = """
ejs: 1
title: A picture that changes
model:
  variables:
    t: 0.0
    dt: 0.05
    u: 0.0
  evolution:
    - ode:
        equations: {u: 1}
view:
  - image: {source: "np.full((48, 64, 3), [0, int(u*50) % 255, 0], dtype=np.uint8)", label: Picture}
  - scene:
      - sphere: {position: [0, 0, 0], radius: 0.3, color: gray}
simulation:
  autoplay: true
"""
