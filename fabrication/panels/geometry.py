"""Panel geometry, vectorised over all faces: planes, flat frames, insets, shape measures.

Every function works on stacks: ``corners (F, 4, 3)``, flat polygons ``(F, k, 2)``.

* Plane of a face: the least-squares plane of its four corners (``ppfab.planes.fit_plane``),
  oriented by the face's corner order (normal along ``(c2 − c0) × (c3 − c1)``, the same
  orientation as ``QuadMesh.face_planes``).  The panel's planarity deviation is the largest
  distance of a corner from that plane (mm).
* Flat frame: an orthonormal frame ``(origin, X, Y, N)`` with ``N`` the outside normal,
  ``X`` along the projected reference edge ``c0 → c1`` and ``Y = N × X``; or (:func:`min_area_frames`)
  turned in the plane so that the outline's minimum-area rectangle is axis-aligned.  The map
  ``p ↦ ((p − origin)·X, (p − origin)·Y)`` is an exact isometry of the face plane onto R²,
  and ``(x, y) ↦ origin + x X + y Y`` its inverse, so the flat outline maps back to 3D.
* Inset: every edge line is moved inwards by ``δ`` in the plane (mitred offset) and
  consecutive lines are intersected: with inward unit normals ``a_k`` and offsets
  ``b_k = a_k·q_k + δ`` the new corner ``k`` solves ``a_{k−1}·x = b_{k−1}``, ``a_k·x = b_k``.
  The inset collapses when an edge shrinks to zero or reverses.
"""

from __future__ import annotations

import numpy as np

from ppfab import planes as pl
from ppfab.metrics import polygon_area as polygon_area   # signed shoelace areas, (F, k, 2) → (F,)


def oriented_planes(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares planes of quads, oriented by corner order, and the corner deviation.

    Parameters
    ----------
    corners : (F, k, 3) float

    Returns
    -------
    planes : (F, 4) unit planes ``n·x + d = 0`` with ``n·((c2 − c0) × (c3 − c1)) >= 0``
    deviation : (F,) largest distance of a corner from its plane
    """
    c = np.asarray(corners, dtype=float)
    planes, deviation = pl.fit_plane(c)
    k = c.shape[-2]
    ref = np.cross(c[..., 2 % k, :] - c[..., 0, :], c[..., 3 % k, :] - c[..., 1, :])
    sign = np.where(np.einsum("...i,...i->...", planes[..., :3], ref) < 0, -1.0, 1.0)
    return planes * sign[..., None], deviation


def edge_vectors(q: np.ndarray) -> np.ndarray:
    """Edges ``q[k+1] − q[k]`` of closed polygons, same shape as ``q``."""
    return np.roll(q, -1, axis=-2) - q


def perimeter(q: np.ndarray) -> np.ndarray:
    """Perimeters ``(F,)`` of closed polygons ``(F, k, d)``."""
    return np.linalg.norm(edge_vectors(q), axis=-1).sum(axis=-1)


def corner_angles(q: np.ndarray) -> np.ndarray:
    """Interior angles ``(F, k)`` in radians of counter-clockwise polygons ``(F, k, 2)`` (reflex > π)."""
    e_in = q - np.roll(q, 1, axis=-2)          # edge arriving at corner k
    e_out = edge_vectors(q)                     # edge leaving corner k
    cross = e_in[..., 0] * e_out[..., 1] - e_in[..., 1] * e_out[..., 0]
    dot = np.einsum("...i,...i->...", e_in, e_out)
    turn = np.arctan2(cross, dot)               # left turn > 0 on a CCW polygon
    return np.pi - turn


def inset_polygons(q: np.ndarray, delta: float) -> tuple[np.ndarray, np.ndarray]:
    """Mitred inward offset by ``delta`` of counter-clockwise polygons ``(F, k, 2)``.

    Returns
    -------
    inset : (F, k, 2) new corners (corner ``k`` from the lines of edges ``k−1`` and ``k``)
    shrink : (F,) smallest ratio ``new edge · old edge / |old edge|²`` over the edges; the inset
        is valid when it is > 0 (an edge that vanished or reversed gives <= 0)
    """
    q = np.asarray(q, dtype=float)
    e = edge_vectors(q)
    length = np.linalg.norm(e, axis=-1)
    safe = np.where(length == 0, 1.0, length)
    a = np.stack([-e[..., 1], e[..., 0]], axis=-1) / safe[..., None]   # inward normal of a CCW polygon
    b = np.einsum("...i,...i->...", a, q) + delta
    a_prev, b_prev = np.roll(a, 1, axis=-2), np.roll(b, 1, axis=-1)
    det = a_prev[..., 0] * a[..., 1] - a_prev[..., 1] * a[..., 0]
    det_safe = np.where(np.abs(det) < 1e-12, np.nan, det)
    x = (b_prev * a[..., 1] - b * a_prev[..., 1]) / det_safe
    y = (a_prev[..., 0] * b - a[..., 0] * b_prev) / det_safe
    inset = np.stack([x, y], axis=-1)
    e_new = edge_vectors(inset)
    ratio = np.einsum("...i,...i->...", e_new, e) / safe ** 2
    shrink = np.where(np.all(np.isfinite(inset), axis=(-1, -2)), np.nanmin(ratio, axis=-1), -np.inf)
    return inset, shrink


def flat_frames(corners: np.ndarray, planes: np.ndarray, outside: np.ndarray) -> tuple[np.ndarray, ...]:
    """Provisional flat frames of faces: centroid origin, ``X`` along the projected edge ``c0 → c1``.

    Parameters
    ----------
    corners : (F, k, 3), ordered counter-clockwise about the outside normal; planes : (F, 4)
        oriented unit planes; outside : (F,) ±1, the outside normal is ``N = outside · n``.

    Returns
    -------
    origin, X, Y, N : each (F, 3); flat : (F, k, 2) coordinates of the corners projected to the plane
    """
    c = np.asarray(corners, dtype=float)
    n = planes[:, :3]
    N = n * outside[:, None]
    origin = c.mean(axis=1)
    origin = origin - (np.einsum("fi,fi->f", n, origin) + planes[:, 3])[:, None] * n
    e0 = c[:, 1] - c[:, 0]
    e0 = e0 - np.einsum("fi,fi->f", e0, N)[:, None] * N
    X = e0 / np.linalg.norm(e0, axis=1, keepdims=True)
    Y = np.cross(N, X)
    rel = c - origin[:, None, :]
    flat = np.stack([np.einsum("fki,fi->fk", rel, X), np.einsum("fki,fi->fk", rel, Y)], axis=-1)
    return origin, X, Y, N, flat


def min_area_rectangles(q: np.ndarray) -> np.ndarray:
    """Smallest enclosing rectangles ``(F, 3)``: ``(long side, short side, angle of long side in degrees)``.

    The optimum has a side on the convex hull; for the convex quads of a panel mesh
    every edge direction is tried (of directions within 1e-6 of the least area, the first edge's) (for non-convex outlines the hull edges are a subset,
    so the result is the same).
    """
    q = np.asarray(q, dtype=float)
    e = edge_vectors(q)
    ang = np.arctan2(e[..., 1], e[..., 0])                       # (F, k)
    c, s = np.cos(ang), np.sin(ang)
    px = q[:, None, :, 0] * c[:, :, None] + q[:, None, :, 1] * s[:, :, None]    # (F, dir, k)
    py = -q[:, None, :, 0] * s[:, :, None] + q[:, None, :, 1] * c[:, :, None]
    w = px.max(-1) - px.min(-1)
    h = py.max(-1) - py.min(-1)
    area = w * h
    # the first edge (from the reference corner) within 1e-6 of the least area: near-ties (opposite edges
    # almost parallel) are decided by corner order, which a rigid motion does not change
    best = np.argmax(area <= area.min(axis=1, keepdims=True) * (1 + 1e-6), axis=1)
    rows = np.arange(len(q))
    wb, hb, ab = w[rows, best], h[rows, best], np.degrees(ang[rows, best])
    long = np.maximum(wb, hb)
    short = np.minimum(wb, hb)
    angle = np.where(wb >= hb, ab, ab + 90.0)
    angle = (angle + 180.0) % 180.0
    return np.stack([long, short, angle], axis=-1)


def min_area_frames(origin: np.ndarray, X: np.ndarray, Y: np.ndarray,
                    outline: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Turn flat frames so each outline lies in its minimum-area rectangle ``[0, long] × [0, short]``.

    With ``θ`` the angle of the rectangle's long side (:func:`min_area_rectangles`) and ``m`` the
    lower-left corner of the turned outline, the new coordinates are ``q = R(−θ) p − m`` and the
    frame ``X' = cos θ X + sin θ Y``, ``Y' = −sin θ X + cos θ Y``, ``origin' = origin + m_x X' + m_y Y'``,
    so ``origin + p_x X + p_y Y = origin' + q_x X' + q_y Y'`` (the same 3D points, ``N`` unchanged).
    Of ``θ`` and ``θ + π`` the one leaving the reference corner (vertex 0) in the lower-left half is used.

    Parameters
    ----------
    origin, X, Y : (F, 3) frames; outline : (F, k, 2) coordinates in them

    Returns
    -------
    origin, X, Y : (F, 3) turned frames; outline : (F, k, 2) in them, corner order unchanged
    """
    theta = np.radians(min_area_rectangles(outline)[:, 2])

    def turned(t: np.ndarray) -> np.ndarray:
        c, s = np.cos(t), np.sin(t)
        return np.stack([c[:, None] * outline[..., 0] + s[:, None] * outline[..., 1],
                         -s[:, None] * outline[..., 0] + c[:, None] * outline[..., 1]], axis=-1)

    q = turned(theta)
    # of the two turns that lay the long side along x (θ, θ + 180°) take the one with the reference
    # corner in the lower-left half of the rectangle: a choice that a rigid motion does not change
    centre = 0.5 * (q.min(axis=1) + q.max(axis=1))
    flip = (q[:, 0, 0] - centre[:, 0]) + (q[:, 0, 1] - centre[:, 1]) > 0
    theta = np.where(flip, theta + np.pi, theta)
    q = turned(theta)
    c, s = np.cos(theta), np.sin(theta)
    m = q.min(axis=1)
    q = q - m[:, None, :]
    X2 = c[:, None] * X + s[:, None] * Y
    Y2 = -s[:, None] * X + c[:, None] * Y
    origin2 = origin + m[:, :1] * X2 + m[:, 1:2] * Y2
    return origin2, X2, Y2, q
