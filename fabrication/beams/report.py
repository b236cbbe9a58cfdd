"""The beam report: one record per plate (size, mass, assembly check) and the defects found.

A *defect* is a plate that would be degenerate or wrong — depth beyond the crossing of two consecutive node
axes, a zero-length or over-trimmed segment, plates meeting at less than ``min_angle_deg``, a polyline that is
not planar where a planar plate is needed, an outline that falls apart — always named by part id with the
measured value and the limit it breaks: a :class:`~ppfab.finding.Finding` whose ``code`` is its kind
(``axis_crossing``, ``short_segment``, ``small_angle``, ``not_planar``, ``too_long``, ``outline``).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from ppfab.errors import FabricationError
from ppfab.finding import Finding


@dataclass(frozen=True)
class BeamRecord:
    """One plate in the report (lengths mm, area mm², mass kg, angles degrees).

    ``slidable``: the plate can be put in place along one direction through all its half-lap slots and past the
    plates its ends butt against (:func:`fabrication.beams.joints.assembly_check`, as ``erection.csv`` says); a
    row plate always is, going in first, into nothing.  ``sliding_play_mm`` is the largest sideways travel of a
    mating plate in its slot along the way the plate goes in (slot length × sine of the angle between them) and
    ``extra_clearance_mm`` how far that exceeds half the clearance, each side of the mating plate (0 for a row).
    """

    part_id: str
    beam_id: str
    family: str
    piece: int
    nodes: int
    length_mm: float
    area_mm2: float
    mass_kg: float
    slots: int
    slot_spread_deg: float
    sliding_play_mm: float
    extra_clearance_mm: float
    slidable: bool
    plane_deviation_mm: float
    type_id: str = ""

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class BeamReport:
    """Records of all plates, the defects, and torsion of the support structure at beam depth."""

    records: tuple[BeamRecord, ...]
    defects: tuple[Finding, ...]
    joint: str
    torsion_max_deg: float
    torsion_offset_max_mm: float

    @property
    def ok(self) -> bool:
        return not self.defects

    def totals(self) -> dict:
        r = self.records
        return {
            "plates": len(r),
            "beams": len({x.beam_id for x in r}),
            "types": len({x.type_id for x in r if x.type_id}),
            "length_m": sum(x.length_mm for x in r) / 1000.0,
            "mass_kg": sum(x.mass_kg for x in r),
            "slots": sum(x.slots for x in r),
            "not_slidable": sum(1 for x in r if not x.slidable),
            "max_extra_clearance_mm": max((x.extra_clearance_mm for x in r), default=0.0),
            "defects": len(self.defects),
            "torsion_max_deg": self.torsion_max_deg,
            "torsion_offset_max_mm": self.torsion_offset_max_mm,
        }

    def as_dict(self) -> dict:
        return {"joint": self.joint, "totals": self.totals(), "defects": [d.as_dict() for d in self.defects],
                "plates": [x.as_dict() for x in self.records]}

    def table(self) -> str:
        """Human-readable summary."""
        t = self.totals()
        lines = [f"beams: {t['beams']} ({t['plates']} plates, {t['types']} types), joint {self.joint}",
                 f"total length {t['length_m']:.1f} m, mass {t['mass_kg']:.0f} kg, slots {t['slots']}",
                 f"torsion max {t['torsion_max_deg']:.3g} deg ({t['torsion_offset_max_mm']:.3g} mm at beam depth)",
                 f"not slidable: {t['not_slidable']} (largest extra clearance {t['max_extra_clearance_mm']:.2f} mm)",
                 f"defects: {t['defects']}"]
        lines += [f"  {d.message}" for d in self.defects[:20]]
        if len(self.defects) > 20:
            lines.append(f"  … and {len(self.defects) - 20} more")
        return "\n".join(lines)

    def raise_if_defects(self) -> None:
        """:class:`~ppfab.errors.FabricationError` naming every defective plate (worst first per kind)."""
        if not self.defects:
            return
        shown = "; ".join(d.message for d in self.defects[:6])
        more = f" (and {len(self.defects) - 6} more)" if len(self.defects) > 6 else ""
        err = FabricationError(f"{len(self.defects)} beam defect(s): {shown}{more}")
        err.defects = list(self.defects)
        raise err
