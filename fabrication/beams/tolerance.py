"""Thickness tolerance of hot-rolled steel plate (EN 10029, class A) and the slot allowance it implies.

EN 10029:2010, Table 1 (tolerances on nominal thickness, class A: the minus tolerance depends on the nominal
thickness, the plus tolerance is the upper deviation below).  A plate ordered ``t`` thick may arrive up to
``t + upper`` thick, so a half-lap slot cut for ``t`` must be at least that wide or the crossing plate does not
go in (a 15 mm plate may be 16.3 mm).  ``[beams] clearance = "auto"`` sizes every slot for the thickest plate
the standard allows plus ``[beams] slot_fit``; see ``docs/glazing.md`` (*Slot widths and play*).
"""

from __future__ import annotations

from ppfab.errors import DesignError

EN10029_CLASS_A: tuple[tuple[float, float, float, float], ...] = (
    # (from t, below t, lower deviation, upper deviation), mm; t within [from, below)
    (3.0, 5.0, -0.4, 0.8),
    (5.0, 8.0, -0.4, 1.1),
    (8.0, 15.0, -0.5, 1.2),
    (15.0, 25.0, -0.6, 1.3),
    (25.0, 40.0, -0.8, 1.4),
    (40.0, 80.0, -1.0, 1.8),
    (80.0, 150.0, -1.0, 2.2),
    (150.0, 250.0 + 1e-9, -1.2, 2.4),
)
"""EN 10029 class A thickness tolerances by nominal thickness band (the last band includes 250 mm)."""


def en10029_upper_deviation(thickness: float, key: str = "thickness") -> float:
    """The class A upper deviation (mm) of a plate of nominal ``thickness`` (mm); outside 3–250 mm the standard
    does not apply and :class:`DesignError` names ``key`` and the way out (an explicit ``clearance``).

    >>> en10029_upper_deviation(15.0), en10029_upper_deviation(12.0)
    (1.3, 1.2)
    """
    for lo, hi, _, upper in EN10029_CLASS_A:
        if lo <= thickness < hi:
            return upper
    raise DesignError(key, f"{thickness:g} mm is outside EN 10029 (3–250 mm plate), so clearance = \"auto\" has "
                           "no thickness tolerance for it; set beams.clearance to a number of mm")
