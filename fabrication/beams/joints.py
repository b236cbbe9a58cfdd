"""Joints where plates meet at a node: half-lap slots, butt ends, and the checks.

At a node every plate contains the node axis (the support planes of a
torsion-free structure pass through it), so two plates cross along the axis
line.  For plate thickness ``t`` and the angle ``θ`` between the two planes:

* **half-lap** (two plates running through the node): one slot from above in the
  rows (family 0), one from below in the columns, both centred on the common line
  of the two planes and half the depth long.  The other plate's slab cuts this
  plate's mid-plane in a strip ``t / sin θ`` wide, shifted by ``±(t/2)·cot θ``
  across this plate's own thickness, so a slot cut square to the plate needs
  ``w = t (1 + cos θ) / sin θ + clearance = t·cot(θ/2) + clearance``; with ``clearance = "auto"`` ``t`` is the
  thickest plate EN 10029 class A allows and the clearance is ``slot_fit``.  Each slot reaches ``slot_play``
  past half the depth, so the two plates never bottom out on each other.
* **butt** (a plate ends at a node): the end is cut parallel to the axis, set back
  from it so it clears every other plate there — ``(t/2)(1 + |cos θ|)/sin θ`` from a
  plate running through (same geometry as the slot), ``(t/2)·cot(φ/2)`` from
  another ending plate at angle ``φ`` between the two (the bisector then separates
  them) — plus half the clearance (``t`` and clearance as for the slots).  Segmented
  joints (P meshes) are butt joints of the segments against the continuous beam.
* **none**: plain intersecting plates, nothing cut.

Outlines are built in each plate's 2D frame with 2D polygon booleans (shapely) and
extruded once later; nothing here touches a CAD kernel.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from shapely.geometry import Polygon
from shapely.ops import unary_union
from shapely.validation import explain_validity

from ppfab import planes as pl
from ppfab.finding import Finding
from ppfab.metrics import polygon_area
from ppfab.support.structure import SupportStructure

from .joint_types import get_joint_type
from .params import BeamParams
from .plates import BeamPlate, Slot


def end_setback(thickness: float, cos_phi: float, sin_phi: float, clearance: float) -> float:
    """How far an ending plate stops short of the node axis to clear a plate at angle ``φ`` (see module doc)."""
    return 0.5 * thickness * (1.0 + cos_phi) / max(sin_phi, 1e-12) + 0.5 * clearance


@dataclass(frozen=True)
class NodeJoint:
    """What happens at one node.

    ``parts``/``roles``: the plates there and whether each runs ``through`` or ``end``s;
    ``angles``: ``(part_a, part_b, dihedral, opening, same_beam)`` for every pair — the angle of
    the two planes (degrees, 0…90), the angle between two *ending* plates around the axis
    (0…180, ``nan`` otherwise) and whether both are pieces of one beam;
    ``kind``: ``halflap``, ``butt``, ``plain`` or ``free`` (a single plate);
    ``slot_width``: mm (half-lap) or ``nan``; ``trims``: ``(part, setback mm)`` of ending plates;
    ``line``: point and unit direction (3D) of the crossing line of a half-lap.
    """

    vertex: int
    parts: tuple[str, ...]
    roles: tuple[str, ...]
    angles: tuple[tuple[str, str, float, float, bool], ...]
    kind: str
    slot_width: float
    trims: tuple[tuple[str, float], ...]
    line: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def dihedral_min_deg(self) -> float:
        """Smallest angle between the planes of two different beams meeting here (``nan`` if < 2 beams)."""
        d = [a[2] for a in self.angles if not a[4]]
        return min(d) if d else float("nan")


def _incidence(plates: list[BeamPlate]) -> dict[int, list[int]]:
    out: dict[int, list[int]] = {}
    for k, p in enumerate(plates):
        for v in p.nodes.tolist():
            out.setdefault(v, []).append(k)
    return out


def _end_direction3(p: BeamPlate, v: int, axis: np.ndarray) -> np.ndarray:
    m = p.frame.vec3d(p.body_direction(v))
    m = m - (m @ axis) * axis
    return m / np.linalg.norm(m)


def analyse_nodes(plates: list[BeamPlate], support: SupportStructure, params: BeamParams
                  ) -> tuple[list[NodeJoint], dict[str, list[tuple[int, float]]], dict[str, list[Slot]], list[Finding]]:
    """Joints at every node: angles, end set-backs, the joint type's cuts where plates run through
    (:mod:`fabrication.beams.joint_types`), angle defects."""
    jt = get_joint_type(params.joint)
    joints: list[NodeJoint] = []
    trims: dict[str, list[tuple[int, float]]] = {}
    slots: dict[str, list[Slot]] = {}
    defects: list[Finding] = []
    t, cl = params.slot_thickness, params.fit
    min_ang = params.min_angle_deg
    for v, idx in sorted(_incidence(plates).items()):
        a = support.axes[v]
        ps = [plates[k] for k in idx]
        roles = ["through" if bool(p.through[np.flatnonzero(p.nodes == v)[0]]) else "end" for p in ps]
        ends = {k: _end_direction3(p, v, a) for k, (p, r) in enumerate(zip(ps, roles)) if r == "end"}
        angles: list[tuple[str, str, float, float, bool]] = []
        setback = {k: 0.0 for k in ends}
        for i in range(len(ps)):
            for j in range(i + 1, len(ps)):
                dihedral = float(np.degrees(pl.angle_between(ps[i].plane, ps[j].plane)))
                opening = float("nan")
                if roles[i] == "end" and roles[j] == "end":
                    mi, mj = ends[i], ends[j]
                    cos, sin = float(mi @ mj), float(np.linalg.norm(np.cross(mi, mj)))
                    opening = float(np.degrees(np.arctan2(sin, cos)))
                    ang = opening
                    pairs = [(i, cos, sin), (j, cos, sin)]
                else:
                    ang = dihedral
                    pairs = []
                    for e, o in ((i, j), (j, i)):
                        if roles[e] == "end":
                            s = abs(float(ends[e] @ ps[o].plane[:3]))
                            c = np.sqrt(max(0.0, 1.0 - s * s))
                            pairs.append((e, c, s))
                angles.append((ps[i].part_id, ps[j].part_id, dihedral, opening,
                               ps[i].beam_id == ps[j].beam_id))
                if ang < min_ang:
                    defects.append(Finding("small_angle", "", ps[i].part_id, ang, min_ang,
                                          f"{ps[i].part_id} and {ps[j].part_id} meet at node {v} at {ang:.1f}° "
                                          f"(< min_angle_deg {min_ang:g}°)"))
                    continue
                if jt.cuts_ends:
                    for e, c, s in pairs:
                        setback[e] = max(setback[e], end_setback(t, c, s, cl))
        through = [k for k, r in enumerate(roles) if r == "through"]
        kind = "free" if len(ps) == 1 else ("butt" if jt.cuts_ends else "plain")
        width = float("nan")
        line = None
        cut = jt.through(ps, through, v, a, support, params) if jt.through is not None else None
        if cut is not None:
            kind, width, line = cut.kind, cut.width, cut.line
            for pid, extra in cut.slots.items():
                slots.setdefault(pid, []).extend(extra)
            defects += cut.defects
        cuts = jt.cuts_ends and len(ps) > 1
        for k, c in setback.items():
            if cuts:
                trims.setdefault(ps[k].part_id, []).append((v, c))
        joints.append(NodeJoint(v, tuple(p.part_id for p in ps), tuple(roles), tuple(angles), kind, width,
                                tuple((ps[k].part_id, c) for k, c in setback.items() if cuts), line))
    return joints, trims, slots, defects


def _trim_polygon(p: BeamPlate, v: int, c: float) -> Polygon:
    """The strip between the node axis line and the end cut ``c`` mm into the plate."""
    T = p.node_top(v)
    s = p.node_axis(v)
    m = p.body_direction(v)
    d = p.depth
    lo = -max(1.0, 0.01 * d)
    pts = [T + al * s + be * m for al, be in ((-0.5 * d, lo), (1.5 * d, lo), (1.5 * d, c), (-0.5 * d, c))]
    return Polygon(pts)


def _clean(coords: np.ndarray) -> np.ndarray:
    """Drop the closing point, near-duplicate and collinear points; counter-clockwise."""
    q = np.asarray(coords, dtype=float)[:-1]
    keep = np.linalg.norm(q - np.roll(q, 1, axis=0), axis=1) > 1e-7
    q = q[keep]
    prev, nxt = np.roll(q, 1, axis=0), np.roll(q, -1, axis=0)
    cross = (q[:, 0] - prev[:, 0]) * (nxt[:, 1] - q[:, 1]) - (q[:, 1] - prev[:, 1]) * (nxt[:, 0] - q[:, 0])
    span = np.linalg.norm(nxt - prev, axis=1)
    q = q[np.abs(cross) > 1e-9 * np.maximum(span, 1.0)]
    return q if polygon_area(q) > 0 else q[::-1]


def _single(geom, plate: BeamPlate, stage: str, defects: list[Finding]) -> Polygon | None:
    if geom.is_empty:
        defects.append(Finding("short_segment", "", plate.part_id, 0.0, 0.0,
                              f"{plate.part_id}: nothing is left after the {stage}"))
        return None
    if geom.geom_type != "Polygon":
        parts = list(getattr(geom, "geoms", []))
        defects.append(Finding("outline", "", plate.part_id, float(len(parts)), 1.0,
                              f"{plate.part_id}: the {stage} split the plate into {len(parts)} pieces"))
        return None
    if len(geom.interiors):
        defects.append(Finding("outline", "", plate.part_id, float(len(geom.interiors)), 0.0,
                              f"{plate.part_id}: the {stage} leave(s) {len(geom.interiors)} hole(s) in the plate"))
        return None
    return geom


def apply_joints(plate: BeamPlate, trims: list[tuple[int, float]], slots: list[Slot], params: BeamParams,
                 defects: list[Finding]) -> BeamPlate:
    """The plate with end cuts and slots drawn into its 2D outline (shapely), checked."""
    raw = Polygon(plate.raw_outline)
    if not raw.is_valid:
        defects.append(Finding("outline", "", plate.part_id, 0.0, 0.0,
                              f"{plate.part_id}: its outline is not a simple polygon ({explain_validity(raw)}); "
                              "the bottom edge crosses itself"))
        return replace(plate, trims=tuple(trims), slots=tuple(slots))
    body = raw
    cut = [_trim_polygon(plate, v, c) for v, c in trims if c > 0]
    if cut:
        body = _single(raw.difference(unary_union(cut)), plate, "end cuts", defects)
    if body is None:
        return replace(plate, trims=tuple(trims), slots=tuple(slots))
    outline = body
    if slots:
        r = params.tool_radius
        for s in slots:
            if r > 0 and s.width < 2 * r:
                defects.append(Finding("outline", "", plate.part_id, s.width, 2 * r,
                                      f"{plate.part_id}: the slot at node {s.node} is {s.width:.3g} mm wide, "
                                      f"narrower than the tool (beams.tool_radius {r:g} mm); use a smaller tool"))
        outline = _single(body.difference(unary_union([s.cutout(r) for s in slots])), plate, "slots",
                          defects)
    if outline is None:
        return replace(plate, body=_clean(np.asarray(body.exterior.coords)), trims=tuple(trims), slots=tuple(slots))
    return replace(plate, body=_clean(np.asarray(body.exterior.coords)),
                   outline=_clean(np.asarray(outline.exterior.coords)), trims=tuple(trims),
                   slots=tuple(sorted(slots, key=lambda s: int(np.flatnonzero(plate.nodes == s.node)[0]))))


def plate_checks(plate: BeamPlate, params: BeamParams) -> list[Finding]:
    """Depth beyond the crossing of consecutive node axes; zero-length edges; over-trimmed or
    over-slotted segments (less than ``min_segment`` of material left)."""
    out: list[Finding] = []
    top, bot = plate.top, plate.bottom
    d = params.depth
    seg = np.linalg.norm(np.diff(top, axis=0), axis=1)
    for edge in np.flatnonzero(seg < max(params.min_segment, 1e-9)):
        out.append(Finding("short_segment", "", plate.part_id, float(seg[edge]), params.min_segment,
                          f"{plate.part_id}: edge {edge} of its top edge is {seg[edge]:.3g} mm long "
                          f"(< min_segment {params.min_segment:g} mm)"))
    s = (bot - top) / d
    for k in range(len(top) - 1):
        m = np.stack([s[k], -s[k + 1]], axis=1)
        det = float(np.linalg.det(m))
        if abs(det) < 1e-12:
            continue
        al = np.linalg.solve(m, top[k + 1] - top[k])
        if al[0] > 0 and al[1] > 0 and al.min() < d:
            out.append(Finding("axis_crossing", "", plate.part_id, float(al.min()), d,
                              f"{plate.part_id}: the node axes at the ends of edge {k} cross {al.min():.0f} mm "
                              f"below the top edge, less than the depth {d:g} mm"))
    # material left between consecutive cuts along the top edge
    cuts = []
    for v, c in plate.trims:
        cuts.append((int(plate.chain[np.flatnonzero(plate.nodes == v)[0]]), c, "end"))
    for sl in plate.slots:
        cuts.append((int(plate.chain[np.flatnonzero(plate.nodes == sl.node)[0]]), 0.5 * sl.width, "slot"))
    cuts.sort()
    arc = np.r_[0.0, np.cumsum(seg)]
    for (c0, w0, k0), (c1, w1, k1) in zip(cuts[:-1], cuts[1:]):
        left = arc[c1] - arc[c0] - w0 - w1
        if left < params.min_segment:
            out.append(Finding("short_segment", "", plate.part_id, float(left), params.min_segment, f"{plate.part_id}: only {left:.3g} mm of plate is left between "
                                                  f"the {k0} cut and the {k1} cut (< min_segment "
                                                  f"{params.min_segment:g} mm)"))
    return out


def assembly_check(plate: BeamPlate, clearance: float) -> tuple[float, float, float, bool]:
    """Can the plate slide into place through all its slots and past the plates its ends butt against along one
    direction?  The report's view of :mod:`fabrication.beams.insertion`, which the erection sequence uses too.

    Returns
    -------
    spread_deg : the angle spread of its slot directions
    play_mm : the largest sideways travel ``L·|sin Δ|`` of a mating plate in its slot (guiding length ``L``, angle
        ``Δ`` to the direction the plate goes in: :func:`~fabrication.beams.insertion.way_in`)
    extra_mm : how far that exceeds the half clearance each side of the mating plate
    slidable : some direction puts it in (:func:`~fabrication.beams.insertion.way_in` finds one)
    """
    from .insertion import way_in

    if not plate.slots and not plate.trims:
        return 0.0, 0.0, 0.0, True
    direction, blocked = way_in(plate, clearance)
    ok = blocked is None
    if not plate.slots:
        return 0.0, 0.0, 0.0, ok
    ang = np.unwrap(np.array([np.arctan2(s.direction[1], s.direction[0]) for s in plate.slots]))
    way = np.asarray(plate.frame.vec2d(direction), dtype=float)
    length = np.array([float(s.length) for s in plate.slots])
    unit = np.array([[np.cos(a), np.sin(a)] for a in ang])
    play = float((length * np.abs(unit[:, 0] * way[1] - unit[:, 1] * way[0])).max())
    extra = max(0.0, play - 0.5 * clearance)
    return float(np.degrees(ang.max() - ang.min())), play, extra, ok
