"""``joint = "halflap"`` (PP meshes): both families run through every node; where two plates cross, one slot
from above in the rows (family 0) and one from below in the columns, both centred on the common line of the
two planes and ``slot_play`` deeper than half the depth (:attr:`~fabrication.beams.params.BeamParams.slot_length`),
so the plates seat on each other's slot ends with ``2·slot_play`` to spare instead of bottoming out; the slot width
``t_max·cot(θ/2) + fit`` (:func:`slot_width`), ``t_max`` the thickest plate EN 10029 allows with
``clearance = "auto"`` (:mod:`fabrication.beams.tolerance`)."""

from __future__ import annotations

import numpy as np

from ppfab import planes as pl
from ppfab.finding import Finding
from ppfab.support.structure import SupportStructure

from ..params import BeamParams
from ..plates import BeamPlate, Slot
from . import JointType, ThroughNode, joint_type


def slot_width(thickness: float, cos_theta: float, clearance: float, deviation: float = 0.0) -> float:
    """Width of a half-lap slot for plates of ``thickness`` (up to ``deviation`` thicker) crossing at ``θ``:
    ``(t + dev)(1 + |cos θ|)/sin θ + c``."""
    c = min(abs(float(cos_theta)), 1.0)
    s = max(np.sqrt(1.0 - c * c), 1e-12)
    return (thickness + deviation) * (1.0 + c) / s + clearance


def halflap_node(ps: list[BeamPlate], through: list[int], v: int, a: np.ndarray, support: SupportStructure,
                 params: BeamParams) -> ThroughNode | None:
    """The slots of the two plates running through node ``v`` (axis ``a``); more than two is a defect."""
    if len(through) > 2:
        return ThroughNode("butt", float("nan"), None, {}, [
            Finding("outline", "", ps[through[0]].part_id, float(len(through)), 2.0,
                   f"node {v}: {len(through)} plates run through it, a half-lap joins two")])
    if len(through) != 2:
        return None
    i, j = through
    if ps[j].family < ps[i].family:
        i, j = j, i
    A, B = ps[i], ps[j]
    cos = abs(float(A.plane[:3] @ B.plane[:3]))
    slots: dict[str, list[Slot]] = {}
    width, line = float("nan"), None
    if cos < np.cos(np.radians(max(params.min_angle_deg, 1e-3))):
        point, d = pl.line_of_two_planes(A.plane, B.plane)
        d = d if d @ a >= 0 else -d
        x = support.vertices[v]
        p0 = point + ((x - point) @ d) * d
        width = slot_width(params.thickness, cos, params.fit, params.thickness_deviation)
        line = (p0, d)
        for plate, top in ((A, True), (B, False)):
            s2 = plate.frame.vec2d(d)
            slots.setdefault(plate.part_id, []).append(Slot(
                v, (B if top else A).part_id, top, plate.frame.to2d(p0), s2 / np.linalg.norm(s2), width,
                params.slot_length if top else params.depth - params.slot_length, params.depth))
    return ThroughNode("halflap", width, line, slots, [])


HALFLAP = joint_type(JointType("halflap", "PP: slots from above in rows, from below in columns", cuts_ends=True,
                               segments=False, planar_requirement="half-lap joints need both families planar (PP)",
                               through=halflap_node))
