"""Parameters of glass panels (the ``[panels]`` table of a design file)."""

from __future__ import annotations

from dataclasses import dataclass

from ppfab.errors import DesignError
from ppfab.schema import param

from .makeup import Makeup, parse_makeup


@dataclass(frozen=True)
class PanelParams:
    """Glass panels cut from the faces of a quad mesh (all lengths in mm).

    Examples
    --------
    >>> from ppfab.schema import parse_params
    >>> p = parse_params(PanelParams, {"gap": 12, "makeup": "6 HS / 0.76 PVB / 6 HS"}, "panels")
    >>> p.gap, p.pane_thickness, round(p.mass_per_m2, 2)
    (12.0, 12.76, 30.81)
    """

    gap: float = param(10.0, doc="joint width between neighbouring panels, mm; every panel edge is inset by gap/2", min=0)
    thickness: float | None = param(None, doc="total glass thickness, mm; default (and after parsing): the "
                                              "make-up's nominal thickness (given, it must equal it)",
                                    exclusive_min=0)
    makeup: str = param("8 HS / 1.52 PVB / 8 HS", doc="glass make-up, outside ply first: plies '<mm> <kind>' "
                                                     "(FL, HS, FT = toughened and heat-soaked) and interlayers "
                                                     "(PVB, SGP, EVA) separated by '/'; overhead glazing must be "
                                                     "laminated (docs/glazing.md)")
    density: float = param(2500.0, doc="density of the glass plies, kg/m³ (interlayers: their own)",
                           exclusive_min=0)
    planarity_tolerance: float = param(1.0, doc="largest allowed distance of a face corner from the face's "
                                                "least-squares plane, mm; checked before anything is written",
                                       exclusive_min=0)
    max_crease_deg: float = param(45.0, doc="largest dihedral angle between neighbouring panels, degrees (0 = "
                                            "coplanar): the fold a joint between two panes takes; a mesh with "
                                            "an edge beyond it stops the build, listing the edges", min=0,
                                  exclusive_max=180)
    min_size: list[float] = param([250.0, 250.0], doc="smallest panel [w, h] the processor accepts, mm (flag)",
                                  length=2, min=0)
    max_size: list[float] = param([6000.0, 3210.0], doc="largest panel [w, h] the processor accepts, mm (flag)",
                                  length=2, exclusive_min=0)
    min_corner_angle_deg: float = param(20.0, doc="corners more acute than this are flagged, degrees", min=0, max=90)
    congruence_tolerance: float = param(1.0, doc="panels whose outlines match within this (mm, after a rigid "
                                                 "motion) share a type id (type_tolerance, when given, wins)",
                                        min=0)
    type_tolerance: float | None = param(None, doc="panels whose outlines match within this (mm, largest corner "
                                                   "distance after a rigid motion) share a type id and are cut "
                                                   "to one outline; default: congruence_tolerance", min=0)
    min_bite: float = param(15.0, doc="smallest overlap of a pane edge with the gasket it rests on, mm, measured "
                                      "in 3D across the edge (edge cover of linearly supported glass, "
                                      "DIN 18008-2; see docs/glazing.md); a build below it stops", min=0)
    mirror_allowed: bool = param(False, doc="the make-up is symmetric (no coating, no print): a panel may be "
                                            "turned over, so mirror images are the same type and may be nested mirrored")
    outside: str = param("auto", doc="which side of a face is the outside: 'normal' (the side its corner order "
                                     "turns counter-clockwise about), 'reverse', or 'auto' (away from the mesh centroid)",
                         choices=("auto", "normal", "reverse"))
    rotation: str = param("free", doc="how panels may turn on the stock sheet: 'free' (float glass has no grain: "
                                      "any angle; each outline is laid out in its minimum-area rectangle), 'grain' "
                                      "(0 or 180°: the sheet's length stays along the panel's reference edge, for "
                                      "coated or patterned glass whose direction must be the same on every pane), "
                                      "or 'quarter' (0, 90, 180, 270°); 'grain' and 'quarter' keep the outline "
                                      "in its reference-edge frame", choices=("free", "grain", "quarter"))
    mark_size: float = param(80.0, doc="length of the reference-corner mark on layer MARK, mm", min=0)
    edge_finish: str = param("arrised", doc="edge work of the panes, written to the glass order (e.g. arrised, "
                                            "ground, polished)")
    coated_side: str = param("none", doc="the side of the pane that carries a coating or print, written to the "
                                         "glass order; the per-type DXF shows the pane seen from outside",
                             choices=("none", "outside", "inside"))

    @property
    def layers(self) -> Makeup:
        """The parsed make-up (:mod:`fabrication.panels.makeup`)."""
        return parse_makeup(self.makeup, "makeup")

    @property
    def pane_thickness(self) -> float:
        """Total nominal thickness of a pane, mm (the make-up's)."""
        return self.layers.thickness_mm

    @property
    def mass_per_m2(self) -> float:
        """Mass of one square metre of pane, kg."""
        return self.layers.mass_per_m2(self.density)

    @property
    def type_tol(self) -> float:
        """The congruence tolerance that groups panels into types (mm)."""
        return self.congruence_tolerance if self.type_tolerance is None else float(self.type_tolerance)

    def __post_init__(self):
        layers = parse_makeup(self.makeup, "makeup")
        if self.thickness is not None and abs(self.thickness - layers.thickness_mm) > 1e-6:
            raise DesignError("thickness", f"{self.thickness:g} mm, but the make-up {layers.text()!r} is "
                                           f"{layers.thickness_mm:g} mm thick: leave thickness out or change makeup")
        # the canonical make-up text and its thickness, so that every table shows the same values
        object.__setattr__(self, "makeup", layers.text())
        object.__setattr__(self, "thickness", layers.thickness_mm)
        if min(self.min_size) > 0 and (max(self.min_size) > max(self.max_size) or min(self.min_size) > min(self.max_size)):
            raise DesignError("min_size", f"{list(self.min_size)} exceeds max_size {list(self.max_size)}")
        if self.coated_side != "none" and self.mirror_allowed:
            raise DesignError("mirror_allowed", f"a pane coated on the {self.coated_side} cannot be turned over: "
                                                "set mirror_allowed = false or coated_side = 'none'")
