"""The erection sequence: in which order the parts of a build go up, and along which direction each goes in.

With half-lap joints the row plates (family 0) carry their slots from above and the column plates (family 1)
from below (:mod:`fabrication.beams.joint_types.halflap`): the rows stand first, the columns are lowered onto
them through their slots.  Once the glazing strips are on the row plates a column can no longer be lowered
(its slots would pass through the strips), so the order matters.  The plan here is

====  ============  =====================================================================================
step  kind          insertion direction (the part moves along it from far away into its place)
====  ============  =====================================================================================
1     ``row``       the row plates, lowered along their common slot direction (top edge → bottom edge)
2     ``column``    the column plates, lowered along their common slot direction through the rows' slots
3     ``weld``      the welds of ``welds.csv`` (half-lap crossings, corner and T-joints, welded splices); no
                    solid, no direction
4     ``splice``    the splice cover plates, lowered beside the beam plate's faces along its first piece's
                    direction (pushed on along the normal from far away they would pass through the next beam)
5     ``strip``     the glazing strips, lowered onto the plates' top edges along the strip's down (−up)
6     ``gasket``    the gaskets, laid onto their strips by hand along the same direction
7     ``setting_block``  the setting blocks, lowered onto the gasket under each pane's down-slope edge along
                    the pane's inside normal (−N): the pane comes down against them
8     ``stop``      the stops behind the blocks (steep panes), the same way
9     ``panel``     the panes, lowered onto their gaskets along their inside normal (−N)
10    ``pressure_gasket``  the EPDM gaskets of the pressure plates, lowered onto the panes along the strip's down
11    ``pressure_plate``   the pressure plates, the same way
12    ``screw``     the clamping screws of each plate (one row per plate, all its screws), down along the strip's
                    down through the plate's, gasket's and strip gasket's holes into the strip
13    ``cover_cap`` the cover caps, clipped on from above along the strip's down
====  ============  =====================================================================================

Empty steps are left out and the rest numbered 1, 2, …; the retention parts are those of
:attr:`fabrication.records.BuildRecord.retention` (none without glazing or with ``retention = "none"``).
The rows go in first, into nothing, along the bisector of their slots' and end axes' directions.  A column goes
in along the middle of the directions its slots and end cuts admit (:mod:`fabrication.beams.insertion`): a
slot admits the directions within ``asin(c/2L)`` of its own (``c`` the joint clearance, half of it on either
side of the mating plate, ``L`` the slot's length), an end cut butting against a row the half-plane of directions
that bring the end towards it (the gap closes to its final ``c/2`` as the part arrives).  Where none is left,
the plate cannot be put in along any single direction: the plan keeps it in its step with the bisector and
records a :class:`Blocked` entry naming the part, the angle spread and the sideways travel (``ppfab verify``'s
erection check then measures the sweep;
``[beams] segment = ["blocked"]`` cuts such columns across the node axis at the nodes a greedy scan finds to
give every part a way in, :func:`fabrication.beams.insertion.node_breaks`; a one-edge part always goes in).
Before, an end cut counted as a guide on both sides of its axis, and every one-edge segment between two rows was blocked
by the angle between its two end axes.

Nothing here measures a collision: ``fabrication/verify/erection.py`` proves the order on the written solids.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .beams.insertion import Blocked, guide_bisector, way_in
from .contract import gasket_id, node_id

if TYPE_CHECKING:  # pragma: no cover
    from .beams import BeamSet
    from .glazing import Glazing
    from .glazing.retention import Retention
    from .panels import Panel

ERECTION_SVG = "drawings/erection.svg"
"""The plan view of the parts coloured by erection step, with a legend."""

STEP_KINDS: tuple[str, ...] = ("row", "column", "weld", "splice", "strip", "gasket", "setting_block", "stop",
                               "panel", "pressure_gasket", "pressure_plate", "screw", "cover_cap")
"""The kinds in erection order (one step each when present)."""

STEP_TITLES = {"row": "row plates (family 0)", "column": "column plates (family 1), lowered through the slots",
               "weld": "welds at the crossings and joints", "splice": "splice cover plates",
               "strip": "glazing strips, welded on", "gasket": "gaskets", "setting_block": "setting blocks",
               "stop": "stops behind the setting blocks", "panel": "panes on their gaskets",
               "pressure_gasket": "pressure gaskets on the panes", "pressure_plate": "pressure plates",
               "screw": "clamping screws through the plates", "cover_cap": "cover caps"}

NEEDS = {"row": (), "column": ("row",), "weld": ("column",), "splice": ("column",), "strip": ("weld",),
         "gasket": ("strip",), "setting_block": ("gasket",), "stop": ("setting_block",),
         "panel": ("gasket", "setting_block", "stop"), "pressure_gasket": ("panel",),
         "pressure_plate": ("pressure_gasket",), "screw": ("pressure_plate",), "cover_cap": ("screw",)}
"""The kinds a step needs done before it (``after`` is the latest step among them, 0 for none)."""


@dataclass(frozen=True)
class Insertion:
    """One part of the sequence: its id, kind (:data:`STEP_KINDS`), step (1-based), the unit direction ``(3,)`` it
    moves along into its place (zeros for a weld) and ``after``, the step it needs done (0 for none)."""

    part_id: str
    kind: str
    step: int
    direction: tuple[float, float, float]
    after: int


@dataclass(frozen=True)
class ErectionPlan:
    """The sequence: ``insertions`` in step order, ``steps`` the kind of each step (index 0 is step 1) and the
    plates that no single direction puts in (``blocked``)."""

    insertions: tuple[Insertion, ...]
    steps: tuple[str, ...]
    blocked: tuple[Blocked, ...]

    def rows(self) -> list[dict[str, str]]:
        """The rows of ``erection.csv`` (:data:`fabrication.contract.ERECTION_COLUMNS`), directions to 6 decimals."""
        out = []
        spread = {b.part_id: f"{b.spread_deg:.2f}" for b in self.blocked}
        for p in self.insertions:
            d = ["" if p.kind == "weld" else f"{round(x, 6) + 0.0:.6f}" for x in p.direction]
            out.append({"step": str(p.step), "part_id": p.part_id, "kind": p.kind, "direction_x": d[0],
                        "direction_y": d[1], "direction_z": d[2], "after": str(p.after),
                        "blocked_spread_deg": spread.get(p.part_id, "")})
        return out


def _unit(v: np.ndarray) -> tuple[float, float, float]:
    n = float(np.linalg.norm(v))
    if n < 1e-12:
        raise ValueError("zero insertion direction")
    u = np.asarray(v, dtype=float) / n
    return float(u[0]), float(u[1]), float(u[2])


def weld_id(part: str, to: str, vertex: int) -> str:
    """The erection row of a weld: ``weld:B-W03/B-U02@N0042`` (node), ``weld:B-U03-S01/B-U03-S02`` (a splice)."""
    return f"weld:{part}/{to}" + (f"@{node_id(vertex)}" if vertex >= 0 else "")


def erection_plan(beams: "BeamSet", glazing: "Glazing | None", panels: "tuple[Panel, ...] | list[Panel]",
                  retention: "Retention | None" = None) -> ErectionPlan:
    """The erection sequence of a build's beam plates, glazing, panes and the ``retention`` parts holding them
    (see the module doc)."""
    by_kind: dict[str, list[tuple[str, tuple[float, float, float]]]] = {k: [] for k in STEP_KINDS}
    plates = {p.part_id: p for p in beams.plates}
    clearance = float(beams.params.clearance_mm)   # a square slot's width beyond the nominal plate thickness
    blocked = []
    for plate in beams.plates:
        kind = "row" if plate.family == 0 else "column"
        # the rows go in first, into nothing, along their slots' bisector; the columns onto them
        if kind == "row":                          # the rows go in first, into nothing
            way = guide_bisector(plate)
        else:
            way, b = way_in(plate, clearance)
            if b is not None:
                blocked.append(b)
        by_kind[kind].append((plate.part_id, _unit(way)))
    if glazing is not None:
        for w in glazing.welds:
            by_kind["weld"].append((weld_id(w.part, w.to, w.vertex), (0.0, 0.0, 0.0)))
        for sp in glazing.splices:
            lower = guide_bisector(plates[sp.pieces[0]])  # lowered beside the beam's face, as its first piece
            n = sp.frame.normal
            for pid in sp.part_ids:
                by_kind["splice"].append((pid, _unit(lower - (lower @ n) * n)))
        for st in glazing.strips:
            down = _unit(-st.frame.normal)
            by_kind["strip"].append((st.part_id, down))
            by_kind["gasket"].append((gasket_id(st.part_id), down))
    for pane in panels:
        by_kind["panel"].append((pane.part_id, _unit(-pane.frame.normal)))
    if retention is not None:
        for part in retention.parts:
            by_kind[part.kind].append((part.part_id, _unit(-part.frame.normal)))
        for sc in retention.screws:
            by_kind["screw"].append((sc.part_id, _unit(-sc.frame.normal)))
    steps = tuple(k for k in STEP_KINDS if by_kind[k])
    number = {k: i + 1 for i, k in enumerate(steps)}

    def after(kind: str) -> int:
        need = [number[k] for k in NEEDS[kind] if k in number]
        if need:
            return max(need)
        earlier = [number[k] for k in steps if number[k] < number[kind]]   # a needed kind absent: the one before
        return max(earlier, default=0)

    insertions = tuple(Insertion(pid, kind, number[kind], d, after(kind))
                       for kind in steps for pid, d in by_kind[kind])
    return ErectionPlan(insertions, steps, tuple(blocked))
