"""Pose-graph optimisation (graph SLAM) in the plane, as the Toolbox's ``PoseGraph``:
vertices are poses ``(x, y, theta)``, edges relative-pose measurements ``z_ij`` (the pose
of j in i's frame) with an information matrix; ``optimize()`` runs Gauss-Newton
(Grisetti et al., "A tutorial on graph-based SLAM", 2010) with the first pose held.

``PoseGraph.load(file)`` reads g2o (``VERTEX_SE2``, ``EDGE_SE2``) and TORO (``VERTEX2``,
``EDGE2``) files.
"""

from __future__ import annotations

import math
import os

import numpy as np
from numpy.typing import ArrayLike

from ._util import Array, wrap

__all__ = ["PoseGraph"]

# the six upper-triangle numbers of an edge's information matrix, as each format lists them
_G2O = [0, 1, 2, 1, 3, 4, 2, 4, 5]  # IXX IXY IXT IYY IYT ITT
_TORO = [0, 1, 4, 1, 2, 5, 4, 5, 3]  # IXX IXY IYY ITT IXT IYT


class PoseGraph:
    def __init__(self) -> None:
        self.names: list[str] = []
        self._index: dict[str, int] = {}
        self._poses: list[Array] = []
        self._edges: list[tuple[int, int, Array, Array]] = []

    # ------------------------------------------------------------------ building
    def add_vertex(self, pose: ArrayLike, name: str | None = None) -> int:
        """Add a pose (3,); returns its index."""
        name = str(len(self.names)) if name is None else str(name)
        if name in self._index:
            raise ValueError(f"a vertex named {name!r} is already in the graph")
        self._index[name] = len(self.names)
        self.names.append(name)
        self._poses.append(np.asarray(pose, dtype=float).reshape(3).copy())
        return len(self.names) - 1

    def add_edge(self, i: int, j: int, z: ArrayLike, info: ArrayLike | None = None) -> None:
        """Add the measurement z (3,) of pose j in pose i's frame, with information (3, 3)."""
        n = len(self.names)
        if not (0 <= i < n and 0 <= j < n):
            raise ValueError(f"an edge joins vertices 0..{n - 1}, got {i} and {j}")
        omega = np.eye(3) if info is None else np.asarray(info, dtype=float).reshape(3, 3)
        self._edges.append((int(i), int(j), np.asarray(z, dtype=float).reshape(3).copy(), omega))

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> "PoseGraph":
        """A graph from a g2o or TORO file (2D poses only)."""
        g = cls()
        with open(path) as f:
            for lineno, line in enumerate(f, 1):
                tok = line.split()
                if not tok or tok[0].startswith("#"):
                    continue
                kind = tok[0]
                try:
                    if kind in ("VERTEX_SE2", "VERTEX2"):
                        g.add_vertex([float(v) for v in tok[2:5]], tok[1])
                    elif kind in ("EDGE_SE2", "EDGE2"):
                        d = np.array([float(v) for v in tok[6:12]])
                        info = d[_G2O if kind == "EDGE_SE2" else _TORO].reshape(3, 3)
                        if tok[1] not in g._index or tok[2] not in g._index:
                            raise ValueError(f"an edge names an unknown vertex ({tok[1]} or {tok[2]})")
                        g.add_edge(g._index[tok[1]], g._index[tok[2]], [float(v) for v in tok[3:6]], info)
                except (ValueError, IndexError) as exc:
                    raise ValueError(f"{os.fspath(path)}:{lineno}: {exc}") from None
        return g

    @property
    def n(self) -> int:
        return len(self.names)

    @property
    def poses(self) -> Array:
        """The vertices' poses (n, 3)."""
        return np.array(self._poses).reshape(-1, 3)

    @property
    def edges(self) -> list[tuple[int, int]]:
        return [(i, j) for i, j, _, _ in self._edges]

    # ------------------------------------------------------------------ optimising
    def _linearise(self, X: Array) -> tuple[Array, Array, Array, Array, Array]:
        """Errors e (m, 3) and Jacobians A, B (m, 3, 3) of every edge at poses X."""
        I = np.array([e[0] for e in self._edges])
        J = np.array([e[1] for e in self._edges])
        Z = np.array([e[2] for e in self._edges])
        xi, xj = X[I], X[J]
        ci, si = np.cos(xi[:, 2]), np.sin(xi[:, 2])
        cz, sz = np.cos(Z[:, 2]), np.sin(Z[:, 2])
        dt = xj[:, :2] - xi[:, :2]
        # f_ij = Ti^-1 Tj; e = xyt(Zij^-1 f_ij)
        fx = ci * dt[:, 0] + si * dt[:, 1]
        fy = -si * dt[:, 0] + ci * dt[:, 1]
        fth = xj[:, 2] - xi[:, 2]
        ex = cz * (fx - Z[:, 0]) + sz * (fy - Z[:, 1])
        ey = -sz * (fx - Z[:, 0]) + cz * (fy - Z[:, 1])
        eth = np.arctan2(np.sin(fth - Z[:, 2]), np.cos(fth - Z[:, 2]))
        e = np.column_stack((ex, ey, eth))
        m = len(I)
        A = np.zeros((m, 3, 3))
        A[:, 0, 0], A[:, 0, 1] = -ci, -si
        A[:, 1, 0], A[:, 1, 1] = si, -ci
        A[:, 0, 2] = -si * dt[:, 0] + ci * dt[:, 1]
        A[:, 1, 2] = -ci * dt[:, 0] - si * dt[:, 1]
        A[:, 2, 2] = -1.0
        B = np.zeros((m, 3, 3))
        B[:, 0, 0], B[:, 0, 1], B[:, 1, 0], B[:, 1, 1], B[:, 2, 2] = ci, si, -si, ci, 1.0
        Rz = np.zeros((m, 3, 3))  # Zij^-1's rotation, as a 3x3 acting on (x, y, theta)
        Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1], Rz[:, 2, 2] = cz, sz, -sz, cz, 1.0
        return e, Rz @ A, Rz @ B, I, J

    def linearize_and_solve(self) -> float:
        """One Gauss-Newton step (the first pose held); returns the sum of the squared
        edge errors before it (the Toolbox's energy)."""
        from scipy import sparse
        from scipy.sparse.linalg import spsolve

        X = self.poses
        e, A, B, I, J = self._linearise(X)
        Om = np.array([ed[3] for ed in self._edges])
        At, Bt = np.swapaxes(A, 1, 2), np.swapaxes(B, 1, 2)
        Hii, Hij, Hjj = At @ Om @ A, At @ Om @ B, Bt @ Om @ B
        bi = -np.einsum("mij,mj->mi", At @ Om, e)
        bj = -np.einsum("mij,mj->mi", Bt @ Om, e)
        n = self.n
        r3, c3 = np.repeat(np.arange(3), 3), np.tile(np.arange(3), 3)
        rows, cols, vals = [], [], []
        for (p, q, blk) in ((I, I, Hii), (J, J, Hjj), (I, J, Hij), (J, I, np.swapaxes(Hij, 1, 2))):
            rows.append((3 * p[:, None] + r3).ravel())
            cols.append((3 * q[:, None] + c3).ravel())
            vals.append(blk.reshape(-1, 9).ravel())
        rows.append(r3)
        cols.append(c3)
        vals.append(np.eye(3).ravel())  # hold the first pose: relative measurements fix no frame
        H = sparse.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                              shape=(3 * n, 3 * n)).tocsr()
        b = np.zeros(3 * n)
        np.add.at(b, (3 * I[:, None] + np.arange(3)).ravel(), bi.ravel())
        np.add.at(b, (3 * J[:, None] + np.arange(3)).ravel(), bj.ravel())
        dx = spsolve(H, b).reshape(n, 3)
        X = X + dx
        X[:, 2] = wrap(X[:, 2])
        self._poses = list(X)
        self.chi2 = float(np.einsum("mi,mij,mj->", e, Om, e))
        return float(np.einsum("mi,mi->", e, e))

    def optimize(self, iterations: int = 10) -> list[float]:
        """Gauss-Newton steps until the energy stops falling (at most ``iterations``);
        returns the energy before each step."""
        if not self._edges:
            raise ValueError("the graph has no edges to optimise")
        out: list[float] = []
        prev = math.inf
        for _ in range(iterations):
            energy = self.linearize_and_solve()
            out.append(energy)
            if energy >= prev:
                break
            prev = energy
        return out
