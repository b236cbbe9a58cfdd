"""Parameters of the glass support (the ``[glazing]`` table of a design file)."""

from __future__ import annotations

from dataclasses import dataclass

from ppfab.errors import DesignError
from ppfab.schema import param


@dataclass(frozen=True)
class GlazingParams:
    """A flat-bar glazing strip welded on the top edge of every beam span, with a gasket on it (mm).

    Each span (mesh edge) gets one strip of ``width × thickness`` centred on its beam plane; the panes
    rest on the gasket with a bite of at least ``[panels] min_bite`` (see ``docs/glazing.md``).

    Examples
    --------
    >>> from ppfab.schema import parse_params
    >>> parse_params(GlazingParams, {"width": 80}, "glazing").width
    80.0
    """

    support: str = param("strip", doc="how the panes bear on the beams: 'strip' (a flat bar welded on each "
                                      "beam's top edge, with a gasket) or 'none' (no support modelled, no bite "
                                      "check: the design must name another glazing system)",
                         choices=("strip", "none"))
    width: float = param(60.0, doc="width of the glazing strip across its beam, mm (a standard flat bar)",
                         exclusive_min=0)
    thickness: float = param(8.0, doc="thickness of the glazing strip, mm", exclusive_min=0)
    material: str = param("S355 flat bar", doc="material of the strips, written to the parts list")
    density: float = param(7850.0, doc="strip density, kg/m³", exclusive_min=0)
    bar_length: float = param(6000.0, doc="stock length of the flat bar the strips are cut from, mm",
                              exclusive_min=0)
    saw_kerf: float = param(3.0, doc="width of one saw cut between strips on a bar, mm", min=0)
    bar_end_allowance: float = param(10.0, doc="length squared off each end of a stock bar before strips are "
                                               "cut from it, mm (ends as delivered are neither square nor clean); "
                                               "strips lie on [allowance, bar_length - allowance]", min=0)
    gasket_thickness: float = param(3.0, doc="thickness of the gasket (EPDM pad) on the strip, mm; the panes "
                                             "rest on it", exclusive_min=0)
    gasket_material: str = param("EPDM 70 Shore A", doc="gasket material, written to the parts list")
    clearance: float = param(5.0, doc="gap between a strip that stops at a node and the strip that runs "
                                      "through it, mm (fillet-welded closed)", min=0)
    setting_block_length: float = param(100.0, doc="length of a setting block (two per pane, under its "
                                                   "lowest edge), mm", exclusive_min=0)
    min_slope_deg: float = param(2.0, doc="smallest slope of a pane from the horizontal, degrees: flatter panes "
                                          "are named in a warning and in the report with a drainage note (water "
                                          "stands on flush-jointed glass below about 2-5°); 0 = no warning",
                                 min=0, max=90)
    retention: str = param("pressure_plate", doc="what holds the panes down and in place: 'pressure_plate' (a "
                                                 "clamping plate with an EPDM gasket and a cover cap on every "
                                                 "strip, bolted at bolt_pitch into the strip through the joint), "
                                                 "'silicone' (structural silicone between pane and strip, its bite "
                                                 "checked against wind_suction; no plates) or 'none' (the design "
                                                 "must name another system); see docs/glazing.md",
                           choices=("pressure_plate", "silicone", "none"))
    pressure_plate_width: float = param(50.0, doc="width of the pressure plate across its joint, mm; it bites "
                                                  "(width − joint)/2 on each pane", exclusive_min=0)
    pressure_plate_thickness: float = param(8.0, doc="thickness of the pressure plate, mm", exclusive_min=0)
    pressure_plate_material: str = param("EN AW-6060 T66", doc="material of the pressure plates and cover caps")
    pressure_gasket_thickness: float = param(4.0, doc="thickness of the EPDM gasket between pressure plate and "
                                                      "glass, mm", exclusive_min=0)
    cover_cap_height: float = param(15.0, doc="height of the cover cap clipped over the pressure plate, mm",
                                    exclusive_min=0)
    retention_bolt: str = param("M8 A4-70", doc="the screws clamping the pressure plates, '<size> <grade>' "
                                                "(A2-70, A4-70, A4-80 stainless or 8.8): studs welded on the strip "
                                                "in the joint's centre line")
    bolt_pitch: float = param(250.0, doc="largest distance between the clamping screws along a pressure plate, "
                                         "mm (and at most half of it from a plate's end)", exclusive_min=0)
    wind_suction: float = param(1.0, doc="wind suction the retention is checked for, kN/m² (characteristic; "
                                         "times load_factor)", min=0)
    load_factor: float = param(1.5, doc="partial factor on the wind suction (EN 1990 γ_Q)", min=1)
    min_clamp_bite: float = param(10.0, doc="smallest overlap of a pressure plate with each pane it clamps, mm",
                                  min=0)
    setting_block_width: float = param(4.0, doc="width of a setting block across the joint, from the pane's "
                                                "down-slope edge face, mm", exclusive_min=0)
    setting_block_material: str = param("silicone 80 Shore A", doc="setting block material and hardness, written "
                                                                   "to retention.csv")
    setting_block_pressure: float = param(1.0, doc="largest bearing pressure on a setting block, N/mm² (the "
                                                   "pane's weight along its slope over two blocks, each bearing "
                                                   "on the glass edge: length × glass thickness)", exclusive_min=0)
    stop_min_slope_deg: float = param(5.0, doc="panes steeper than this get a steel stop in the joint under "
                                               "each setting block, degrees; flatter panes are held along the "
                                               "slope by the clamp's friction (weight along the slope under "
                                               "9 % of it)", min=0, max=90)
    stop_width: float = param(3.0, doc="width of a down-slope stop across the joint, mm (S355, fixed through "
                                       "the gasket into the strip)", exclusive_min=0)
    silicone_design_stress: float = param(0.14, doc="design tensile stress of structural silicone under wind, "
                                                    "N/mm² (ETAG 002 σ_des); retention = 'silicone' only",
                                          exclusive_min=0)
    bevel_min_deg: float = param(2.0, doc="beam plates leaning more than this off the strip on them, degrees, get "
                                          "their top edge raised by (t/2)·tan(lean) and bevelled at the lean to "
                                          "the strip's underside (bevels.csv); below it the fillet weld takes up "
                                          "the fit", min=0, max=45)
    max_tilt_deg: float = param(6.0, doc="largest angle between a pane and the strip it rests on, degrees; "
                                         "the gasket takes up the wedge (width × tan of the angle); steeper edges are warned "
                                         "about (they need tapered gaskets)",
                                min=0, max=45)

    def __post_init__(self):
        if self.saw_kerf >= self.bar_length:
            raise DesignError("saw_kerf", f"{self.saw_kerf:g} mm is not below bar_length {self.bar_length:g} mm")
        if 2.0 * self.bar_end_allowance >= self.bar_length:
            raise DesignError("bar_end_allowance", f"twice {self.bar_end_allowance:g} mm leaves nothing of the "
                                                   f"{self.bar_length:g} mm bar; lower it")
