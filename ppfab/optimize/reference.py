"""Closest points on a reference quad surface (for the surface closeness term).

The reference is the input mesh, each quad split along its diagonal ``0–2``.
Candidate triangles come from a k-d tree of triangle centroids; the exact
closest point on each candidate is computed in one vectorised pass
(Ericson, *Real-Time Collision Detection*, §5.1.5).  The returned normal is
interpolated: the vertex normals of the reference (normalised sums of the unit
normals of the quads around each vertex) blended with the barycentric
coordinates of the foot point in its triangle and normalised.  It is therefore
continuous across edges and vertices, where the closest triangle is not unique
(every input vertex is its own foot point and lies on up to eight triangles),
so the result does not depend on how such ties are broken.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


def closest_on_triangles(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Closest points ``(..., 3)`` on triangles ``abc`` to points ``p`` (all broadcast ``(..., 3)``)."""
    ab, ac, ap = b - a, c - a, p - a
    d1 = np.einsum("...i,...i", ab, ap)
    d2 = np.einsum("...i,...i", ac, ap)
    bp = p - b
    d3 = np.einsum("...i,...i", ab, bp)
    d4 = np.einsum("...i,...i", ac, bp)
    cp = p - c
    d5 = np.einsum("...i,...i", ab, cp)
    d6 = np.einsum("...i,...i", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    # the foot as a + s·ab + t·ac, region by region (later regions take precedence, as in Ericson's order)
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        s = np.where(denom != 0, vb / denom, 0.0)                                  # interior
        t = np.where(denom != 0, vc / denom, 0.0)
        t_ab = np.clip(d1 / np.where(d1 - d3 != 0, d1 - d3, 1.0), 0, 1)
        t_ac = np.clip(d2 / np.where(d2 - d6 != 0, d2 - d6, 1.0), 0, 1)
        t_bc = np.clip((d4 - d3) / np.where((d4 - d3) + (d5 - d6) != 0, (d4 - d3) + (d5 - d6), 1.0), 0, 1)
    on_bc = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
    s = np.where(on_bc, 1.0 - t_bc, s)
    t = np.where(on_bc, t_bc, t)
    on_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    s = np.where(on_ac, 0.0, s)
    t = np.where(on_ac, t_ac, t)
    on_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    s = np.where(on_ab, t_ab, s)
    t = np.where(on_ab, 0.0, t)
    at_c = (d6 >= 0) & (d5 <= d6)
    s = np.where(at_c, 0.0, s)
    t = np.where(at_c, 1.0, t)
    at_b = (d3 >= 0) & (d4 <= d3)
    s = np.where(at_b, 1.0, s)
    t = np.where(at_b, 0.0, t)
    at_a = (d1 <= 0) & (d2 <= 0)
    s = np.where(at_a, 0.0, s)
    t = np.where(at_a, 0.0, t)
    return a + s[..., None] * ab + t[..., None] * ac


class ReferenceSurface:
    """The input quad mesh as a surface to stay close to.

    Parameters
    ----------
    vertices : (N, 3) float
    faces : (F, 4) int quads, or (F, 3) int triangles (a designer's triangle mesh)
    candidates : number of nearest triangles (by centroid) examined per query point
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, candidates: int = 8):
        v = np.asarray(vertices, dtype=float)
        f = np.asarray(faces, dtype=np.int64)
        if f.shape[1] == 3:
            self.tri = f
            self.quad_of = np.arange(len(f))
            n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        else:
            self.tri = np.concatenate([f[:, [0, 1, 2]], f[:, [0, 2, 3]]])
            self.quad_of = np.concatenate([np.arange(len(f)), np.arange(len(f))])
            n = np.cross(v[f[:, 2]] - v[f[:, 0]], v[f[:, 3]] - v[f[:, 1]])
        self.corners = v[self.tri]                                  # (2F, 3, 3)
        self.quad_normals = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        vn = np.zeros_like(v)
        np.add.at(vn, f.ravel(), np.repeat(self.quad_normals, f.shape[1], axis=0))
        self.vertex_normals = vn / np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-300)
        self.tree = cKDTree(self.corners.mean(axis=1))
        self.k = min(candidates, len(self.tri))

    def closest(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Foot points ``(M, 3)`` and unit normals ``(M, 3)`` of ``points (M, 3)``."""
        p = np.asarray(points, dtype=float)
        _, cand = self.tree.query(p, k=self.k)
        cand = cand.reshape(len(p), -1)
        c = self.corners[cand]                                      # (M, k, 3, 3)
        foot = closest_on_triangles(p[:, None, :], c[..., 0, :], c[..., 1, :], c[..., 2, :])
        best = np.argmin(np.linalg.norm(foot - p[:, None, :], axis=-1), axis=1)
        rows = np.arange(len(p))
        tri = cand[rows, best]
        x = foot[rows, best]
        a, b, c = (self.corners[tri, k] for k in range(3))
        w = barycentric(x, a, b, c)
        n = np.einsum("mk,mki->mi", w, self.vertex_normals[self.tri[tri]])
        n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        return x, n


def barycentric(x: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Barycentric coordinates ``(M, 3)`` of points ``x (M, 3)`` in triangles ``abc`` (each ``(M, 3)``),
    clipped to the triangle (degenerate triangles: the first vertex)."""
    v0, v1, v2 = b - a, c - a, x - a
    d00 = np.einsum("ij,ij->i", v0, v0)
    d01 = np.einsum("ij,ij->i", v0, v1)
    d11 = np.einsum("ij,ij->i", v1, v1)
    d20 = np.einsum("ij,ij->i", v2, v0)
    d21 = np.einsum("ij,ij->i", v2, v1)
    den = d00 * d11 - d01 * d01
    ok = den > 0
    den = np.where(ok, den, 1.0)
    wb = np.where(ok, (d11 * d20 - d01 * d21) / den, 0.0)
    wc = np.where(ok, (d00 * d21 - d01 * d20) / den, 0.0)
    w = np.clip(np.stack([1.0 - wb - wc, wb, wc], axis=1), 0.0, 1.0)
    return w / w.sum(axis=1, keepdims=True)
