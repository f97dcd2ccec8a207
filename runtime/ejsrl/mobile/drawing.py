"""Shapes to draw a mobile robot's world with the 2D panel's existing kinds (polygons,
traces, point sets): covariance ellipses, a vehicle outline, a laser scan's rays."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ._util import Array

__all__ = ["ellipse_points", "vehicle_outline", "chi2_2dof"]


def chi2_2dof(confidence: float) -> float:
    """The chi-squared value with 2 degrees of freedom for ``confidence`` (0-1):
    ``-2 ln(1 - confidence)`` (exact for 2 degrees of freedom)."""
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be between 0 and 1, got {confidence!r}")
    return -2.0 * math.log(1.0 - confidence)


def ellipse_points(P: ArrayLike, centre: ArrayLike = (0.0, 0.0), *, confidence: float | None = None,
                   scale: float = 1.0, n: int = 64) -> Array:
    """Points (n + 1, 2) of the ellipse ``(p - c)^T P^-1 (p - c) = s^2`` (closed: the last
    point is the first) for the (2, 2) covariance P (the top-left 2x2 of a pose covariance
    is used if larger): ``s = scale``, or the chi-squared radius holding ``confidence`` of a
    Gaussian. A singular P gives a segment or a point."""
    P = np.asarray(P, dtype=float)[:2, :2]
    s = math.sqrt(chi2_2dof(confidence)) if confidence is not None else float(scale)
    w, V = np.linalg.eigh(0.5 * (P + P.T))
    w = np.sqrt(np.clip(w, 0.0, None))
    t = np.linspace(0.0, 2.0 * math.pi, n + 1)
    circle = np.vstack((np.cos(t), np.sin(t)))
    pts = (V @ (s * w[:, None] * circle)).T
    pts[-1] = pts[0]
    return pts + np.asarray(centre, dtype=float)[:2]


def vehicle_outline(x: ArrayLike, length: float = 1.0, width: float | None = None) -> Array:
    """A vehicle at pose x = (x, y, theta) as a triangle (3, 2) pointing along its heading:
    ``length`` (m) from tail to nose, ``width`` (default half the length)."""
    x0, y0, th = (float(v) for v in np.asarray(x, dtype=float)[:3])
    w = 0.5 * length if width is None else float(width)
    body = np.array([[0.6 * length, 0.0], [-0.4 * length, 0.5 * w], [-0.4 * length, -0.5 * w]])
    c, s = math.cos(th), math.sin(th)
    return body @ np.array([[c, s], [-s, c]]) + [x0, y0]
