"""The figures a sweep collects for every variant, and the cost model.

:data:`FIGURES` is the registry: each :class:`Figure` names its unit, whether smaller or larger is better
(``--best`` and the Pareto front read it) and the first stage that measures it (:data:`STAGES`).  A figure
of a stage the sweep does not run is left empty (null) in the results table.  :func:`measure` turns the
records of the build stages into one :class:`Figures` row; :func:`cost` prices it with the sweep's ``[cost]``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from ppfab.geometry import Geometry
    from ppfab.metrics import Quality
    from ppfab.support.structure import SupportStructure

    from ..pipeline.records import Build, PanelSet

STAGES: tuple[str, ...] = ("geometry", "nesting", "files")
"""What a sweep runs of each variant: ``geometry`` (mesh, quality, support, panels and their types),
``nesting`` (every compute stage of a build: beams, glazing, nesting, nodes; no file), ``files`` (a whole
build written into ``RESULTS/builds/<variant>/``, with its report)."""


@dataclass(frozen=True)
class Figure:
    """One column of the results table: ``unit``, ``better`` (``"min"`` or ``"max"``), the first ``stage``
    that measures it and what it is (``doc``)."""

    name: str
    unit: str
    better: str
    stage: str
    doc: str


FIGURES: dict[str, Figure] = {f.name: f for f in (
    Figure("panels", "", "min", "geometry", "glass panels"),
    Figure("panel_types", "", "min", "geometry", "congruent panel types at [panels] congruence_tolerance"),
    Figure("glass_area_m2", "m²", "min", "geometry", "glass area"),
    Figure("panel_deviation_mm", "mm", "min", "geometry", "largest distance of a panel corner from its plane"),
    Figure("surface_deviation_mm", "mm", "min", "geometry",
           "largest distance of a vertex from the design surface (an optimised mesh file; 0 for a construction)"),
    Figure("torsion_max_deg", "°", "min", "geometry", "largest torsion of a node axis pair along an edge"),
    Figure("glass_sheets", "", "min", "nesting", "glass stock sheets of the nesting"),
    Figure("glass_yield", "", "max", "nesting", "share of the glass sheets' area used by panels (0–1)"),
    Figure("plate_sheets", "", "min", "nesting", "steel plate sheets of the beam nesting"),
    Figure("plate_yield", "", "max", "nesting", "share of the plate sheets' area used by beam plates (0–1)"),
    Figure("steel_kg", "kg", "min", "nesting", "steel take-off: mass of the beam plates"),
    Figure("beam_length_m", "m", "min", "nesting", "length of the beams"),
    Figure("weld_m", "m", "min", "nesting", "weld length of the joints and welded splices"),
    Figure("bite_min_mm", "mm", "max", "nesting", "smallest bite of a pane edge on its glazing strip"),
    Figure("node_types", "", "min", "nesting", "node types (joint, plate roles, angles at 1°)"),
    Figure("cost", "", "min", "geometry", "the [cost] model: unit prices times quantities"),
    Figure("cpu_s", "s", "min", "geometry", "CPU seconds of the thread that computed the variant"),
    Figure("wall_s", "s", "min", "geometry", "wall seconds the variant took on its worker"),
)}
"""Every figure, in the order of the results table's columns."""

COST_KEYS: dict[str, str] = {
    "glass_sheet": "glass_sheets", "plate_sheet": "plate_sheets", "steel_kg": "steel_kg", "weld_m": "weld_m",
    "panel_type": "panel_types", "node_type": "node_types", "glass_m2": "glass_area_m2",
}
"""``[cost]`` key (price per unit) → the figure it multiplies."""


@dataclass(frozen=True)
class Figures:
    """The measured figures of one variant (``None``: not measured at the stage the sweep ran)."""

    values: dict[str, float | int | None] = field(default_factory=dict)

    def get(self, name: str) -> float | int | None:
        return self.values.get(name)


def stage_rank(stage: str) -> int:
    """Position of ``stage`` in :data:`STAGES` (``files`` measures everything ``nesting`` does)."""
    return STAGES.index(stage)


def measure_geometry(design: Any, geometry: "Geometry", quality: "Quality", support: "SupportStructure",
                     panels: "PanelSet") -> dict[str, float | int | None]:
    """The figures of the ``geometry`` stage."""
    import numpy as np

    opt = geometry.optimize_result
    surface = float(opt.surface_distance_max) * float(design.geometry.scale) if opt is not None else 0.0
    return {
        "panels": len(panels.panels),
        "panel_types": len(panels.types),
        "glass_area_m2": float(sum(p.area_mm2 for p in panels.panels) / 1e6),
        "panel_deviation_mm": float(quality.deviation_abs_max),
        "surface_deviation_mm": surface,
        "torsion_max_deg": float(np.degrees(support.torsion.max())) if len(support.edges) else 0.0,
    }


def measure_build(build: "Build") -> dict[str, float | int | None]:
    """The figures of a whole build (stages ``nesting`` and ``files``)."""
    from ..nodetypes import node_types

    out = measure_geometry(build.design, build.geometry, build.quality, build.support, build.panels)
    s = build.summary
    g = build.glazing
    out.update({
        "glass_sheets": int(s.glass_sheets), "glass_yield": float(s.glass_utilisation),
        "plate_sheets": int(s.plate_sheets), "plate_yield": float(s.plate_utilisation),
        "steel_kg": float(s.beam_mass_kg), "beam_length_m": float(s.beam_length_m),
        "weld_m": float(sum(w.length_mm for w in g.welds) / 1000.0) if g is not None else 0.0,
        "bite_min_mm": float(g.bite_min) if g is not None and g.bites else None,
        "node_types": len(node_types(build.nodes.records)),
    })
    return out


def cost(values: dict[str, float | int | None], prices: dict[str, float]) -> float | None:
    """Sum of ``price × quantity`` over the ``[cost]`` keys (:data:`COST_KEYS`); ``None`` when a priced
    quantity was not measured, or when no price is set.

    >>> cost({"glass_sheets": 4, "steel_kg": 100.0}, {"glass_sheet": 500.0, "steel_kg": 3.0})
    2300.0
    >>> cost({"glass_sheets": None}, {"glass_sheet": 500.0}) is None
    True
    """
    if not prices:
        return None
    total = 0.0
    for key, price in prices.items():
        q = values.get(COST_KEYS[key])
        if q is None:
            return None
        total += float(price) * float(q)
    return total
