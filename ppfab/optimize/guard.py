"""Reject Levenberg–Marquardt steps that would fold or collapse the mesh.

A step is refused (and undone; the damping grows) when it produces a
non-finite coordinate, turns a face over (its diagonal normal
``(c2 − c0) × (c3 − c1)`` reverses relative to the current state), folds the
mesh at an edge (the normals of the two faces at an interior edge, which point
the same way before the step, point in opposite directions after it: a cuspidal
edge builds up over several steps even when no single face turns over), makes a
convex face non-convex, or shortens an edge below ``min_edge_ratio`` times its
input length.  This is what keeps second-order planarisers from diverging on
strongly non-planar meshes such as ``DOI__rot4_def1_sparse.obj``.
"""

from __future__ import annotations

import numpy as np

from ..metrics import nonconvex_faces


def _diag_normals(c: np.ndarray) -> np.ndarray:
    return np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])


class StepGuard:
    """Checks a candidate vertex array against the current one.

    Parameters
    ----------
    faces : (F, 4) int
    edges : (E, 2) int, unique undirected edges
    vertices0 : (N, 3) float, input vertices (reference edge lengths)
    min_edge_ratio : smallest allowed edge length / input edge length
    """

    def __init__(self, faces: np.ndarray, edges: np.ndarray, vertices0: np.ndarray, min_edge_ratio: float = 0.2,
                 edge_faces: np.ndarray | None = None):
        self.faces = np.asarray(faces, dtype=np.int64)
        self.edges = np.asarray(edges, dtype=np.int64)
        ef = np.zeros((0, 2), dtype=np.int64) if edge_faces is None else np.asarray(edge_faces, dtype=np.int64)
        self.edge_faces = ef[(ef >= 0).all(axis=1)]
        self.min_len = min_edge_ratio * np.linalg.norm(vertices0[self.edges[:, 1]] - vertices0[self.edges[:, 0]],
                                                       axis=1)

    def check(self, current: np.ndarray, candidate: np.ndarray) -> str:
        """``''`` when the step is acceptable, otherwise the reason
        (``nan``, ``flip``, ``fold``, ``nonconvex``, ``collapse``)."""
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
        if np.any(nonconvex_faces(c_new) & ~nonconvex_faces(c_old)):
            return "nonconvex"
        e = self.edges
        if np.any(np.linalg.norm(candidate[e[:, 1]] - candidate[e[:, 0]], axis=1) < self.min_len):
            return "collapse"
        return ""
