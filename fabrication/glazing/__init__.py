"""How the glass bears on the structure and how the structure's pieces are joined.

* :mod:`.strips` — a flat-bar glazing strip with a gasket on the top edge of every beam span;
* :mod:`.bite` — the bite of every pane edge on its strip, measured in 3D (``[panels] min_bite``);
* :mod:`.splices` — bolted cover-plate splices where a beam is cut into pieces;
* :mod:`.welds` — weld length, dihedral angle and preparation of the butt joints;
* :mod:`.cutlist` — the strips cut from stock bars.
* :mod:`.retention` — setting blocks, stops, pressure plates and their screws holding every pane, with
  :mod:`.retention_strength` (the plates' bending and the screws' tension resistance) and :mod:`.screws` (the
  screws' stations and their clearance to the glass).

:func:`make_glazing` runs them for a build (the ``glazing`` stage of :mod:`fabrication.pipeline.stages`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .bite import BiteError, EdgeBite, check_bites, edge_normals, measure_bites
from .params import GlazingParams
from .slope import warn_flat_panes
from .splices import Splice, SpliceParams, edge_ups, make_splices, welded_splices
from .strips import Strip, make_strips
from .welds import Weld, butt_welds, corner_welds, halflap_welds

__all__ = ["BiteError", "EdgeBite", "Glazing", "GlazingParams", "Splice", "SpliceParams", "Strip", "Weld",
           "make_glazing"]


@dataclass(frozen=True, eq=False)
class Glazing:
    """The glass support and the joints of a build: strips, the bite of every pane edge, splices, welds, and
    the height ``offset`` (mm) of the panes' underside above the mesh faces (strip + gasket)."""

    params: GlazingParams
    splice_params: SpliceParams
    strips: tuple[Strip, ...]
    bites: tuple[EdgeBite, ...]
    splices: tuple[Splice, ...]
    welds: tuple[Weld, ...]
    offset: float

    @property
    def bite_min(self) -> float:
        return min((b.bite for b in self.bites), default=float("nan"))


def make_glazing(support, panels, beams, params: GlazingParams, splice_params: SpliceParams,
                 min_bite: float, strict: bool = True) -> Glazing:
    """Strips, bites (checked against ``min_bite`` when ``strict``), splices and welds of a build.

    Raises :class:`BiteError` naming the pane edges below ``min_bite`` (or steeper than
    ``params.max_tilt_deg``), and :class:`~ppfab.errors.FabricationError` naming splices whose cover plates do
    not fit on their pieces.
    """
    from ppfab.errors import FabricationError

    from ..contract import beam_ids

    normals = edge_normals(panels, support.vertices, support.edges)
    ups = edge_ups(support.edges, normals) if params.support != "none" else None
    splices = make_splices(beams.plates, splice_params, ups)
    bad = [s for s in splices if not s.fits]
    if strict and bad:
        names = ", ".join(f"{s.pieces[0]}/{s.pieces[1]}" for s in bad[:8])
        raise FabricationError(f"{len(bad)} splice cover plate(s) of {splice_params.length:g} mm do not fit on their "
                               f"beam pieces (a slot or an end is in the way): {names}; lower splices.columns or "
                               "splices.e1/p1")
    bp = beams.params
    welds = (butt_welds(beams.joints, bp.depth, bp.thickness) + corner_welds(beams.joints, bp.depth, bp.thickness)
             + (halflap_welds(beams.joints, bp.depth, bp.thickness) if bp.halflap_welds else [])
             + welded_splices(beams.plates))
    if params.support == "none":
        return Glazing(params, splice_params, (), (), tuple(splices), tuple(welds), 0.0)
    on_face = np.zeros((len(support.mesh.faces), 3))
    for p in panels:
        on_face[p.face] = p.frame.normal
    strips = make_strips(support, beam_ids(support), params, normals, on_face)
    short = [s for s in strips if s.length <= 0]
    if short:
        raise FabricationError(f"{len(short)} glazing strip(s) have no length left between the strips running "
                               f"through their nodes: {', '.join(s.part_id for s in short[:8])}; lower "
                               "glazing.width or glazing.clearance")
    bites = measure_bites(panels, strips, support.vertices, support.edges, params.gasket_thickness)
    if strict:
        check_bites(bites, min_bite, params.max_tilt_deg)
        warn_flat_panes(panels, params.min_slope_deg)
    return Glazing(params, splice_params, tuple(strips), tuple(bites), tuple(splices), tuple(welds),
                   params.thickness + params.gasket_thickness)
