"""The plate-top bevel, modelled: each top-edge span under a leaning glazing strip raised and planed to the strip.

:mod:`fabrication.glazing.bevel` states the fit of every strip on its plate; this module makes it the plate's
geometry.  A top-edge span of a plate (``top[c] → top[c+1]``) carries the strip of its mesh edge; where the
plate leans off the strip by more than ``glazing.bevel_min_deg`` its top face is the strip's underside plane
``u·(p − o) = 0`` (``u`` the strip's up, ``o`` its frame origin, which lies on the span).  In the plate frame
(``p = O + x·ex + y·ey + z·n``) that plane meets the face ``z`` in the line

    a·x + b·y = c − w·z,        a = u·ex, b = u·ey, c = u·(o − O), w = u·n,

so on the two faces ``z = ±t/2`` the span's top edge is the mid-plane edge moved by ``∓w·(t/2)/|(a, b)|`` along
its normal: ``Δ = (t/2)·tan λ`` up on one face, down on the other (``sin λ = |w|``).  Every other edge of the
outline (end cuts, slots, the bottom) is the same line on both faces.  The face polygons are the outline with
each edge on its line of that face, each vertex where two consecutive lines meet (a mitre), so both faces have
the same vertices in the same order and every side face — the quad between an edge on the front and the same
edge on the back — joins two parallel segments and is planar (:func:`face_outlines`).  Two consecutive spans
with different bevels meet in their planes' common line, which runs from face to face through the node.

What is cut from the sheet (:attr:`~fabrication.beams.plates.BeamPlate.cut_outline`, the DXF and the nesting) is
the union of the two faces: the outline raised by ``Δ`` on every bevelled span; the shop then planes the bevel
off the face that stands lower (:attr:`TopBevel.side` names the face that keeps the raised edge).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ppfab.metrics import polygon_area

from .plates import BeamPlate

if TYPE_CHECKING:  # pragma: no cover
    from ..glazing import Glazing
    from ..glazing.strips import Strip
    from .build import BeamSet

ON_SPAN_MM = 1e-5
"""How far (mm) an outline edge's end may lie from a top-edge span to count as on it."""

ON_STRIP_MM = 0.5
"""How far (mm) a span's ends may lie from a strip's line for the strip to be the span's (the strip lies in its
edge's support plane, the plate in its polyline's: the same plane within ``beams.plane_tolerance``)."""

STRAIGHT_MM = 1e-6
"""A corner of the cut outline closer than this (mm) to the line through its neighbours is dropped."""

PARALLEL = 1e-9
"""``|sin|`` of the angle below which two consecutive edge lines are taken as parallel."""


@dataclass(frozen=True)
class TopBevel:
    """The bevel of one top-edge span of a plate: ``span`` the index ``c`` of ``top[c] → top[c+1]``, the strip
    on it, the lean ``λ`` (degrees), ``Δ = (t/2)·tan λ`` (mm, square to the edge in the plate's plane), ``side``
    the face that keeps the raised edge (``+1`` the front, ``z = +t/2``, towards the frame normal; ``−1`` the
    back) and ``line = (a, b, c, w)``: on the face ``z`` the top edge is ``a·x + b·y = c − w·z`` with
    ``a² + b² = 1`` (plate frame; module docstring)."""

    span: int
    strip: str
    lean_deg: float
    delta: float
    side: int
    line: tuple[float, float, float, float]

    def text(self) -> str:
        """The shop instruction: ``BEVEL 23.3° Δ +3.23 mm, raised face F`` (``F`` front, ``B`` back)."""
        return f"BEVEL {self.lean_deg:.1f}\u00b0 \u0394 +{self.delta:.2f} mm, raised face {'F' if self.side > 0 else 'B'}"


def span_strips(plate: BeamPlate, strips: Sequence["Strip"]) -> dict[int, "Strip"]:
    """Top-edge span index → the strip lying on it: the strip of the plate's beam whose underside line holds
    both ends of the span (within :data:`ON_STRIP_MM`) and a length of the strip."""
    f = plate.frame
    out: dict[int, Strip] = {}
    top3 = f.to3d(plate.top)
    for s in strips:
        if s.beam_id != plate.beam_id:
            continue
        ex, o = s.frame.ex, s.frame.origin
        d = top3 - o
        along = d @ ex
        off = np.linalg.norm(d - np.outer(along, ex), axis=1)
        on = off <= ON_STRIP_MM
        for c in range(len(top3) - 1):
            if not (on[c] and on[c + 1]):
                continue
            a, b = sorted((float(along[c]), float(along[c + 1])))
            if min(b, s.x1) - max(a, s.x0) > ON_SPAN_MM:          # the span holds a length of the strip
                out.setdefault(c, s)
    return out


def top_bevels(plate: BeamPlate, strips: Sequence["Strip"], min_deg: float) -> tuple[TopBevel, ...]:
    """The :class:`TopBevel` of every span of ``plate`` whose strip leans more than ``min_deg`` off it, in span
    order (:func:`fabrication.glazing.bevel.strip_bevel` decides, so bevels.csv and the model agree)."""
    from ..glazing.bevel import strip_bevel

    f = plate.frame
    n = f.normal
    out = []
    for c, s in sorted(span_strips(plate, strips).items()):
        fit = strip_bevel(s, plate, min_deg)
        if not fit.bevelled:
            continue
        u = s.frame.normal
        a, b, w = float(u @ f.ex), float(u @ f.ey), float(u @ n)
        cc = float(u @ (s.frame.origin - f.origin))
        r = math.hypot(a, b)
        out.append(TopBevel(c, s.part_id, fit.lean_deg, fit.delta_mm, 1 if w < 0 else -1,
                            (a / r, b / r, cc / r, w / r)))
    return tuple(out)


def _edge_lines(plate: BeamPlate, outline: np.ndarray) -> tuple[np.ndarray, list[TopBevel | None]]:
    """For each edge ``k`` of ``outline``: its line ``(a, b, c)`` (unit normal, outward for a CCW ring) and the
    bevel of the span it lies on (``None``: the same line on both faces)."""
    by_span = {b.span: b for b in plate.bevels}
    q = outline
    nxt = np.roll(q, -1, axis=0)
    d = nxt - q
    length = np.linalg.norm(d, axis=1)
    normal = np.c_[d[:, 1], -d[:, 0]] / np.maximum(length, 1e-300)[:, None]
    lines = np.c_[normal, np.einsum("ij,ij->i", normal, q)]
    bev: list[TopBevel | None] = [None] * len(q)
    top = plate.top
    for c, b in by_span.items():
        p0, p1 = top[c], top[c + 1]
        e = p1 - p0
        L = float(np.linalg.norm(e))
        e = e / L

        def on(p: np.ndarray) -> np.ndarray:
            r = p - p0
            t = np.clip(r @ e, 0.0, L)
            return np.linalg.norm(r - np.outer(t, e), axis=1) <= ON_SPAN_MM

        hit = on(q) & on(nxt) & (length > 0)
        for k in np.flatnonzero(hit):
            bev[int(k)] = b
    return lines, bev


def _split_at_nodes(plate: BeamPlate, outline: np.ndarray) -> np.ndarray:
    """``outline`` with each top point inserted where it lies inside an edge (collinear spans merged by the
    outline's clean-up), so that every edge lies on one span."""
    q = [p for p in outline]
    for t in plate.top[1:-1]:
        for k in range(len(q)):
            a, b = q[k], q[(k + 1) % len(q)]
            e = b - a
            L = float(np.linalg.norm(e))
            if L < 1e-9:
                continue
            s = float((t - a) @ e) / (L * L)
            if ON_SPAN_MM / L < s < 1.0 - ON_SPAN_MM / L and abs(float(e[0] * (t - a)[1] - e[1] * (t - a)[0])) / L <= ON_SPAN_MM:
                q.insert(k + 1, np.asarray(t, dtype=float))
                break
    return np.array(q)


class BevelError(ValueError):
    """The faces of a bevelled plate cannot be drawn (two parallel edges with different bevels meet)."""


def face_outlines(plate: BeamPlate) -> tuple[np.ndarray, np.ndarray]:
    """``(front, back)``: the plate's outline on its faces ``z = +t/2`` and ``z = −t/2`` (frame coordinates,
    CCW, the same number of vertices in the same order; module docstring).  A plate without bevels gives its
    outline twice.  Raises :class:`BevelError` where two parallel consecutive edges have different lines."""
    q = np.asarray(plate.outline, dtype=float)
    if not plate.bevels:
        return q, q
    q = _split_at_nodes(plate, q)
    lines, bev = _edge_lines(plate, q)
    h = 0.5 * plate.thickness
    faces = []
    for z in (h, -h):
        ln = lines.copy()
        for k, b in enumerate(bev):
            if b is not None:
                a, bb, c, w = b.line
                if a * ln[k, 0] + bb * ln[k, 1] < 0:          # the strip's up is the outline's outward normal
                    a, bb, c, w = -a, -bb, -c, -w
                ln[k] = (a, bb, c - w * z)
        pts = np.empty_like(q)
        for k in range(len(q)):
            p, r = ln[k - 1], ln[k]
            det = p[0] * r[1] - p[1] * r[0]
            if abs(det) <= PARALLEL:
                if bev[k - 1] is bev[k] or abs(p[2] - r[2]) <= 1e-9:
                    pts[k] = q[k] - (r[:2] @ q[k] - r[2]) * r[:2]
                    continue
                raise BevelError(f"{plate.part_id}: two parallel edges with different bevels meet at "
                                 f"({q[k, 0]:.1f}, {q[k, 1]:.1f})")
            pts[k] = np.array([(p[2] * r[1] - p[1] * r[2]) / det, (p[0] * r[2] - p[2] * r[0]) / det])
        faces.append(pts)
    return faces[0], faces[1]


def _valid_faces(plate: BeamPlate) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`face_outlines` when both are simple polygons turning the outline's way, else ``None``."""
    from shapely.geometry import Polygon

    try:
        front, back = face_outlines(plate)
    except BevelError:
        return None
    q = _split_at_nodes(plate, np.asarray(plate.outline, dtype=float))
    along = np.roll(q, -1, axis=0) - q
    for ring in (front, back):
        poly = Polygon(ring)
        if not poly.is_valid or polygon_area(ring) <= 0:
            return None
        # an edge a bevel's corner moved past its other end turns round on that face: the side face folds
        if len(ring) == len(q) and np.any(np.einsum("ij,ij->i", np.roll(ring, -1, axis=0) - ring, along) <= 0):
            return None
    return front, back


def cut_outline(front: np.ndarray, back: np.ndarray) -> np.ndarray:
    """What is cut from the sheet: the union of the two faces' outlines (CCW, the closing point dropped,
    collinear points removed)."""
    from shapely.geometry import Polygon

    from .joints import _clean

    import shapely

    # snap-rounded on a 1e-9 mm grid: the faces share their end cuts, and a floating overlay of segments on one
    # line that differ in the last digits can return one face for the union
    union = shapely.union(Polygon(front), Polygon(back), grid_size=1e-9)
    if union.geom_type == "GeometryCollection":      # a line the snap rounding left beside the outline
        polygons = [g for g in shapely.get_parts(union) if g.geom_type == "Polygon"]
        union = polygons[0] if len(polygons) == 1 else union
    if union.geom_type != "Polygon" or len(union.interiors):       # pragma: no cover - faces overlap by design
        raise BevelError("the two faces of a bevelled plate do not overlap into one outline")
    # a point snap rounding put a few 1e-7 mm beside a corner where the faces' collinear edges meet goes onto that
    # corner (kept beside it, both would be dropped below as straight, and the corner with them)
    from scipy.spatial import cKDTree

    ring = np.asarray(union.exterior.coords)[:-1]
    corners = np.vstack([front, back])
    d, k = cKDTree(corners).query(ring)
    ring = np.where((d <= 1e-5)[:, None], corners[k], ring)
    q = _clean(np.vstack([ring, ring[:1]]))
    # a corner where the two faces cross on (nearly) one line is no corner of the cut: its distance from the line
    # through its neighbours is under STRAIGHT_MM (as the step file's decimals leave it)
    prev, nxt = np.roll(q, 1, axis=0), np.roll(q, -1, axis=0)
    cross = (q[:, 0] - prev[:, 0]) * (nxt[:, 1] - q[:, 1]) - (q[:, 1] - prev[:, 1]) * (nxt[:, 0] - q[:, 0])
    return q[np.abs(cross) > STRAIGHT_MM * np.linalg.norm(nxt - prev, axis=1)]


def bevel_plate(plate: BeamPlate, strips: Sequence["Strip"], min_deg: float) -> BeamPlate:
    """A new plate with the :class:`TopBevel` of its spans and its :attr:`cut_outline` (the plate itself when no
    span is bevelled, or when its faces cannot be drawn: logged, the plate stays square there)."""
    bevels = top_bevels(plate, strips, min_deg)
    if not bevels:
        return plate
    out = replace(plate, bevels=bevels)
    faces = _valid_faces(out)
    if faces is None:
        logging.getLogger("ppfab").warning("%s: the bevel of its top edge cannot be drawn (an edge of the outline "
                                           "is shorter than the bevel moves it); the plate keeps a square top edge and the strip's fillet weld takes "
                                           "up the lean's overlap (the shop fits it; raise glazing.bevel_min_deg to "
                                           "bevel fewer plates, or thin beams.thickness to shrink the overlap)",
                                           plate.part_id)
        return plate
    return replace(out, cut_outline=cut_outline(*faces))


def bevelled_beams(beams: "BeamSet", glazing: "Glazing | None") -> "BeamSet":
    """The beam set with every plate's top edge raised and bevelled under the glazing strips that lean more than
    ``glazing.bevel_min_deg`` off it (new plate records; type ids and report records follow: a bevelled plate
    is its own type unless another has the same outline and bevels)."""
    from .flat import type_ids

    if glazing is None or not glazing.strips:
        return beams
    by_beam: dict[str, list] = {}
    for s in glazing.strips:
        by_beam.setdefault(s.beam_id, []).append(s)
    min_deg = glazing.params.bevel_min_deg
    plates = tuple(bevel_plate(p, by_beam.get(p.beam_id, []), min_deg) for p in beams.plates)
    # the pieces of a beam meet at their splice cuts with one cut edge, which the splice's cover plates and
    # ppfab verify take from both: where one piece had to keep its square top edge, its beam's other pieces do too
    square = {b.beam_id for a, b in zip(beams.plates, plates)
              if b.n_pieces > 1 and not b.bevels and top_bevels(a, by_beam.get(a.beam_id, []), min_deg)}
    if square:
        logging.getLogger("ppfab").warning("%d beam(s) keep a square top edge on every piece, as one of their pieces "
                                           "must (%s); their strips' fillet welds take up the lean's overlap (raise glazing.bevel_min_deg to "
                                           "accept this everywhere)", len(square), ", ".join(sorted(square)[:6]))
        plates = tuple(a if a.beam_id in square else b for a, b in zip(beams.plates, plates))
    types = type_ids(list(plates))
    by_id = {p.part_id: p for p in plates}
    density = beams.params.density
    records = []
    for r in beams.report.records:
        p = by_id.get(r.part_id)
        if p is not None and p.cut_outline is not None:       # area and mass as cut, as parts.csv states them
            area = float(polygon_area(p.cut_outline))
            r = replace(r, area_mm2=area, mass_kg=area * p.thickness * density * 1e-9)
        records.append(replace(r, type_id=types.get(r.part_id, r.type_id)))
    return replace(beams, plates=plates, report=replace(beams.report, records=tuple(records)), types=types)
