"""``rectangles``: bounding rectangles in rows, every cut parallel to the sheet's edges (:mod:`..rows`).

Rows run across the sheet, parts across each row, and each part is trimmed inside its box: the
plan a rectangle optimiser would make, cut edge to edge in three stages.
"""

from __future__ import annotations

from ..registry import Run, strategy
from ..rows import COST_SCAN, SheetFiller


def boxes(cat, work) -> SheetFiller:
    """The box-row filler."""
    return SheetFiller(cat, work)


def boxes_floor(cat) -> float:
    """Work units of the cheapest first solution of box rows, estimated."""
    return 10 * COST_SCAN * len(cat.orients) + 300.0 * cat.n_parts


@strategy("rectangles", "bounding rectangles in rows; every cut parallel to the sheet edges, edge to edge", rank=0)
def rectangles(cat, params) -> list[Run]:
    return [Run(boxes, "rectangles", 1.0, boxes_floor)]
