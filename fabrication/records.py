"""The typed results of the build stages and :class:`BuildRecord`, which holds them all: data only.

Each stage of :mod:`fabrication.pipeline.stages` returns one frozen record; nothing passes between stages
in an untyped dictionary.  The support structure (node axes and support planes) exists once, in
:attr:`BuildRecord.support`: the beams, the node table, ``mesh.json``, ``nodes.csv`` and the report all read it
from there.  The writers, the parts list, the report and the in-memory reader type against
:class:`BuildRecord`; :class:`fabrication.pipeline.records.Build` (what ``build(design)`` returns) adds
writing and verifying a folder to it, one layer up.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any

from .model import PartsTable

if TYPE_CHECKING:  # pragma: no cover
    from ppfab.geometry import Geometry
    from ppfab.metrics import Quality
    from ppfab.support.structure import SupportStructure

    from .beams import BeamSet
    from .design import Design
    from .flatpart import FlatPart
    from .glazing import Glazing
    from .glazing.retention import Retention
    from .glazing.seat import PaneSeat
    from .nesting import Nesting
    from .panels import Panel


@dataclass(frozen=True)
class PanelSet:
    """Glass panels (in face order) and their congruence types: ``types[type_id] = [part_id, …]``."""

    panels: tuple["Panel", ...]
    types: dict[str, list[str]]


@dataclass(frozen=True)
class NestingSet:
    """The flat parts of glass and beam plates and their nestings on stock sheets."""

    glass_parts: tuple["FlatPart", ...]
    beam_parts: tuple["FlatPart", ...]
    glass: "Nesting"
    plates: "Nesting"


@dataclass(frozen=True)
class NodeTable:
    """One record per mesh vertex, in vertex order: the rows of ``nodes.json`` (see :mod:`fabrication.nodes`)."""

    records: tuple[dict[str, Any], ...]


@dataclass(frozen=True)
class Summary:
    """Totals for the manifest, the report and ``ppfab build --json`` (mm, m, m², kg).  ``beam_mass_kg`` is the
    beam plates alone; ``steel_mass_kg`` the whole steel take-off (beam plates, glazing strips, splice cover
    plates); ``weld_length_m`` every weld of ``welds.csv``; ``retention_mass_kg`` the glass retention (setting
    blocks, stops, pressure gaskets and plates, cover caps, screws: their ``parts.csv`` masses)."""

    extent_mm: list[float]
    panels: int
    panel_types: int
    glass_area_m2: float
    glass_weight_kg: float
    beams: int
    beam_plates: int
    beam_types: int
    beam_length_m: float
    beam_mass_kg: float
    plate_area_m2: float
    nodes: int
    glass_sheets: int
    glass_utilisation: float
    glass_lower_bound: int
    plate_sheets: int
    plate_utilisation: float
    plate_lower_bound: int
    torsion_max_deg: float
    steel_mass_kg: float = 0.0
    weld_length_m: float = 0.0
    retention_mass_kg: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        """Plain values in field order (the manifest's ``summary``)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True, eq=False)
class BuildRecord:
    """Everything a build computed, stage by stage (data only).

    ``seats``: where every pane rests on its gaskets (:func:`fabrication.glazing.seat.seat_panes`, in panel
    order; empty without glazing strips); ``retention``: the glass retention placed on the built panes and
    strips (:func:`fabrication.glazing.retention.retention_of`; ``None`` without strips or with
    ``retention = "none"``).  ``parts`` is the parts list, made once from the other records
    (:func:`fabrication.parts.parts_table`) for every writer that lists parts.  ``times`` holds the seconds each
    stage took (not written to any file, so builds stay byte-reproducible).
    """

    design: "Design"
    geometry: "Geometry"
    quality: "Quality"
    support: "SupportStructure"
    panels: PanelSet
    beams: "BeamSet"
    nesting: NestingSet
    nodes: NodeTable
    summary: Summary
    glazing: "Glazing | None" = None
    seats: tuple["PaneSeat", ...] = ()
    retention: "Retention | None" = None
    parts: PartsTable = field(default_factory=PartsTable)
    times: dict[str, float] = field(default_factory=dict, compare=False)

    @property
    def mesh(self) -> Any:
        """The placed mesh in mm (:class:`~ppfab.mesh.QuadGrid` or :class:`~ppfab.mesh.QuadMesh`)."""
        return self.geometry.mesh

    def pane_offsets(self) -> dict[str, float]:
        """Part id → the height (mm) of each pane's underside above its face's plane along its outside normal,
        as every model places it (``panels.step``, IFC, Rhino, glTF): its seat on the gaskets, 0 (on the mesh
        face) for a build without glazing strips (``[glazing] support = "none"``)."""
        seats = {s.panel: s.offset for s in self.seats}
        return {p.part_id: float(seats.get(p.part_id, 0.0)) for p in self.panels.panels}
