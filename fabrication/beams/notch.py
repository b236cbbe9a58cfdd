"""Notches under crossing strips: a plate's top edge cut down where a glazing strip of another beam runs over it.

At a node one polyline runs through and its strips run over the node (:mod:`fabrication.glazing.strips`); the
plate of every other polyline at that node passes under them (a half-lap's plate slotted from below, a plate
ending against the running one, a plate of a corner node).  Its top edge reaches the node's top point, which
lies on the running strip's underside, but the plate leans off that strip (by ``λ``: ``sin λ = |u·n|``, ``u``
the strip's up, ``n`` the plate's normal) and its top edge leaves the strip's plane along the plate: over the
strip's width one top corner of the plate stands up to ``(t/2)·tan λ`` plus that rise into the strip
(smallest_roof: 5.05 mm; before this module the model drew the steel through the strip there).

The notch takes away every point of the plate that lies within the strip's box grown by the clearance
``c = NOTCH_CLEARANCE_MM`` — above the strip's underside less ``c``, within its length and width plus ``c`` —
on any face ``z ∈ [−t/2, t/2]`` of the plate.  In the strip frame that box is the intersection of half-spaces
``g·(p − o) ≤ h``; with ``p = O + x·ex + y·ey + z·n`` (plate frame) each is linear in ``(x, y, z)``, so the set
of plate points to cut is a convex polytope and its projection on the plate's plane (every ``z`` at once: the
notch is cut square through the plate) is the convex hull of the polytope's vertices
(:func:`notch_region`).  The plate's outline less that region is its new outline; the shop cuts the notch with
the plate's profile (DXF), square to the plate, so one face keeps a wedge of air under the strip of at most
``t·tan λ``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ppfab.metrics import polygon_area

from .plates import BeamPlate

if TYPE_CHECKING:  # pragma: no cover
    from ..glazing import Glazing
    from ..glazing.strips import Strip
    from .build import BeamSet

NOTCH_CLEARANCE_MM = 1.0
"""Air (mm) the notch leaves between the plate and the crossing strip: under its underside and beyond its sides
and ends."""

MIN_NOTCH_MM = 0.05
"""A plate standing less than this (mm) into a crossing strip's grown box is not notched (a cut the shop cannot
make; the clearance is then at least ``NOTCH_CLEARANCE_MM − MIN_NOTCH_MM``)."""

BEVEL_MARGIN_MM = 0.25
"""How far (mm) a notch's floor stays below the edge a bevel moves down on the lower face (so the notch's ends
keep a length on both faces and the faces' side walls stay planar quads, :mod:`fabrication.beams.bevel_cut`)."""

END_MM = 100.0
"""A notch that comes within this (mm, along the top edge) of the plate's end runs out over the end: no sliver of
top edge is left between it and the end cut (an edge shorter than a bevel moves it cannot be bevelled).  Where
that end is a splice cut (the plate one piece of a longer beam) the notch never runs over it — the two pieces'
cut edges must stay the same: beside a **bolted** splice the notch is not made (its cover plates sit a set
distance under the full top edge there; its cuts keep 240 mm more than the joints from a node, so this is rare),
beside a **welded** one it ends where it ends, leaving a sliver of full top edge of at least
:func:`weld_sliver_mm` before the cut, and is not made when it would leave less.  A strip left overlapping a
plate deeper than 0.25 mm is a finding of the erection check."""


def weld_sliver_mm(thickness: float) -> float:
    """The shortest full top edge (mm) a notch leaves before a welded splice cut: one plate thickness — square
    plate for the butt weld's end and its run-off tab (on a piece of the default at 88 × 60 faces, whose welded
    cuts stand 50 mm more than the joints from a node, the notches end 36 mm or more before the cut)."""
    return float(thickness)

HEADROOM_MM = 1.0e4
"""How far above the strip's underside the region to cut reaches (it only bounds the polytope: the plate below
its top edge never reaches it)."""


@dataclass(frozen=True)
class Notch:
    """A notch of a plate under the strips of another beam that run over one of its nodes: the strips (part ids,
    ``;``-separated), the node, the notch's depth below the plate's top edge (mm: the larger of its floor's depth
    square to the edge and the distance of the node's top point from the notched outline) and its length along
    the top edge (mm)."""

    strip: str
    node: int
    depth: float
    length: float

    def cell(self) -> dict[str, float | int | str]:
        """The notch as ``parts.csv``'s ``notches`` cell holds it (``depth_mm``, ``length_mm`` to 0.01 mm)."""
        return {"strip": self.strip, "node": self.node, "depth_mm": round(self.depth, 2),
                "length_mm": round(self.length, 2)}


def _half_spaces(plate: BeamPlate, strip: "Strip", clearance: float) -> np.ndarray:
    """``(m, 4)`` rows ``(A, B, C, D)``: the strip's grown box is ``A·x + B·y + C·z ≤ D`` in the plate frame, and
    the plate's slab ``|z| ≤ t/2``."""
    f, s = plate.frame, strip.frame
    rows = []
    for g, h in ((-s.normal, clearance), (s.normal, HEADROOM_MM),
                 (-s.ex, clearance - strip.x0), (s.ex, strip.x1 + clearance),
                 (-s.ey, 0.5 * strip.width + clearance), (s.ey, 0.5 * strip.width + clearance)):
        # g·(O + x ex + y ey + z n − o) ≤ h
        rows.append((float(g @ f.ex), float(g @ f.ey), float(g @ f.normal), h - float(g @ (f.origin - s.origin))))
    t = 0.5 * plate.thickness
    rows += [(0.0, 0.0, 1.0, t), (0.0, 0.0, -1.0, t)]
    return np.array(rows)


def notch_region(plate: BeamPlate, strip: "Strip", clearance: float = NOTCH_CLEARANCE_MM) -> np.ndarray:
    """``(k, 2)`` the convex region of the plate's plane (frame coordinates, CCW) whose points lie, on some face
    ``z ∈ [−t/2, t/2]``, inside ``strip``'s box grown by ``clearance`` (module docstring); empty ``(0, 2)`` when
    the plate's slab misses that box.  Exact: the projection of the vertices of the polytope, each the meeting
    point of three of its bounding planes."""
    from scipy.spatial import ConvexHull, QhullError

    hs = _half_spaces(plate, strip, clearance)
    m = hs[:, :3]
    pts = []
    for i, j, k in itertools.combinations(range(len(hs)), 3):
        a = m[[i, j, k]]
        if abs(np.linalg.det(a)) < 1e-12:
            continue
        p = np.linalg.solve(a, hs[[i, j, k], 3])
        if np.all(m @ p <= hs[:, 3] + 1e-9):
            pts.append(p[:2])
    if len(pts) < 3:
        return np.zeros((0, 2))
    q = np.unique(np.round(np.array(pts), 9), axis=0)
    try:
        hull = ConvexHull(q)
    except (QhullError, ValueError):
        return np.zeros((0, 2))                          # a flat polytope: no area to cut
    ring = q[hull.vertices]
    return ring if polygon_area(ring) > 0 else ring[::-1]


def _crossing_strips(plate: BeamPlate, strips: Sequence["Strip"]) -> list[tuple["Strip", int]]:
    """The strips of other beams with an end at one of the plate's nodes, with that node."""
    nodes = {int(k) for k in plate.nodes}
    out = []
    for s in strips:
        if s.beam_id == plate.beam_id:
            continue
        for k in s.vertices:
            if int(k) in nodes:
                out.append((s, int(k)))
                break
    return out


def _span_deltas(plate: BeamPlate, own: Sequence["Strip"]) -> dict[int, float]:
    """Top-edge span → how far (mm) a bevel under the plate's own strip may move that span's edge on a face,
    ``(t/2)·tan λ`` (:func:`fabrication.glazing.bevel.strip_bevel`; bevelled or not)."""
    from ..glazing.bevel import strip_bevel
    from .bevel_cut import span_strips

    return {c: float(strip_bevel(s, plate, 90.0).delta_mm) for c, s in span_strips(plate, own).items()}


def _end_is_node(plate: BeamPlate) -> tuple[bool, bool]:
    """Whether the plate's first and last top points are nodes (an end cut at a node), not splice cuts."""
    chain = np.asarray(plate.chain)
    return bool(np.any(chain == 0)), bool(np.any(chain == len(plate.top) - 1))


def _square_notch(plate: BeamPlate, taken: np.ndarray, deltas: dict[int, float], extra: float = 0.0
                  ) -> tuple[list[np.ndarray], float, float]:
    """The notch cut for the points ``taken (m, 2)`` of the plate that lie in a crossing strip's grown box: on each
    top-edge span they reach, a rectangle square to the span from above the edge down to ``D`` below it over
    their extent along the span (``D`` their largest depth below the span, plus the span's bevel allowance and
    :data:`BEVEL_MARGIN_MM`, so that a bevelled face's edge stays above the notch's floor; an end at a node is
    carried past it by ``D`` so that the rectangles of two spans meeting there overlap).  Returns the
    rectangles, ``D`` (the largest) and the length of top edge notched."""
    top = np.asarray(plate.top, dtype=float)
    # the material lies left of the top edge when top + reversed bottom runs counter-clockwise
    left = polygon_area(np.concatenate([top, np.asarray(plate.bottom, dtype=float)[::-1]])) > 0
    rects: list[np.ndarray] = []
    deepest, length = 0.0, 0.0
    first_node, last_node = _end_is_node(plate)
    # how much full top edge a notch must leave before a splice cut (END_MM): all of it beside a bolted splice
    sliver = weld_sliver_mm(plate.thickness) if plate.meta.get("splice") == "welded" else np.inf
    for c in range(len(top) - 1):
        p0, p1 = top[c], top[c + 1]
        e = p1 - p0
        L = float(np.linalg.norm(e))
        if L <= 0:
            continue
        e = e / L
        inward = np.array([-e[1], e[0]]) if left else np.array([e[1], -e[0]])     # square to the span, into it
        along = (taken - p0) @ e
        # the points over the span, and those past its ends within the region's size: under a kink at a node the
        # region's deepest corner lies past both spans' ends (measured from the span's line carried on)
        reach = float(np.ptp(along)) + 1e-9
        inside = (along >= -reach) & (along <= L + reach)
        if not np.any(inside):
            continue
        depth = float(np.max((taken[inside] - p0) @ inward))
        if depth < MIN_NOTCH_MM:
            continue
        # below the bevel's reach on this span and its neighbours (the rectangle runs past a node into the next)
        D = depth + max(deltas.get(k, 0.0) for k in (c - 1, c, c + 1)) + BEVEL_MARGIN_MM + extra
        lo, hi = float(along[inside].min()), float(along[inside].max())
        # past a node by D (the next span's rectangle overlaps it), elsewhere by the clearance (no sliver is left
        # between the notch's end and an end cut that is not square to the span)
        lo -= D if lo <= 1e-6 else NOTCH_CLEARANCE_MM
        hi += D if hi >= L - 1e-6 else NOTCH_CLEARANCE_MM
        if c == 0 and lo < END_MM:
            if first_node:
                lo = -HEADROOM_MM                        # at the plate's end: the notch runs out over its end cut
            elif lo < sliver:                            # a splice cut keeps its edge (END_MM)
                return [], 0.0, 0.0
        if c == len(top) - 2 and hi > L - END_MM:
            if last_node:
                hi = L + HEADROOM_MM
            elif hi > L - sliver:
                return [], 0.0, 0.0
        up = -inward * HEADROOM_MM
        rects.append(np.array([p0 + lo * e + up, p0 + lo * e + D * inward, p0 + hi * e + D * inward,
                               p0 + hi * e + up]))
        deepest = max(deepest, D)
        length += max(0.0, min(hi, L) - max(lo, 0.0))
    return rects, deepest, length


def notch_plate(plate: BeamPlate, strips: Sequence["Strip"], clearance: float = NOTCH_CLEARANCE_MM,
                bevel_min_deg: float | None = None) -> BeamPlate:
    """The plate with its outline cut under every strip of another beam that crosses one of its nodes (its
    :attr:`~BeamPlate.outline` less the square notch of each :func:`notch_region`, the notches in
    :attr:`~BeamPlate.notches`); the plate itself when none is deeper than :data:`MIN_NOTCH_MM`.  With
    ``bevel_min_deg`` the notches are deepened (by the largest bevel of the plate, up to three times) until the
    bevel of the notched plate can be drawn: a notch's wall shorter than a bevel moves its corner folds the face."""
    deltas = _span_deltas(plate, [s for s in strips if s.beam_id == plate.beam_id])
    reach = max(deltas.values(), default=0.0)
    out = plate
    for extra in (0.0, reach, 2.0 * reach, 3.0 * reach):
        out = _notched(plate, strips, clearance, deltas, extra)
        if bevel_min_deg is None or not out.notches or reach <= 0 or _bevel_drawable(out, strips, bevel_min_deg):
            return out
    return out


def _bevel_drawable(plate: BeamPlate, strips: Sequence["Strip"], min_deg: float) -> bool:
    from .bevel_cut import _valid_faces, top_bevels

    bevels = top_bevels(plate, [s for s in strips if s.beam_id == plate.beam_id], min_deg)
    return not bevels or _valid_faces(replace(plate, bevels=bevels)) is not None


def _notched(plate: BeamPlate, strips: Sequence["Strip"], clearance: float, deltas: dict[int, float],
             extra: float) -> BeamPlate:
    from shapely.geometry import Polygon
    from shapely.ops import unary_union

    from .joints import _clean

    outline = Polygon(plate.outline)
    at: dict[int, list] = {}
    for s, node in _crossing_strips(plate, strips):
        at.setdefault(node, []).append(s)
    notches = []
    for node, crossing in sorted(at.items()):
        # the strips running over the node (one on each side of it) make one notch of one depth
        regions = [Polygon(r) for r in (notch_region(plate, s, clearance) for s in crossing) if len(r) >= 3]
        if not regions:
            continue
        taken = outline.intersection(unary_union(regions))
        if taken.is_empty or taken.area <= 0:
            continue
        pts = np.concatenate([np.asarray(g.exterior.coords) for g in getattr(taken, "geoms", [taken])
                              if g.geom_type == "Polygon"])
        rects, depth, length = _square_notch(plate, pts, deltas, extra)
        if not rects:
            continue
        rest = outline.difference(unary_union([Polygon(r) for r in rects]))
        if rest.geom_type != "Polygon" or len(rest.interiors):
            continue                                      # a notch that would split the plate: left as it is
        outline = rest
        notches.append(Notch(";".join(sorted(s.part_id for s in crossing)), node, depth, length))
    if not notches:
        return plate
    # the depth at the node is what the cut leaves there: where two spans' rectangles meet at a kink of the top
    # edge, the floor's corner lies D / cos(kink / 2) below the node's top point, a little more than D
    from shapely.geometry import Point

    chain = {int(n): int(c) for n, c in zip(plate.nodes, plate.chain)}
    notches = [replace(n, depth=max(n.depth, float(outline.exterior.distance(Point(plate.top[chain[n.node]])))))
               if n.node in chain else n for n in notches]
    return replace(plate, outline=_clean(np.asarray(outline.exterior.coords)), notches=tuple(notches))


def notched_beams(beams: "BeamSet", glazing: "Glazing | None") -> "BeamSet":
    """The beam set with every plate notched under the strips of other beams that run over it
    (:func:`notch_plate`; area and mass of the report's records follow the notched outline)."""
    if glazing is None or not glazing.strips:
        return beams
    at_node: dict[int, list] = {}
    for s in glazing.strips:
        for k in s.vertices:
            at_node.setdefault(int(k), []).append(s)
    plates = []
    for p in beams.plates:
        near = {id(s): s for k in p.nodes for s in at_node.get(int(k), [])}
        plates.append(notch_plate(p, list(near.values()), bevel_min_deg=glazing.params.bevel_min_deg))
    notched = {p.part_id: p for p in plates if p.notches}
    if not notched:
        return beams
    density = beams.params.density
    records = []
    for r in beams.report.records:
        q = notched.get(r.part_id)
        if q is not None:
            area = float(polygon_area(q.outline))
            r = replace(r, area_mm2=area, mass_kg=area * q.thickness * density * 1e-9)
        records.append(r)
    return replace(beams, plates=tuple(plates), report=replace(beams.report, records=tuple(records)))
