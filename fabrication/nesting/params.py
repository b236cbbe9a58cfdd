"""Parameters of nesting (the ``[nesting]`` table of a design file) and the usable sheet area."""

from __future__ import annotations

from dataclasses import dataclass

from ppfab.errors import DesignError
from ppfab.schema import param


@dataclass(frozen=True)
class NestingParams:
    """Stock sheets, edge trim, spacing, rotations, mode and search budget (lengths in mm).

    Examples
    --------
    >>> from ppfab.schema import parse_params
    >>> p = parse_params(NestingParams, {"margin": [10, 10, 20, 20]}, "nesting")
    >>> p.usable()
    (10.0, 20.0, 5990.0, 3190.0)
    """

    sheet: list[float] = param([6000.0, 3210.0], doc="stock sheet [length, width], mm (x along the length)",
                               length=2, exclusive_min=0)
    margin: float | list[float] = param(0.0, doc="edge trim per side, mm: one number or [left, right, bottom, top]",
                                        min=0)
    spacing: float = param(10.0, doc="smallest distance between two parts, mm", min=0)
    rotations: list[float] = param([0.0, 90.0, 180.0, 270.0], doc="allowed rotations, degrees, of parts without "
                                   "a rotation policy of their own (beam plates: e.g. [0, 180] keeps the rolling "
                                   "direction along the plate; glass panels follow [panels] rotation)", min_length=1)
    free_rotation: bool = param(False, doc="parts without a rotation policy of their own may turn to any angle "
                                           "(tried: each long hull edge along the sheet, the minimum-area frame)")
    mode: str = param("auto", doc="nesting strategy: 'rectangles' (bounding rectangles in rows, every cut "
                                  "parallel to the sheet edges), 'guillotine' (true shapes in rows, every cut "
                                  "straight and edge to edge, slanted between neighbours, as glass is scored and "
                                  "broken), 'irregular' (true shapes nestled freely; long thin beam plates stacked "
                                  "bend into bend), or 'auto' (all three; fewest sheets wins, ties go to the "
                                  "easier cut)")
    time_budget: float = param(20.0, doc="wall time of the whole nesting (poses, search, placements, check), "
                                         "seconds on the reference machine; it buys a fixed work count "
                                         "(1e6 units a second), so the layout depends only on the parts, the "
                                         "parameters and the seed, never on the machine's speed", min=0)
    seed: int = param(0, doc="seed of the randomised search", min=0)
    tag_prefix: str = param("S", doc="first letters of the nest tags (``S03-017`` = sheet 3, part 17); glass and "
                                     "beam plates use different prefixes so every tag is unique")

    def __post_init__(self):
        m = self.margins()
        if m is None:
            raise DesignError("margin", f"needs one number or 4 numbers [left, right, bottom, top], got {self.margin!r}")
        left, right, bottom, top = m
        if left + right >= self.sheet[0] or bottom + top >= self.sheet[1]:
            raise DesignError("margin", f"trim {list(m)} leaves no usable area on a {self.sheet[0]:g} x "
                                        f"{self.sheet[1]:g} mm sheet")
        x0, y0, x1, y1 = self.usable()
        if self.spacing >= min(x1 - x0, y1 - y0):
            raise DesignError("spacing", f"part spacing {self.spacing:g} mm is not smaller than the usable "
                                         f"sheet ({x1 - x0:g} x {y1 - y0:g} mm)")
        from .registry import get_strategy

        get_strategy(self.mode, "mode")
        if not self.tag_prefix.isalnum():
            raise DesignError("tag_prefix", f"must be letters or digits, got {self.tag_prefix!r}")

    def margins(self) -> tuple[float, float, float, float] | None:
        """Edge trim ``(left, right, bottom, top)`` in mm (``None`` if malformed)."""
        if isinstance(self.margin, (int, float)) and not isinstance(self.margin, bool):
            v = float(self.margin)
            return (v, v, v, v) if v >= 0 else None
        if isinstance(self.margin, (list, tuple)) and len(self.margin) == 4:
            vals = tuple(float(v) for v in self.margin)
            return vals if min(vals) >= 0 else None  # type: ignore[return-value]
        return None

    def usable(self) -> tuple[float, float, float, float]:
        """Usable area after trim as ``(x0, y0, x1, y1)`` in sheet coordinates (mm)."""
        left, right, bottom, top = self.margins()  # type: ignore[misc]
        return (left, bottom, float(self.sheet[0]) - right, float(self.sheet[1]) - top)
