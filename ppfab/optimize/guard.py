"""Reject Levenberg–Marquardt steps that would fold or collapse the mesh.

A step is refused (and undone; the damping grows) when it produces a
non-finite coordinate, turns a face over (its diagonal normal
``(c2 − c0) × (c3 − c1)`` reverses relative to the current state), folds the
mesh at an edge (the normals of the two faces at an interior edge, which point
the same way before the step, point in opposite directions after it: a cuspidal
edge builds up over several steps even when no single face turns over), creases
an edge (its dihedral angle grows beyond ``crease_limit``, in degrees: a fin
builds up long before it folds), makes a convex face non-convex, or shortens an
edge below ``min_edge_ratio`` times its input length.  This is what keeps second-order planarisers from diverging on
strongly non-planar meshes such as ``DOI__rot4_def1_sparse.obj``.
"""

from __future__ import annotations

import numpy as np

from ..metrics import nonconvex_faces


def _diag_normals(c: np.ndarray) -> np.ndarray:
    return np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])


def _cosines(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cosines of the angles between rows of ``a`` and ``b`` ``(E, 3)``."""
    den = np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1)
    return np.einsum("ij,ij->i", a, b) / np.where(den > 0, den, 1.0)


class StepGuard:
    """Checks a candidate vertex array against the current one.

    Parameters
    ----------
    faces : (F, 4) int
    edges : (E, 2) int, unique undirected edges
    vertices0 : (N, 3) float, input vertices (reference edge lengths)
    min_edge_ratio : smallest allowed edge length / input edge length
    edge_faces : (E, 2) int, faces on either side of each edge (``-1`` on the boundary)
    crease_limit : largest dihedral angle (degrees) a step may grow an edge to, or ``None`` (no crease check)
    """

    REASONS = ("nan", "flip", "fold", "crease", "nonconvex", "collapse")

    def __init__(self, faces: np.ndarray, edges: np.ndarray, vertices0: np.ndarray, min_edge_ratio: float = 0.2,
                 edge_faces: np.ndarray | None = None, crease_limit: float | None = None):
        self.faces = np.asarray(faces, dtype=np.int64)
        self.edges = np.asarray(edges, dtype=np.int64)
        ef = np.zeros((0, 2), dtype=np.int64) if edge_faces is None else np.asarray(edge_faces, dtype=np.int64)
        self.edge_faces = ef[(ef >= 0).all(axis=1)]
        self.crease_cos = None if crease_limit is None or crease_limit >= 180 else np.cos(np.radians(crease_limit))
        self.min_len = min_edge_ratio * np.linalg.norm(vertices0[self.edges[:, 1]] - vertices0[self.edges[:, 0]],
                                                       axis=1)

    def check(self, current: np.ndarray, candidate: np.ndarray) -> str:
        """``''`` when the step is acceptable, otherwise the reason
        (``nan``, ``flip``, ``fold``, ``crease``, ``nonconvex``, ``collapse``)."""
        if not np.all(np.isfinite(candidate)):
            return "nan"
        c_old = current[self.faces]
        c_new = candidate[self.faces]
        n_old, n_new = _diag_normals(c_old), _diag_normals(c_new)
        if np.any(np.einsum("ij,ij->i", n_old, n_new) <= 0):
            return "flip"
        if len(self.edge_faces):
            a, b = self.edge_faces.T
            before = np.einsum("ij,ij->i", n_old[a], n_old[b]) > 0
            after = np.einsum("ij,ij->i", n_new[a], n_new[b]) > 0
            if np.any(before & ~after):
                return "fold"
            if self.crease_cos is not None:
                cos_old = _cosines(n_old[a], n_old[b])
                cos_new = _cosines(n_new[a], n_new[b])
                if np.any((cos_new < self.crease_cos) & (cos_new < cos_old - 1e-12)):
                    return "crease"
        if np.any(nonconvex_faces(c_new) & ~nonconvex_faces(c_old)):
            return "nonconvex"
        e = self.edges
        if np.any(np.linalg.norm(candidate[e[:, 1]] - candidate[e[:, 0]], axis=1) < self.min_len):
            return "collapse"
        return ""
