"""Clash and contact of the glass on its support: panels.step against glazing.step, measured with manifold3d.

Each solid is read back with the CAD kernel and rebuilt as a manifold3d solid from its vertices (a strip, a
gasket and a convex pane are the convex hulls of their vertices; a non-convex pane the union of the prisms over
a triangulation of its underside), so the measurement shares nothing with the code that placed the panes.

Broad phase: the axis-aligned boxes of every strip and gasket in a k-d tree of their centres; a pane meets
only the solids whose box overlaps its own grown by :data:`SEARCH` (its own edges' strips and gaskets, and the
strips running through its corners).  For every such pair:

* **clash**: the intersection of pane and solid; its depth is its extent along the pane's normal (a part
  entering the pane from below meets it in a slab from the underside up to the part's top), or its thinnest
  width over its face normals when that is less (a setting block against the glass's edge face meets it in a
  sliver as tall as the glass and a rounding thin).  Deeper than
  :data:`~fabrication.glazing.seat.SEAT_TOLERANCE` is a finding naming pane, part and depth;
* **contact**: the gap between pane and gasket (manifold3d's ``min_gap``, 0 where they touch).  A pane whose
  nearest gasket is farther than the tolerance bears on nothing: a finding naming pane, gasket and gap.

Only builds with glazing strips are checked (``files.glazing_step`` and ``files.panels_step`` in the manifest).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..contract import gasket_id
from . import Verification, check
from ._shapes import face_outline, solid_points

SEARCH = 5.0
"""mm: how far beyond a pane's box the broad phase looks for strips and gaskets, and how far ``min_gap`` looks."""


@dataclass(frozen=True)
class PairMeasure:
    """One pane against one strip or gasket: the part ids, the depth (mm) of their intersection along the
    pane's normal (0 when they do not intersect) and their gap (mm; 0 where they touch or intersect,
    :data:`SEARCH` or more when farther)."""

    pane: str
    part: str
    depth: float
    gap: float


def _normal(points: np.ndarray) -> np.ndarray:
    """The unit normal of a thin prism's large faces: the least-variance direction of its vertices."""
    c = points.mean(axis=0)
    return np.linalg.svd(points - c)[2][2]


def pane_manifold(solid: Any) -> tuple[Any, np.ndarray]:
    """A pane solid as a manifold3d ``Manifold`` and the unit normal ``n`` of its large faces (either sense)."""
    from ._bodies import manifold3d

    m3 = manifold3d()
    import shapely
    from shapely.geometry import Polygon

    pts = solid_points(solid)
    n = _normal(pts)
    z = pts @ n
    under = float(z.min())
    ring = face_outline(solid, n)
    if ring is None:
        ring = pts[z < 0.5 * (z.min() + z.max())]
    ex = ring[1] - ring[0]
    ex = ex - (ex @ n) * n
    ex /= np.linalg.norm(ex)
    ey = np.cross(n, ex)
    flat = np.stack([ring @ ex, ring @ ey], axis=1)
    poly = Polygon(flat)
    thick = float(z.max() - z.min())
    base = ring - np.outer(ring @ n - under, n)
    if abs(poly.area - poly.convex_hull.area) <= 1e-6 * max(poly.area, 1.0):
        return m3.Manifold.hull_points(np.vstack([base, base + thick * n])), n
    parts = []
    for tri in shapely.constrained_delaunay_triangles(poly).geoms:
        q = np.asarray(tri.exterior.coords)[:3]
        p3 = base[0] + np.outer(q[:, 0] - flat[0, 0], ex) + np.outer(q[:, 1] - flat[0, 1], ey)
        p3 = p3 - np.outer(p3 @ n - under, n)
        parts.append(m3.Manifold.hull_points(np.vstack([p3, p3 + thick * n])))
    return m3.Manifold.batch_boolean(parts, m3.OpType.Add), n


def measure_pair(pane: Any, n: np.ndarray, other: Any, pane_id: str, part_id: str) -> PairMeasure:
    """Depth and gap of one pane (a manifold with unit normal ``n``) against one part (a manifold)."""
    from ._bodies import depth_of

    common = pane ^ other
    if not common.is_empty() and common.volume() > 1e-9:
        z = np.asarray(common.to_mesh().vert_properties)[:, :3] @ n
        # a part against the glass's edge face (a setting block) meets it in a sliver as tall as the glass:
        # the depth is never more than the sliver's thinnest width
        return PairMeasure(pane_id, part_id, min(float(z.max() - z.min()), depth_of(common)[0]), 0.0)
    return PairMeasure(pane_id, part_id, 0.0, float(pane.min_gap(other, SEARCH)))


def measure_clashes(panes: dict[str, Any], supports: dict[str, Any]) -> list[PairMeasure]:
    """Every pane (name → solid) against the strips and gaskets (name → solid) whose boxes come within
    :data:`SEARCH` of its own: one :class:`PairMeasure` per pair, in pane order."""
    from ._bodies import manifold3d

    m3 = manifold3d()
    from scipy.spatial import cKDTree

    names = list(supports)
    if not names or not panes:
        return []
    pts = [solid_points(supports[k]) for k in names]
    lo = np.array([p.min(axis=0) for p in pts])
    hi = np.array([p.max(axis=0) for p in pts])
    hulls = [m3.Manifold.hull_points(p) for p in pts]
    centre = 0.5 * (lo + hi)
    half = float(np.linalg.norm(0.5 * (hi - lo), axis=1).max())
    tree = cKDTree(centre)
    out = []
    for pane_id, solid in panes.items():
        shape, n = pane_manifold(solid)
        p = solid_points(solid)
        plo, phi = p.min(axis=0) - SEARCH, p.max(axis=0) + SEARCH
        reach = float(np.linalg.norm(0.5 * (phi - plo))) + half
        for k in sorted(tree.query_ball_point(0.5 * (plo + phi), reach)):
            if np.all(lo[k] <= phi) and np.all(hi[k] >= plo):
                out.append(measure_pair(shape, n, hulls[k], pane_id, names[k]))
    return out


@check("clash")
def check_clash(v: Verification) -> None:
    from ..glazing.seat import SEAT_TOLERANCE
    from ._step_read import read_or_report

    files = v.manifest.get("files", {})
    rel_p, rel_g = files.get("panels_step"), files.get("glazing_step")
    if rel_p is None or rel_g is None:
        return
    glass = read_or_report(v, rel_p)
    support = read_or_report(v, rel_g)
    if glass is None or support is None:
        return
    panes = {s.name: s.solid for s in glass if s.name.startswith("P-")}
    supports = {s.name: s.solid for s in support}
    gaskets = {gasket_id(r["part_id"]) for r in (v.parts or []) if r.get("kind") == "strip"}
    pairs = measure_clashes(panes, supports)
    tol = SEAT_TOLERANCE
    for p in sorted((p for p in pairs if p.depth > tol), key=lambda p: -p.depth)[:20]:
        v.error(rel_p, p.pane, f"penetrates {p.part} of {rel_g} by {p.depth:.2f} mm (more than {tol:g} mm)")
    nearest: dict[str, PairMeasure] = {}
    for p in pairs:
        if p.part in gaskets and (p.pane not in nearest or p.gap < nearest[p.pane].gap):
            nearest[p.pane] = p
    for pane_id in panes:
        near = nearest.get(pane_id)
        if near is None:
            v.error(rel_p, pane_id, f"has no gasket of {rel_g} within {SEARCH:g} mm: it bears on nothing")
        elif near.gap > tol:
            v.error(rel_p, pane_id, f"bears on no gasket: the nearest, {near.part}, is {near.gap:.2f} mm below it "
                                    f"(more than {tol:g} mm)")
    v.checked.append("clash")
