"""``joint = "halflap"`` (PP meshes): both families run through every node; where two plates cross, one slot
from above in the rows (family 0) and one from below in the columns, both centred on the common line of the
two planes and half the depth long; the slot width ``t·cot(θ/2) + clearance`` (:func:`~fabrication.beams.joints.slot_width`)."""

from __future__ import annotations

import numpy as np

from ppfab import planes as pl
from ppfab.support.structure import SupportStructure

from ..params import BeamParams
from ..plates import BeamPlate, Slot
from ..report import Defect
from . import JointType, ThroughNode, joint_type


def slot_width(thickness: float, cos_theta: float, clearance: float) -> float:
    """Width of a half-lap slot for plates of ``thickness`` crossing at ``θ``: ``t(1 + |cos θ|)/sin θ + c``."""
    c = min(abs(float(cos_theta)), 1.0)
    s = max(np.sqrt(1.0 - c * c), 1e-12)
    return thickness * (1.0 + c) / s + clearance


def halflap_node(ps: list[BeamPlate], through: list[int], v: int, a: np.ndarray, support: SupportStructure,
                 params: BeamParams) -> ThroughNode | None:
    """The slots of the two plates running through node ``v`` (axis ``a``); more than two is a defect."""
    if len(through) > 2:
        return ThroughNode("butt", float("nan"), None, {}, [
            Defect(ps[through[0]].part_id, "outline", float(len(through)), 2.0, f"node {v}",
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
        width = slot_width(params.thickness, cos, params.clearance)
        line = (p0, d)
        for plate, top in ((A, True), (B, False)):
            s2 = plate.frame.vec2d(d)
            slots.setdefault(plate.part_id, []).append(Slot(
                v, (B if top else A).part_id, top, plate.frame.to2d(p0), s2 / np.linalg.norm(s2), width,
                0.5 * params.depth, params.depth))
    return ThroughNode("halflap", width, line, slots, [])


HALFLAP = joint_type(JointType("halflap", "PP: slots from above in rows, from below in columns", cuts_ends=True,
                               segments=False, planar_requirement="half-lap joints need both families planar (PP)",
                               through=halflap_node))
