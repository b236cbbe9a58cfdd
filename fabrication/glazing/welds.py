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

A **half-lap crossing** (two plates running through a node, slotted into each other) is welded along the
crossing line in its four corners, over the full depth (two runs on each face of each plate: length ``4 D``,
``joint = "halflap"``): the slots alone transfer contact forces only, the welds make the crossing a rigid node
of the gridshell.  The corners meet at ``dihedral`` and ``180° − dihedral``; the preparation follows the same
rule as a T-joint.  ``[beams] halflap_welds = false`` leaves them out (a grid whose crossings the engineer
designs as hinges, or joins with bolted cleats).

A **corner node** — every plate there ends, none runs through (the corners of a boundary) — joins its ending
plates pairwise, each with the one nearest around the axis: their square ends, set back to clear each other on the
bisector, form an open V of ``180° − opening`` along the node axis, welded with full penetration from outside with
a sealing run inside (length ``2 D``, throat ``t``, ``joint = "corner"``).

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


HALFLAP_RUNS = 4
"""Weld runs along the crossing line of a welded half-lap: one in each of its four corners."""

CORNER_PREPARATION = "corner: full penetration in the open V of the square ends, sealing run inside"


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


def halflap_welds(joints, depth: float, thickness: float) -> list[Weld]:
    """The :class:`Weld` of every pair of plates of different beams crossing at a ``halflap`` joint: along the
    crossing line in its four corners over the depth (module docstring); ``part`` is the plate listed first at
    the node (the rows' before the columns'), ``to`` the other."""
    out: list[Weld] = []
    for j in joints:
        if j.kind != "halflap":
            continue
        role = dict(zip(j.parts, j.roles))
        for a, b, dihedral, _opening, same in j.angles:
            if not same and role.get(a) == "through" and role.get(b) == "through":
                prep, throat = preparation(float(dihedral), thickness)
                out.append(Weld(int(j.vertex), a, b, float(dihedral), HALFLAP_RUNS * depth, prep, throat,
                                "halflap"))
    return out


def corner_pairs(parts: tuple[str, ...], roles: tuple[str, ...],
                 angles: tuple[tuple[str, str, float, float, bool], ...]) -> list[tuple[str, str, float, float]]:
    """``(part, to, dihedral °, opening °)`` of the welds of a node where every plate ends: each plate with the
    plate of another beam nearest around the axis (smallest opening), each pair once, in the order of ``angles``.

    >>> corner_pairs(("A", "B"), ("end", "end"), (("A", "B", 80.0, 95.0, False),))
    [('A', 'B', 80.0, 95.0)]
    """
    if len(parts) < 2 or any(r != "end" for r in roles):
        return []
    nearest: dict[str, tuple[float, int]] = {}
    pairs = [(a, b, float(d), float(op)) for a, b, d, op, same in angles if not same and op == op]
    for k, (a, b, _d, op) in enumerate(pairs):
        for x in (a, b):
            if x not in nearest or op < nearest[x][0]:
                nearest[x] = (op, k)
    chosen = sorted({k for _, k in nearest.values()})
    return [pairs[k] for k in chosen]


def corner_welds(joints, depth: float, thickness: float) -> list[Weld]:
    """The :class:`Weld` of every pair :func:`corner_pairs` gives at the nodes where every plate ends
    (``butt`` joints without a plate running through)."""
    out: list[Weld] = []
    for j in joints:
        if j.kind != "butt":
            continue
        for a, b, dihedral, _opening in corner_pairs(j.parts, j.roles, j.angles):
            out.append(Weld(int(j.vertex), a, b, dihedral, 2.0 * depth, CORNER_PREPARATION, float(thickness),
                            "corner"))
    return out
