"""From a support structure to checked beam plates: layout → joints → outlines → checks → report."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ppfab.errors import DesignError
from ppfab.finding import Finding
from ppfab.support.structure import SupportStructure
from ppfab.topology import FAMILY_NAMES

from .flat import flat_parts, type_ids
from .insertion import node_breaks
from .joints import NodeJoint, analyse_nodes, apply_joints, assembly_check, plate_checks
from .params import BeamParams
from .plates import BLOCKED_RULE, BeamPlate, SpliceClearances, layout_plates
from .report import BeamRecord, BeamReport
from .torsion import check_torsion


@dataclass(frozen=True, eq=False)
class BeamSet:
    """All beam plates of a structure with their joints and report."""

    support: SupportStructure
    params: BeamParams
    plates: tuple[BeamPlate, ...]
    joints: tuple[NodeJoint, ...]
    report: BeamReport
    types: dict
    node_breaks: tuple[tuple[int, tuple[int, ...]], ...] = ()
    """``(polyline, vertices)`` of every column beam ``[beams] segment = ["blocked"]`` cut across its node axes,
    and where (:func:`fabrication.beams.insertion.node_breaks`)."""

    @cached_property
    def by_id(self) -> dict[str, BeamPlate]:
        return {p.part_id: p for p in self.plates}

    @cached_property
    def joint_at(self) -> dict[int, NodeJoint]:
        """Vertex id → its :class:`NodeJoint`."""
        return {j.vertex: j for j in self.joints}

    def flat_parts(self) -> list:
        """:class:`~fabrication.flatpart.FlatPart` of every plate (kind ``"beam"``)."""
        return flat_parts(list(self.plates), self.params.material, self.params.density, self.types)



def with_splice_holes(plates: list[BeamPlate], splice_params, ups=None) -> list[BeamPlate]:
    """The plates with the bolt holes of every bolted splice (:func:`fabrication.glazing.splices.make_splices`) cut
    in the pieces it joins: each cover plate hole, mapped from the first piece's frame through 3D into each
    piece's own frame, in the piece whose outline holds it (the holes on its side of the cut), with the cover
    plate's hole diameter."""
    from dataclasses import replace

    from shapely.geometry import Point, Polygon

    from ..glazing.splices import make_splices

    extra: dict[str, list[np.ndarray]] = {}
    by_id = {p.part_id: p for p in plates}
    for s in make_splices(plates, splice_params, ups):
        at3 = s.frame.to3d(s.holes)
        for pid in s.pieces:
            piece = by_id[pid]
            body = Polygon(piece.outline)
            xy = piece.frame.to2d(at3)
            inside = np.array([body.contains(Point(q).buffer(0.5 * s.hole)) for q in xy], dtype=bool)
            extra.setdefault(pid, []).append(np.c_[xy[inside], np.full(int(inside.sum()), s.hole)])
    return [replace(p, holes=np.concatenate([p.holes, *extra[p.part_id]])) if p.part_id in extra else p
            for p in plates]


def build_beams(support: SupportStructure, params: BeamParams | None = None, strict: bool = True,
                max_height: float = 0.0, splice_clearances: SpliceClearances = (("bolted", 0.0),),
                splice_params=None, splice_ups=None) -> BeamSet:
    """Planar beam plates with joints for a mesh with a support structure.

    Parameters
    ----------
    support : node axes and support planes (:mod:`ppfab.support`), in mm
    params : beam parameters (defaults when omitted)
    strict : raise :class:`~fabrication.beams.torsion.TorsionError` when the support's torsion at beam depth
        exceeds ``params.max_torsion_mm`` (listing the edges), and :class:`~ppfab.errors.FabricationError`
        naming every defective plate (with its measured value) instead of returning them in ``report.defects``
    max_height : the widest flat piece the plate stock holds across its length, mm (0 = no limit): long
        curved beams are cut so that their pieces fit it
    splice_clearances : the splice kinds a split beam may get, in order, each with how much further (mm) than
        the joints need its cuts stay from a node (:mod:`fabrication.glazing.splices`); a beam takes the first
        kind its cuts fit with (``meta["splice"]`` of its pieces)
    splice_params : the ``[splices]`` table; given, the bolt holes of the bolted splices are cut in the pieces
        they join (:func:`with_splice_holes`)
    splice_ups : the glazing strips' ups by mesh edge (:data:`fabrication.glazing.splices.EdgeUps`), which lower
        the cover plates under leaning strips (``None``: no glazing strips)

    Returns
    -------
    BeamSet
    """
    params = params or BeamParams()
    if not isinstance(params, BeamParams):
        raise DesignError("beams", f"expected BeamParams, got {type(params).__name__}")
    if strict:
        check_torsion(support, params)
    plates, defects, joints, final = _laid_out(support, params, max_height, splice_clearances)
    breaks: dict[int, set[int]] = {}
    if BLOCKED_RULE in params.segment:
        for _ in range(_BREAK_ROUNDS):
            more = {(p.polyline, k) for p in final if p.family == 1
                    for k in node_breaks(p, params.clearance_mm) if k not in breaks.get(p.polyline, ())}
            if not more:
                break
            for l, k in more:
                breaks.setdefault(l, set()).add(k)
            plates, defects, joints, final = _laid_out(support, params, max_height, splice_clearances, breaks)
    if splice_params is not None:
        final = with_splice_holes(final, splice_params, splice_ups)
    for p in final:
        defects += plate_checks(p, params)
    types = type_ids(final)
    records = []
    for p in final:
        spread, play, extra, ok = assembly_check(p, params.clearance_mm)
        if p.family == 0:              # the rows go in first, into nothing (fabrication.erection): nothing blocks
            extra, ok = 0.0, True
        area = p.area
        records.append(BeamRecord(p.part_id, p.beam_id, FAMILY_NAMES[p.family], p.piece, len(p.nodes),
                                  p.length, area, area * p.thickness * params.density * 1e-9, len(p.slots),
                                  spread, play, extra, ok, p.plane_deviation, types[p.part_id]))
    off = support.torsion_offset(params.depth) if len(support.edges) else np.zeros(1)
    report = BeamReport(tuple(records), tuple(_dedupe(defects)), params.joint,
                        float(np.degrees(support.torsion.max())) if len(support.edges) else 0.0, float(off.max()))
    if strict:
        report.raise_if_defects()
    return BeamSet(support, params, tuple(final), tuple(joints), report, types,
                   tuple((l, tuple(sorted(breaks[l]))) for l in sorted(breaks)))


_BREAK_ROUNDS = 8
"""How often the ``blocked`` rule lays the plates out again.  A beam cut at nodes has its splice cuts planned
again between the breaks, which can make new pieces that no direction puts in; those are cut in the next round
(fig16_conical1_pp_conical: 141, 82, 8 and 4 new breaks in four rounds, then none).  What is still blocked
after the last round is said by the erection sequence (:mod:`fabrication.erection`)."""


# root causes first: a self-intersecting outline is usually the consequence of crossing axes
def _laid_out(support: SupportStructure, params: BeamParams, max_height: float, splice_clearances: SpliceClearances,
              breaks: dict[int, set[int]] | None = None
              ) -> tuple[list[BeamPlate], list[Finding], list[NodeJoint], list[BeamPlate]]:
    """The plates as laid out (``breaks``: polyline → vertices it is cut at), the defects so far, the node joints
    and the plates with their joints cut."""
    plates, defects = layout_plates(support, params, max_height, splice_clearances, breaks)
    ids = [p.part_id for p in plates]
    if len(set(ids)) != len(ids):  # pragma: no cover - naming is by construction unique
        raise DesignError("beams", "duplicate part ids")
    joints, trims, slots, jdef = analyse_nodes(plates, support, params)
    defects += jdef
    final = [apply_joints(p, trims.get(p.part_id, []), slots.get(p.part_id, []), params, defects) for p in plates]
    return plates, defects, joints, final


_PRIORITY = {"not_planar": 0, "axis_crossing": 1, "small_angle": 2, "short_segment": 3, "too_long": 4, "outline": 5}


def _dedupe(defects: list[Finding]) -> list[Finding]:
    seen, out = set(), []
    for d in defects:
        key = (d.element, d.code, d.message)
        if key not in seen:
            seen.add(key)
            out.append(d)
    return sorted(out, key=lambda d: _PRIORITY.get(d.code, 9))
