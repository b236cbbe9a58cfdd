"""Weld data of the butt joints: where a plate ends against a plate that runs through a node.

For every ending plate ``a`` at a node with a plate ``b`` running through it, the joint is a T-joint along
``a``'s end line, which runs down the node axis over the beam depth ``D`` (``bottom = top + D·â``), welded
from both sides: weld length ``2 D``.  ``dihedral`` is the angle between the two plates' planes (0…90°,
:class:`~fabrication.beams.joints.NodeJoint`); the T-joint's fusion faces meet at ``dihedral`` on one side and
``180° − dihedral`` on the other.  The preparation follows EN 1993-1-8 §4.3.2.1 (fillet welds only where the
fusion faces meet at 60°…120°; below 60° a weld counts as a partial-penetration butt weld) and the joint
preparations of EN ISO 9692-1:

* ``dihedral ≥ 60°``: double fillet weld, no preparation, throat ``a = ⌈0.55 t⌉`` (a full-strength rule of
  thumb for S355 to be confirmed by the structural design);
* ``30° ≤ dihedral < 60°``: single bevel (HV, 45°) on the acute side, full penetration, fillet on the
  obtuse side;
* ``dihedral < 30°``: the plates are nearly in line: single-V butt weld, 60° included angle, 2 mm root gap.

A welded splice (:func:`~fabrication.glazing.splices.welded_splices`) joins two pieces of one beam in line
across their cut: a full-penetration butt weld over the cut line, single V up to 10 mm plate and double V
(welded from both faces, less distortion) above (EN ISO 9692-1 1.3 and 2.5.1), ``joint = "splice"`` and no
node in ``welds.csv``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Weld:
    """One welded joint: node (vertex id; −1 for a splice, which lies inside an edge), the ending part, the part
    it is welded to, dihedral (degrees), total weld length (mm), preparation, throat (mm) and the joint:
    ``"T"`` (a plate ending against one that runs through a node) or ``"splice"`` (two pieces of a beam in line
    across a cut)."""

    vertex: int
    part: str
    to: str
    dihedral_deg: float
    length_mm: float
    preparation: str
    throat_mm: float
    joint: str = "T"


def preparation(dihedral_deg: float, thickness: float) -> tuple[str, float]:
    """``(preparation, throat mm)`` for a T-joint of plates ``thickness`` mm meeting at ``dihedral_deg``."""
    if dihedral_deg >= 60.0:
        return "double fillet", float(math.ceil(0.55 * thickness))
    if dihedral_deg >= 30.0:
        return "single bevel HV 45 deg full penetration + fillet", float(thickness)
    return "single V 60 deg, root gap 2 mm, full penetration", float(thickness)


def splice_preparation(thickness: float) -> tuple[str, float]:
    """``(preparation, throat mm)`` of a full-penetration butt weld joining two plates of ``thickness`` mm in
    line."""
    if thickness <= 10.0:
        return "single V 60 deg, root gap 2 mm, full penetration, root back-gouged and sealed", float(thickness)
    return "double V 60 deg, root face 2 mm, root gap 2 mm, full penetration", float(thickness)


def butt_welds(joints, depth: float, thickness: float) -> list[Weld]:
    """The :class:`Weld` of every ending plate against every plate running through the same node, at the
    ``butt`` joints of ``joints`` (:class:`~fabrication.beams.joints.NodeJoint`)."""
    out: list[Weld] = []
    for j in joints:
        if j.kind != "butt":
            continue
        role = dict(zip(j.parts, j.roles))
        for a, b, dihedral, _opening, same in j.angles:
            if same:
                continue
            for end, through in ((a, b), (b, a)):
                if role.get(end) == "end" and role.get(through) == "through":
                    prep, throat = preparation(float(dihedral), thickness)
                    out.append(Weld(int(j.vertex), end, through, float(dihedral), 2.0 * depth, prep, throat))
    return out
