"""``guillotine``: true shapes in rows, every cut a straight line edge to edge (glass is scored and broken).

Rows are cut across the sheet; within a row a straight cut between neighbours runs from the
row's bottom to its top, slanted along their meeting edges (:mod:`..bands`); each convex part is
then trimmed by its own edge lines.  Parts that are not convex cannot be trimmed that way: then
the plan is :mod:`.rectangles`.
"""

from __future__ import annotations

import numpy as np

from ..bands import COST_PROFILE, BandFiller
from ..registry import Run, strategy
from .rectangles import boxes, boxes_floor


def all_convex(cat) -> bool:
    """Whether every part's outline is convex (area equal to its hull's within 1e-9 relative)."""
    from shapely.geometry import MultiPoint

    for part in cat.parts:
        pts = np.asarray(part.outline, dtype=float)
        if MultiPoint([tuple(p) for p in pts]).convex_hull.area > part.area * (1 + 1e-9) + 1e-6:
            return False
    return True


def cut_bands(cat, work) -> BandFiller:
    """The band filler with straight edge-to-edge cuts."""
    return BandFiller(cat, work, guillotine=True)


def bands_floor(cat) -> float:
    """Work units of the cheapest first solution of true-shape rows, estimated."""
    return COST_PROFILE * len(cat.orients) + 600.0 * cat.n_parts


@strategy("guillotine", "true shapes in rows; straight edge-to-edge cuts, slanted between neighbours "
                        "(rectangles when a part is not convex)", rank=1)
def guillotine(cat, params) -> list[Run]:
    if all_convex(cat):
        return [Run(cut_bands, "guillotine", 1.0, bands_floor)]
    return [Run(boxes, "rectangles", 1.0, boxes_floor)]
