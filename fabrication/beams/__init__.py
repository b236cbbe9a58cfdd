"""Planar beam plates along the support planes, joints at the nodes, STEP solids, flat parts.

``build_beams(support, BeamParams(...))`` lays a plate into every support plane
that carries a mesh polyline (top edge = the polyline, bottom edge = the
polyline moved by the depth along the node axes), cuts half-lap slots or
butt ends at the nodes in each plate's own 2D frame, checks every plate and
reports the defects by part id.  ``fabrication.writers.step`` writes ``beams.step``
(one extruded solid per plate, build123d imported only there) and
``BeamSet.flat_parts()`` gives the plates for nesting and DXF cutting sheets.
"""

from __future__ import annotations

from .build import BeamSet, build_beams
from .joint_types.halflap import slot_width
from .joints import NodeJoint, end_setback
from .params import BeamParams
from .plates import BeamPlate, Slot
from .report import BeamRecord, BeamReport

__all__ = ["BeamSet", "build_beams", "BeamParams", "BeamPlate", "Slot", "NodeJoint",
           "BeamRecord", "BeamReport", "slot_width", "end_setback"]
