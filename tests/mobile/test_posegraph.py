"""Pose-graph optimisation: the Toolbox's example graph (pg1.g2o) optimises to the poses
the Toolbox's ``PoseGraph`` finds (recorded), and a square loop with consistent
measurements and a bad initial guess converges to the measured geometry exactly."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ejsrl import mobile as M

FIXTURES = Path(__file__).resolve().parent / "fixtures"


def test_pg1_optimises_to_the_toolbox_poses(rtb_ref) -> None:  # type: ignore[no-untyped-def]
    g = M.PoseGraph.load(FIXTURES / "pg1.g2o")
    assert g.n == 4 and g.edges == [(0, 1), (1, 2), (2, 3), (3, 0)]
    energy = g.optimize()
    np.testing.assert_allclose(g.poses, rtb_ref["posegraph_pg1"], atol=1e-8)
    assert energy[-1] < 1e-9 < energy[0]


def test_a_consistent_square_converges_to_its_measurements() -> None:
    rng = np.random.default_rng(5)
    true = np.array([[0, 0, 0], [4, 0, math.pi / 2], [4, 4, math.pi], [0, 4, -math.pi / 2]], dtype=float)
    g = M.PoseGraph()
    for k, x in enumerate(true):
        g.add_vertex(x + (rng.normal(0, 0.3, 3) if k else 0.0))
    for i in range(4):
        j = (i + 1) % 4
        Ti, Tj = M.SE2(*true[i]), M.SE2(*true[j])
        g.add_edge(i, j, (Ti.inv() * Tj).xyt(), np.diag([100.0, 100.0, 400.0]))
    g.optimize(20)
    np.testing.assert_allclose(g.poses, true, atol=1e-9)
    assert g.chi2 < 1e-12


def test_load_names_the_bad_line(tmp_path) -> None:  # type: ignore[no-untyped-def]
    f = tmp_path / "bad.g2o"
    f.write_text("VERTEX_SE2 1 0 0 0\nEDGE_SE2 1 7 1 0 0 1 0 0 1 0 1\n")
    with pytest.raises(ValueError, match=r"bad.g2o:2: an edge names an unknown vertex"):
        M.PoseGraph.load(f)
