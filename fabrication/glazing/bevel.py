"""The fit of each glazing strip on the top edge of its beam plate: the plate's lean and the bevel it needs.

A strip lies in the plane through its span that bisects the panes on it (:mod:`.strips`); the beam plate
under it lies in its support plane, which may lean off the glass (a PP support plane ``U_i`` leans up to 20°
and more).  The strip's ``ex`` lies in the plate's plane, so the two differ by a rotation about the span, the
plate's *lean*

    λ = arcsin |u · n_p|,

with ``u`` the strip's up and ``n_p`` the plate's unit normal.  The plate's top face is square to the plate:
of its two top corners, ``t/2`` either side of the mid-plane (``t`` the plate thickness), one stands
``(t/2)·sin λ`` above the strip's underside (along ``u``) — it runs into the strip by that much — and the other
as far below it, a gap under the weld.  Measured along the plate (square to its top edge), both are
``Δ = (t/2)·tan λ``.

The fabricator's answer where ``λ`` exceeds ``glazing.bevel_min_deg``: the span's top edge is cut ``Δ`` higher
in the plate's flat outline and bevelled (planed) at ``λ`` to the strip's underside plane, so that the strip
bears on the whole bevelled face — no overlap and no gap.  :func:`strip_bevels` states it per strip and plate
(``bevels.csv``), and :mod:`fabrication.beams.bevel_cut` makes it the plates' geometry (the cut outline, the DXF's
``BEVEL`` layer, the solid of ``beams.step``) with the same decision (:func:`strip_bevel`); below the threshold the overlap and gap (at most ``(t/2)·tan(bevel_min_deg)``) are taken up
by the fillet weld's fit-up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .strips import Strip


@dataclass(frozen=True)
class StripBevel:
    """The fit of one strip on its plate: strip and plate ids, the lean ``λ`` (degrees), the overlap (mm, along
    the strip's up: ``(t/2)·sin λ``), ``Δ = (t/2)·tan λ`` (mm, along the plate) and whether the plate's top edge
    is bevelled there (``λ > bevel_min_deg``)."""

    strip: str
    plate: str
    lean_deg: float
    overlap_mm: float
    delta_mm: float
    bevelled: bool

    def text(self) -> str:
        """The shop instruction, e.g. ``top edge +3.18 mm, bevel 23.0° to the strip`` (or ``square``)."""
        if not self.bevelled:
            return "square"
        return f"top edge +{self.delta_mm:.2f} mm, bevel {self.lean_deg:.1f}° to the strip"


def plate_under(strip: Strip, plates: Sequence) -> object | None:
    """The beam plate (piece) of the strip's beam that holds both its nodes, else one holding either."""
    i, j = strip.vertices
    mine = [p for p in plates if p.beam_id == strip.beam_id]
    both = [p for p in mine if i in set(p.nodes.tolist()) and j in set(p.nodes.tolist())]
    either = [p for p in mine if i in set(p.nodes.tolist()) or j in set(p.nodes.tolist())]
    return (both or either or [None])[0]


def strip_bevel(strip: Strip, plate, min_deg: float) -> StripBevel:
    """The :class:`StripBevel` of ``strip`` on ``plate`` (module docstring)."""
    n = np.asarray(plate.plane[:3], dtype=float)
    n = n / np.linalg.norm(n)
    s = min(1.0, abs(float(strip.frame.normal @ n)))
    lean = math.asin(s)
    half = 0.5 * float(plate.thickness)
    return StripBevel(strip.part_id, plate.part_id, math.degrees(lean), half * s, half * math.tan(lean),
                      math.degrees(lean) > min_deg + 1e-12)


def strip_bevels(strips: Sequence[Strip], plates: Sequence, min_deg: float, as_cut: bool = False
                 ) -> list[StripBevel]:
    """One :class:`StripBevel` per strip that has a plate under it, in strip order.  ``as_cut`` (``plates`` as
    :mod:`fabrication.beams.bevel_cut` left them): a strip leaning past ``min_deg`` on a plate that kept its square
    top edge (its bevel could not be drawn) is ``square`` there, as the plate is."""
    from dataclasses import replace

    by_beam: dict[str, list] = {}
    for p in plates:
        by_beam.setdefault(p.beam_id, []).append(p)
    out = []
    for s in strips:
        plate = plate_under(s, by_beam.get(s.beam_id, []))
        if plate is not None:
            fit = strip_bevel(s, plate, min_deg)
            cut = getattr(plate, "bevels", None)
            if as_cut and fit.bevelled and cut is not None and not any(b.strip == s.part_id for b in cut):
                fit = replace(fit, bevelled=False)
            out.append(fit)
    return out
