"""The bite check: how far each pane edge overlaps the support it rests on, measured in 3D.

A pane rests on the gaskets with its underside in the plane of its inset outline moved out by
``h = t_s + t_g`` (strip and gasket) along its outside normal ``N``.  For a pane edge ``A → B`` (length
``L``, direction ``d``) the pane lies on the side ``u = N × d`` (the outline is counter-clockwise seen from
``N``).  The gasket's top face of the edge's own strip (a rectangle, :meth:`Strip.top_corners`) is projected
along ``N`` into the pane plane and written in the edge's coordinates ``(s, r) = ((X − A)·d, (X − A)·u)``.
At a station ``s`` the bite is the length of the pane's inward ray over it,

    bite(s) = max(0, min(r_max(s), R) − max(r_min(s), 0)),

with ``[r_min(s), r_max(s)]`` the cross-section of the (convex) projected rectangle at ``s``.  The edge's bite
is the smallest over ``stations`` stations spread evenly over the part of the edge that its strip spans
(shortened by 1 mm at both ends); near the corners the pane lies on the strip that runs through the node.
The angle between the pane and the gasket face (the wedge the gasket takes up) is reported as ``tilt``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Sequence

import logging

import numpy as np
from scipy.spatial import cKDTree

from ppfab.errors import FabricationError

from .strips import Strip

if TYPE_CHECKING:  # pragma: no cover
    from ..panels import Panel

log = logging.getLogger("ppfab")


@dataclass(frozen=True)
class EdgeBite:
    """The bite of one pane edge: pane part id, outline edge index ``k`` (from outline vertex ``k`` to
    ``k + 1``), the mesh edge and strip under it, the smallest bite (mm), the supported length (mm) of the
    pane edge's length and the tilt (degrees) between the pane and the gasket face."""

    panel: str
    edge: int
    mesh_edge: int
    strip: str
    bite: float
    supported: float
    length: float
    tilt_deg: float


class BiteError(FabricationError):
    """Pane edges whose bite on their support is below ``[panels] min_bite``."""


def _section(poly: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``[r_min, r_max]`` of the convex polygon ``poly (k, 2)`` in ``(s, r)`` at stations ``s (m,)`` (NaN outside)."""
    a, b = poly, np.roll(poly, -1, axis=0)
    ds = b[:, 0] - a[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (s[:, None] - a[None, :, 0]) / ds[None, :]
    inside = (t >= 0) & (t <= 1) & (np.abs(ds)[None, :] > 1e-12)
    r = a[None, :, 1] + t * (b[:, 1] - a[:, 1])[None, :]
    lo = np.where(inside, r, np.inf).min(axis=1)
    hi = np.where(inside, r, -np.inf).max(axis=1)
    lo[~np.isfinite(lo)] = np.nan
    hi[~np.isfinite(hi)] = np.nan
    return lo, hi


def pane_edges(panels: Sequence["Panel"], vertices: np.ndarray, edges: np.ndarray) -> list[tuple["Panel", int, int]]:
    """``(panel, outline edge k, mesh edge)`` for every edge of every pane: the mesh edge is the face edge the
    outline edge was inset from (found by the face corners' positions)."""
    tree = cKDTree(vertices)
    nv = len(vertices)
    key = edges[:, 0] * nv + edges[:, 1]
    order = np.argsort(key)
    out = []
    for p in panels:
        _, vid = tree.query(p.corners_3d)
        ci = np.asarray(p.corner_index)
        k = len(p.outline)
        for q in range(k):
            a, b = int(vid[ci[q]]), int(vid[ci[(q + 1) % k]])
            lo, hi = min(a, b), max(a, b)
            pos = int(np.searchsorted(key, lo * nv + hi, sorter=order))
            e = int(order[pos]) if pos < len(order) and key[order[pos]] == lo * nv + hi else -1
            out.append((p, q, e))
    return out


def edge_normals(panels: Sequence["Panel"], vertices: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """``(E, 3)``: the sum of the outside normals of the panes on each mesh edge (zero where none)."""
    out = np.zeros((len(edges), 3))
    for p, _, e in pane_edges(panels, vertices, edges):
        if e >= 0:
            out[e] += p.frame.normal
    return out


def measure_bites(panels: Sequence["Panel"], strips: list[Strip], vertices: np.ndarray, edges: np.ndarray, gasket: float,
                  stations: int = 9) -> list[EdgeBite]:
    """The :class:`EdgeBite` of every pane edge (see the module docstring)."""
    by_edge = {s.edge: s for s in strips}
    out: list[EdgeBite] = []
    for p, q, e in pane_edges(panels, vertices, edges):
        h = strips[0].thickness + gasket if strips else 0.0
        N = p.frame.normal
        ring = p.outline_3d() + h * N
        A, B = ring[q], ring[(q + 1) % len(ring)]
        L = float(np.linalg.norm(B - A))
        d = (B - A) / L
        u = np.cross(N, d)
        strip = by_edge.get(e)
        if strip is None:
            out.append(EdgeBite(p.part_id, q, e, "", 0.0, 0.0, L, 90.0))
            continue
        top = strip.top_corners(gasket)
        top = top - np.outer((top - A) @ N, N)
        poly = np.stack([(top - A) @ d, (top - A) @ u], axis=1)
        s_lo = max(0.0, float(poly[:, 0].min()) + 1.0)
        s_hi = min(L, float(poly[:, 0].max()) - 1.0)
        if s_hi <= s_lo:
            out.append(EdgeBite(p.part_id, q, e, strip.part_id, 0.0, 0.0, L, 90.0))
            continue
        s = np.linspace(s_lo, s_hi, stations)
        lo, hi = _section(poly, s)
        bite = np.nan_to_num(np.clip(hi, 0.0, None) - np.clip(lo, 0.0, None), nan=0.0)
        tilt = float(np.degrees(np.arccos(min(1.0, abs(float(N @ strip.frame.normal))))))
        out.append(EdgeBite(p.part_id, q, e, strip.part_id, float(bite.min()), s_hi - s_lo, L, tilt))
    return out


def check_bites(bites: list[EdgeBite], min_bite: float, max_tilt_deg: float) -> None:
    """Raise :class:`BiteError` naming every pane edge with a bite below ``min_bite``, worst first; warn about
    pane edges that lie steeper than ``max_tilt_deg`` on their strip (they need wedge gaskets)."""
    low = sorted((b for b in bites if b.bite < min_bite - 1e-9), key=lambda b: b.bite)
    if low:
        names = ", ".join(f"{b.panel} edge {b.edge} ({b.bite:.1f} mm)" for b in low[:8])
        more = f" and {len(low) - 8} more" if len(low) > 8 else ""
        raise BiteError(f"{len(low)} pane edge(s) bite less than panels.min_bite = {min_bite:g} mm on their "
                        f"glazing strip: {names}{more}; widen [glazing] width or narrow [panels] gap")
    steep = sorted((b for b in bites if b.tilt_deg > max_tilt_deg + 1e-9), key=lambda b: -b.tilt_deg)
    if steep:
        names = ", ".join(f"{b.panel} edge {b.edge} ({b.tilt_deg:.1f}°)" for b in steep[:8])
        log.warning("%d pane edge(s) lie steeper on their glazing strip than glazing.max_tilt_deg = %g°: %s; "
                    "order tapered (wedge) gaskets for them (the glass order does not; flat gaskets leave the pane on one "
                    "line of its edge), or raise glazing.max_tilt_deg where the gasket takes the wedge",
                    len(steep), max_tilt_deg, names)
