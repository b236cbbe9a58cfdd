"""Self-intersections of a quad mesh: pairs of faces that are not neighbours but meet.

A gridshell whose surface passes through itself cannot be built, yet every local check (planar faces,
planar polylines, no fold between neighbours) passes on it.  :func:`self_intersections` finds the
pairs of faces that share no corner (corners at the same position count as shared, so a seam where a
closed surface was cut open is not a meeting) and still meet: each quad is split into the triangles
``(c0, c1, c2)`` and ``(c0, c2, c3)``; candidate pairs are faces whose bounding boxes overlap (found
with a k-d tree on the face centres); a pair of triangles meets when an edge of one crosses the other
(Möller–Trumbore, inclusive within a relative tolerance, so faces that only touch count) or, for
triangles in one plane, when their outlines cross or one lies inside the other.

Examples
--------
>>> import numpy as np
>>> from ppfab.mesh import QuadMesh
>>> v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
...               [0.5, 0.5, -1], [0.5, 0.5, 1], [0.6, 0.6, 1], [0.6, 0.6, -1.0]])
>>> self_intersections(QuadMesh(v, np.array([[0, 1, 2, 3], [4, 5, 6, 7]]))).tolist()
[[0, 1]]
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .mesh import QuadGrid, QuadMesh, as_quadmesh

_CHUNK = 100_000


def self_intersections(mesh: QuadMesh | QuadGrid, rtol: float = 1e-9) -> np.ndarray:
    """``(K, 2)`` int, the pairs ``(f, g)``, ``f < g``, of faces that share no corner position but meet.

    Parameters
    ----------
    mesh : any quad mesh, ``vertices (N, 3)``, ``faces (F, 4)``
    rtol : tolerance relative to the bounding-box diagonal (faces closer than this meet)
    """
    qm = as_quadmesh(mesh)
    v = np.asarray(qm.vertices, dtype=float)
    f = np.asarray(qm.faces, dtype=np.int64)
    if len(f) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    size = float(np.linalg.norm(np.ptp(v, axis=0))) or 1.0
    eps = rtol * size
    _, weld = np.unique(np.round(v / eps), axis=0, return_inverse=True)
    wf = weld.ravel()[f]                                             # (F, 4) corners by position
    c = v[f]
    lo, hi = c.min(axis=1) - eps, c.max(axis=1) + eps
    centre, half = 0.5 * (lo + hi), 0.5 * np.linalg.norm(hi - lo, axis=1)
    pairs = cKDTree(centre).query_pairs(2.0 * float(half.max()), output_type="ndarray")
    if len(pairs) == 0:
        return np.zeros((0, 2), dtype=np.int64)
    a, b = pairs[:, 0], pairs[:, 1]
    keep = np.all((lo[a] <= hi[b]) & (lo[b] <= hi[a]), axis=1)
    keep &= ~(wf[a][:, :, None] == wf[b][:, None, :]).any(axis=(1, 2))
    a, b = a[keep], b[keep]
    tri = c[:, [[0, 1, 2], [0, 2, 3]]]                              # (F, 2, 3, 3)
    hits = []
    for s in range(0, len(a), _CHUNK):
        fa, fb = a[s:s + _CHUNK], b[s:s + _CHUNK]
        met = np.zeros(len(fa), dtype=bool)
        for ta in (0, 1):
            for tb in (0, 1):
                met |= triangles_meet(tri[fa, ta], tri[fb, tb], eps)
        hits.append(np.stack([fa[met], fb[met]], axis=1))
    out = np.concatenate(hits) if hits else np.zeros((0, 2), dtype=np.int64)
    out = np.sort(out, axis=1)
    return out[np.lexsort((out[:, 1], out[:, 0]))]


def triangles_meet(p: np.ndarray, q: np.ndarray, eps: float) -> np.ndarray:
    """``(M,)`` bool: triangles ``p[k]`` and ``q[k]`` (``(M, 3, 3)``) meet (within ``eps``)."""
    out = np.zeros(len(p), dtype=bool)
    for x, y in ((p, q), (q, p)):
        for k in range(3):
            out |= _segment_hits(x[:, k], x[:, (k + 1) % 3], y, eps)
    coplanar = _coplanar(p, q, eps)
    if np.any(coplanar):
        idx = np.flatnonzero(coplanar & ~out)
        out[idx] = _coplanar_meet(p[idx], q[idx], eps)
    return out


def _segment_hits(s0: np.ndarray, s1: np.ndarray, t: np.ndarray, eps: float) -> np.ndarray:
    """Segments ``s0 → s1`` (``(M, 3)``) crossing triangles ``t`` (``(M, 3, 3)``), Möller–Trumbore; segments
    parallel to their triangle's plane are left to the coplanar test."""
    d = s1 - s0
    e1, e2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    h = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, h)
    scale = np.linalg.norm(d, axis=1) * np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1)
    ok = np.abs(det) > 1e-12 * np.maximum(scale, 1e-300)
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    r = s0 - t[:, 0]
    u = inv * np.einsum("ij,ij->i", r, h)
    qv = np.cross(r, e1)
    w = inv * np.einsum("ij,ij->i", d, qv)
    par = inv * np.einsum("ij,ij->i", e2, qv)
    # tolerances in parameter space: eps over the lengths involved
    tu = eps / np.maximum(np.linalg.norm(e1, axis=1), 1e-300) + eps / np.maximum(np.linalg.norm(e2, axis=1), 1e-300)
    ts = eps / np.maximum(np.linalg.norm(d, axis=1), 1e-300)
    return ok & (u >= -tu) & (w >= -tu) & (u + w <= 1 + tu) & (par >= -ts) & (par <= 1 + ts)


def _coplanar(p: np.ndarray, q: np.ndarray, eps: float) -> np.ndarray:
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.linalg.norm(n, axis=1)
    n = n / np.maximum(length, 1e-300)[:, None]
    dist = np.einsum("ij,ikj->ik", n, q - p[:, :1])
    return (length > 0) & (np.abs(dist).max(axis=1) <= eps)


def _coplanar_meet(p: np.ndarray, q: np.ndarray, eps: float) -> np.ndarray:
    """Coplanar triangles (``(M, 3, 3)``): outlines crossing, or a corner of one inside the other (2D)."""
    n = np.abs(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]))
    drop = np.argmax(n, axis=1)
    keep = np.array([[1, 2], [0, 2], [0, 1]])[drop]                # project along the dominant normal axis
    p2 = np.take_along_axis(p, keep[:, None, :], axis=2)
    q2 = np.take_along_axis(q, keep[:, None, :], axis=2)
    out = np.zeros(len(p), dtype=bool)
    for i in range(3):
        for j in range(3):
            out |= _segments_cross_2d(p2[:, i], p2[:, (i + 1) % 3], q2[:, j], q2[:, (j + 1) % 3], eps)
    out |= _inside_2d(p2[:, 0], q2, eps) | _inside_2d(q2[:, 0], p2, eps)
    return out


def _cross2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]


def _segments_cross_2d(a0, a1, b0, b1, eps: float) -> np.ndarray:
    da, db = a1 - a0, b1 - b0
    den = _cross2(da, db)
    ok = np.abs(den) > 1e-300
    inv = np.where(ok, 1.0 / np.where(ok, den, 1.0), 0.0)
    r = b0 - a0
    s = _cross2(r, db) * inv
    t = _cross2(r, da) * inv
    ta = eps / np.maximum(np.linalg.norm(da, axis=1), 1e-300)
    tb = eps / np.maximum(np.linalg.norm(db, axis=1), 1e-300)
    return ok & (s >= -ta) & (s <= 1 + ta) & (t >= -tb) & (t <= 1 + tb)


def _inside_2d(x: np.ndarray, tri: np.ndarray, eps: float) -> np.ndarray:
    signs = []
    for k in range(3):
        e = tri[:, (k + 1) % 3] - tri[:, k]
        signs.append(_cross2(e, x - tri[:, k]) / np.maximum(np.linalg.norm(e, axis=1), 1e-300))
    s = np.stack(signs, axis=1)
    return np.all(s >= -eps, axis=1) | np.all(s <= eps, axis=1)
