"""Part orientations and exact polygon sliding (the geometry of nesting).

An :class:`Orient` is one allowed pose of a part: the outline rotated by ``rotation``
(after the mirror ``x ↦ −x`` when ``mirrored``) and shifted so its bounding box starts
at the origin.  Placing it with its box corner at ``(X, Y)`` is the placement
``x = X + shift[0]``, ``y = Y + shift[1]`` of :func:`fabrication.flatpart.place_points`.

Sliding: a polygon ``M`` moving along a unit direction ``d`` first touches a polygon
``F`` where a vertex of one meets an edge of the other.  For a vertex ``p`` and an edge
``a + u (b − a)``, ``p + t d = a + u e`` gives ``t = (a − p) × e / (d × e)`` and
``u = (a − p) × d / (d × e)``; the contact distance is the least ``t >= 0`` over
``u ∈ [0, 1]``, over the vertices of ``M`` against the edges of ``F`` and the vertices
of ``F`` against the edges of ``M`` (moving by ``−d``).  Spacing ``s`` is kept by sliding
against the *halo* of ``F`` (its outline offset by ``s``, mitred, which contains the true
offset), so first contact leaves a distance of at least ``s``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

HALO_EXTRA = 1e-3   # mm added to the spacing in halos: contacts never fall below the spacing by rounding


@dataclass(frozen=True, eq=False)
class Orient:
    """One pose of part ``part``: ``poly (k, 2)`` with bounding box ``[0, w] × [0, h]``."""

    part: int
    rotation: float
    mirrored: bool
    poly: np.ndarray
    shift: np.ndarray
    w: float
    h: float
    halo: np.ndarray


def rotate(points: np.ndarray, degrees: float, mirrored: bool = False) -> np.ndarray:
    """``R(degrees) · M · p`` for points ``(k, 2)`` (``M`` mirrors ``x`` when ``mirrored``)."""
    p = np.asarray(points, dtype=float)
    if mirrored:
        p = p * np.array([-1.0, 1.0])
    a = math.radians(degrees)
    c, s = math.cos(a), math.sin(a)
    if abs(degrees % 90.0) < 1e-12:       # exact quarter turns: no rounding noise
        c, s = round(c), round(s)
    return p @ np.array([[c, s], [-s, c]])


def ccw(points: np.ndarray) -> np.ndarray:
    """The polygon in counter-clockwise order (a mirrored outline turns clockwise)."""
    p = np.asarray(points, dtype=float)
    x, y = p[:, 0], p[:, 1]
    area2 = float(x[:-1] @ y[1:] - y[:-1] @ x[1:] + x[-1] * y[0] - y[-1] * x[0])
    return p if area2 >= 0 else p[::-1].copy()


def rotations_matrix(degrees: np.ndarray) -> np.ndarray:
    """Matrices ``(R, 2, 2)`` acting on row vectors: ``p @ M[r]`` is ``p`` turned by ``degrees[r]``."""
    a = np.radians(np.asarray(degrees, dtype=float))
    c, s = np.cos(a), np.sin(a)
    quarter = np.abs(np.asarray(degrees, dtype=float) % 90.0) < 1e-12      # exact quarter turns
    c, s = np.where(quarter, np.round(c), c), np.where(quarter, np.round(s), s)
    return np.stack([np.stack([c, s], -1), np.stack([-s, c], -1)], -2)


def halo(poly: np.ndarray, spacing: float) -> np.ndarray:
    """Outline offset outwards by ``spacing`` (mitred, limit 1.1: contains the round offset), ``(b, 2)``."""
    return halos([poly], spacing)[0]


def halos(polys: list[np.ndarray], spacing: float) -> list[np.ndarray]:
    """:func:`halo` of many outlines at once (one vectorised shapely call), each ``(b_i, 2)`` counter-clockwise.

    The halo of a rotated outline is the rotated halo, so a part's halo is made once and turned
    with each of its poses.
    """
    if spacing <= 0:
        return [ccw(p) for p in polys]
    import shapely

    geoms = [shapely.Polygon(p) for p in polys]
    out = shapely.buffer(np.array(geoms, dtype=object), spacing + HALO_EXTRA, join_style="mitre", mitre_limit=1.1)
    return [ccw(np.asarray(shapely.get_exterior_ring(g).coords, dtype=float)[:-1]) for g in out]


def convex_hull(outline: np.ndarray) -> np.ndarray:
    """Counter-clockwise convex hull ``(h, 2)`` of a polygon (the polygon itself when it is convex)."""
    p = np.asarray(outline, dtype=float)
    e_in = p - np.concatenate([p[-1:], p[:-1]])
    e_out = np.concatenate([p[1:], p[:1]]) - p
    if np.all(e_in[:, 0] * e_out[:, 1] - e_in[:, 1] * e_out[:, 0] >= 0):
        return p
    from shapely.geometry import MultiPoint

    return ccw(np.asarray(MultiPoint([tuple(q) for q in p]).convex_hull.exterior.coords, dtype=float)[:-1])


def hull_edge_angles(outline: np.ndarray, most: int = 8) -> list[float]:
    """Rotations (degrees, in [0, 360)) that lay a convex-hull edge of ``outline`` along +x.

    An edge ``e`` of a counter-clockwise hull laid along +x has the part above it (the edge at the
    bottom); ``+ 180°`` puts it on top.  Only the ``most`` longest hull edges are used.
    """
    hull = convex_hull(outline)
    e = np.concatenate([hull[1:], hull[:1]]) - hull
    keep = np.argsort(-np.hypot(e[:, 0], e[:, 1]), kind="stable")[:most]
    ang = (-np.degrees(np.arctan2(e[keep, 1], e[keep, 0]))) % 360.0
    return [float(a) for a in ang]


def free_angles(outline: np.ndarray) -> list[float]:
    """Rotations tried for a part that may turn freely, degrees in [0, 360).

    Every (longest) hull edge along +x at the bottom and at the top of the part, and the frame of
    the part's minimum-area rectangle in its four quarter turns (lying and standing).
    """
    edge = hull_edge_angles(outline)
    rect = min_rect_angle(outline)
    angles = edge + [(a + 180.0) % 360.0 for a in edge] + [(rect + 90.0 * k) % 360.0 for k in range(4)]
    return unique_angles(angles)


def min_rect_angle(outline: np.ndarray) -> float:
    """Rotation (degrees) that lays the long side of the minimum-area rectangle of ``outline`` along +x.

    The optimum has a side on the convex hull (Freeman & Shapira), so every hull edge direction is tried.
    """
    hull = convex_hull(outline)
    e = np.concatenate([hull[1:], hull[:1]]) - hull
    ang = np.arctan2(e[:, 1], e[:, 0])
    c, s = np.cos(ang), np.sin(ang)
    px = hull[None, :, 0] * c[:, None] + hull[None, :, 1] * s[:, None]
    py = -hull[None, :, 0] * s[:, None] + hull[None, :, 1] * c[:, None]
    w, h = np.ptp(px, axis=1), np.ptp(py, axis=1)
    k = int(np.argmin(w * h))
    a = -math.degrees(ang[k]) + (0.0 if w[k] >= h[k] else 90.0)
    return a % 360.0


def unique_angles(angles: list[float], tol: float = 1e-6) -> list[float]:
    """Angles modulo 360 without near-duplicates (within ``tol`` degrees), sorted."""
    out: list[float] = []
    for a in sorted(float(x) % 360.0 for x in angles):
        if not out or a - out[-1] > tol:
            out.append(a)
    if len(out) > 1 and out[0] + 360.0 - out[-1] <= tol:
        out.pop()
    return out


def orientations(part_index: int, outline: np.ndarray, rotations: list[float], mirror: bool,
                 spacing: float, part_halo: np.ndarray | None = None, dedupe: bool = True) -> list[Orient]:
    """All poses of a part (with ``dedupe``, duplicates of the same polygon removed).

    ``part_halo`` is the halo of ``outline`` (made here when not given); each pose's halo is it
    turned with the pose.  All rotations are applied at once (one matrix product per mirror side).
    """
    out: list[Orient] = []
    seen: set = set()
    hl = halo(outline, spacing) if part_halo is None else part_halo
    rots = np.array([float(r) % 360.0 for r in rotations])
    M = rotations_matrix(rots)
    for mirrored in ([False, True] if mirror else [False]):
        flip = np.array([-1.0, 1.0]) if mirrored else np.array([1.0, 1.0])
        P = np.einsum("kj,rji->rki", outline * flip, M)             # (R, k, 2)
        Hh = np.einsum("kj,rji->rki", hl * flip, M)
        lo = P.min(axis=1)
        P = P - lo[:, None, :]
        Hh = Hh - lo[:, None, :]
        size = P.max(axis=1)
        if mirrored:                                                  # mirroring reverses the orientation
            P, Hh = P[:, ::-1], Hh[:, ::-1]
        for r in range(len(rots)):
            if dedupe:                                                # the same point set = the same pose
                q = np.round(P[r], 6) + 0.0
                key = q[np.lexsort((q[:, 1], q[:, 0]))].tobytes()
                if key in seen:
                    continue
                seen.add(key)
            out.append(Orient(part_index, float(rots[r]), mirrored, P[r], -lo[r], float(size[r, 0]),
                              float(size[r, 1]), Hh[r]))
    return out


def pad(polys: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Stack polygons: edge starts (= vertices) and edge ends, each ``(P, kmax, 2)``; padding edges have length 0."""
    kmax = max(len(p) for p in polys)
    v = np.empty((len(polys), kmax, 2))
    nxt = np.empty((len(polys), kmax, 2))
    for i, p in enumerate(polys):
        k = len(p)
        v[i, :k] = p
        v[i, k:] = p[-1]
        nxt[i, :k - 1] = p[1:]
        nxt[i, k - 1] = p[0]
        nxt[i, k:] = p[-1]
    return v, nxt


def _ray_hits(p: np.ndarray, d: np.ndarray, a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
    """Least ``t`` at which point ``p`` moving along ``d`` enters polygon edge ``[a, b]``; inf if never.

    Only edges that face the motion count (``d · n < 0`` with ``n`` the outward normal of a
    counter-clockwise polygon's edge): a point leaving a polygon is never blocked.  A point up
    to ``tol`` behind a facing edge (rounding) is blocked at ``t = 0``.  Shapes broadcast ``(..., 2)``.
    """
    e = b - a
    den = d[..., 0] * e[..., 1] - d[..., 1] * e[..., 0]      # = d · (e_y, −e_x) = d · n
    ap = a - p
    t_num = ap[..., 0] * e[..., 1] - ap[..., 1] * e[..., 0]
    u_num = ap[..., 0] * d[..., 1] - ap[..., 1] * d[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = t_num / den
        u = u_num / den
    ok = (den < -1e-12) & (u >= -1e-9) & (u <= 1 + 1e-9) & (t >= -tol)
    return np.where(ok, np.maximum(t, 0.0), np.inf)


def slide_distance(moving: np.ndarray, fixed: list[np.ndarray], direction: tuple[float, float],
                   tol: float = 0.01) -> float:
    """How far polygon ``moving (k, 2)`` can travel along ``direction`` before touching any of ``fixed``.

    ``fixed`` are counter-clockwise polygons (halos, to keep spacing), not overlapping ``moving``
    at the start (callers start beyond the halos' extent).  Returns ``inf`` when nothing is in
    the way.
    """
    if not fixed:
        return math.inf
    d = np.asarray(direction, dtype=float)
    m = np.asarray(moving, dtype=float)
    fa = np.concatenate(fixed) if len(fixed) > 1 else np.asarray(fixed[0], dtype=float)
    fb = np.concatenate([np.concatenate([f[1:], f[:1]]) for f in fixed])
    t1 = _ray_hits(m[:, None, :], d, fa[None], fb[None], tol).min(initial=math.inf)
    t2 = _ray_hits(fa[:, None, :], -d, m[None], np.concatenate([m[1:], m[:1]])[None], tol).min(initial=math.inf)
    return float(min(t1, t2))
