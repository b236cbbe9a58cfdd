"""The flat geometry of the parts that the tables do not hold: a cutting outline mapped back from its sheet
(the inverse of :func:`fabrication.flatpart.place_points`) and the rectangle of a glazing strip."""

from __future__ import annotations

import math
from typing import Sequence

from ..model import Placement

Points = tuple[tuple[float, float], ...]


def unplace(points: Sequence[Sequence[float]], placement: Placement) -> Points:
    """Sheet points back into the part's own frame: ``p = M · R(−rotation) · (q − (x, y))``.

    >>> [(round(x, 9), round(y, 9)) for x, y in unplace([(10.0, 21.0)], Placement(1, "s.dxf", 10.0, 20.0, 90.0, True))]
    [(-1.0, 0.0)]
    """
    a = math.radians(placement.rotation_deg)
    c, s = math.cos(a), math.sin(a)
    out = []
    for qx, qy in points:
        dx, dy = float(qx) - placement.x, float(qy) - placement.y
        px, py = c * dx + s * dy, -s * dx + c * dy
        out.append((-px if placement.mirrored else px, py))
    return tuple(out)


def unplace_outline(points: Sequence[Sequence[float]], placement: Placement) -> Points:
    """A CUT outline back into the part's frame: :func:`unplace`, and for a mirrored placement the order reversed
    again (the writer reverses it to keep the drawn outline counter-clockwise), so the corners come back in the
    part's own order."""
    pts = unplace(points, placement)
    return pts[::-1] if placement.mirrored else pts


BOX_KINDS = ("setting_block", "stop", "pressure_gasket", "pressure_plate", "cover_cap")
"""The retention kinds drawn as a box on their ``frame``: outline ``length × width`` from its origin, as a strip's."""


def strip_outline(length: float | None, width: float | None) -> Points | None:
    """A glazing strip is a flat bar cut square: the rectangle ``length × width`` from the origin (``None``
    without both)."""
    if length is None or width is None:
        return None
    return ((0.0, 0.0), (float(length), 0.0), (float(length), float(width)), (0.0, float(width)))
