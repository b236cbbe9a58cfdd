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
