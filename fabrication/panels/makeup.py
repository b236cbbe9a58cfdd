"""The glass make-up of the panes: plies and interlayers, thickness, weight, and what the order must say.

A make-up is written as the glass trade writes it, outside ply first, plies and interlayers separated by ``/``::

    8 HS / 1.52 PVB / 8 HS        laminated: two heat-strengthened 8 mm plies, a 1.52 mm PVB interlayer
    10 FT                         monolithic toughened 10 mm (vertical glazing only)
    6 FT-HST / 0.76 SGP / 6 HS    toughened heat-soaked, ionoplast interlayer, heat-strengthened

Glass plies (``<mm> <kind>``):

* ``FL`` annealed float glass (EN 572-2);
* ``HS`` heat-strengthened glass (EN 1863-1);
* ``FT`` thermally toughened safety glass (EN 12150-1); a toughened ply is always ordered heat-soaked
  (EN 14179-1: nickel-sulphide inclusions make untreated toughened glass break spontaneously), so ``FT`` and
  ``FT-HST`` order the same glass.

Interlayers (``<mm> <kind>``): ``PVB`` (polyvinyl butyral, 1070 kg/m³), ``SGP`` (ionoplast, 950 kg/m³),
``EVA`` (940 kg/m³), in multiples of 0.38 mm as the trade sells them.

Thickness tolerances are those of float glass by nominal ply thickness (EN 572-2: ±0.2 mm up to 6 mm, ±0.3 mm
for 8–12 mm, ±0.5 mm for 15 mm, ±1.0 mm for 19–25 mm), summed over the plies, plus ±0.1 mm for interlayers under
2 mm in total and ±0.2 mm above (the laminated-glass rule of EN ISO 12543-5).  We have read these figures in
manufacturers' summaries of the standards, not in the standards themselves; a processor confirms them.

Overhead glazing — a pane inclined more than 10° from the vertical (DIN 18008-1's definition) — must be
laminated safety glass: a monolithic make-up there is refused (:func:`check_overhead`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ppfab.errors import DesignError

GLASS_KINDS: dict[str, str] = {
    "FL": "annealed float glass (EN 572-2)",
    "HS": "heat-strengthened glass (EN 1863-1)",
    "FT": "toughened safety glass, heat-soaked (EN 12150-1, EN 14179-1)",
    "FT-HST": "toughened safety glass, heat-soaked (EN 12150-1, EN 14179-1)",
}
"""Glass ply kinds and what the order calls them."""

INTERLAYER_DENSITY: dict[str, float] = {"PVB": 1070.0, "SGP": 950.0, "EVA": 940.0}
"""Interlayer kinds and their densities, kg/m³."""

INTERLAYER_STEP_MM = 0.38
"""Interlayers are sold in multiples of this thickness (0.38, 0.76, 1.14, 1.52 … mm)."""

OVERHEAD_FROM_VERTICAL_DEG = 10.0
"""A pane inclined more than this from the vertical is overhead glazing (DIN 18008-1)."""

_PLY = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*(?:mm\s*)?([A-Za-z][A-Za-z-]*)\s*$")


def float_tolerance_mm(nominal_mm: float) -> float:
    """± thickness tolerance of one float ply of ``nominal_mm`` (EN 572-2, by nominal thickness).

    >>> [float_tolerance_mm(t) for t in (4, 6, 8, 10, 12, 15, 19)]
    [0.2, 0.2, 0.3, 0.3, 0.3, 0.5, 1.0]
    """
    if nominal_mm <= 6.0 + 1e-9:
        return 0.2
    if nominal_mm <= 12.0 + 1e-9:
        return 0.3
    if nominal_mm <= 15.0 + 1e-9:
        return 0.5
    return 1.0


@dataclass(frozen=True)
class Ply:
    """One layer of a make-up: a glass ply (``kind`` in :data:`GLASS_KINDS`) or an interlayer (in
    :data:`INTERLAYER_DENSITY`), ``thickness_mm`` nominal."""

    thickness_mm: float
    kind: str

    @property
    def is_glass(self) -> bool:
        return self.kind in GLASS_KINDS

    @property
    def toughened(self) -> bool:
        return self.kind in ("FT", "FT-HST")

    def text(self) -> str:
        return f"{self.thickness_mm:g} {self.kind}"


@dataclass(frozen=True)
class Makeup:
    """A glass make-up, outside ply first (module docstring)."""

    plies: tuple[Ply, ...]

    @property
    def glass(self) -> tuple[Ply, ...]:
        return tuple(p for p in self.plies if p.is_glass)

    @property
    def interlayers(self) -> tuple[Ply, ...]:
        return tuple(p for p in self.plies if not p.is_glass)

    @property
    def laminated(self) -> bool:
        """Two or more glass plies bonded by interlayers (laminated safety glass)."""
        return len(self.glass) >= 2

    @property
    def thickness_mm(self) -> float:
        """Nominal total thickness, mm."""
        return float(sum(p.thickness_mm for p in self.plies))

    @property
    def glass_thickness_mm(self) -> float:
        return float(sum(p.thickness_mm for p in self.glass))

    @property
    def heat_soak(self) -> bool:
        """Some ply is toughened and so ordered heat-soaked (EN 14179-1)."""
        return any(p.toughened for p in self.glass)

    @property
    def thickness_tolerance_mm(self) -> float:
        """± tolerance of the total thickness, mm (module docstring)."""
        inter = sum(p.thickness_mm for p in self.interlayers)
        extra = 0.0 if not self.interlayers else (0.1 if inter < 2.0 else 0.2)
        return round(sum(float_tolerance_mm(p.thickness_mm) for p in self.glass) + extra, 3)

    def mass_per_m2(self, glass_density: float) -> float:
        """Mass of one square metre, kg: the glass plies at ``glass_density`` kg/m³, the interlayers at theirs.

        >>> round(parse_makeup("8 HS / 1.52 PVB / 8 HS").mass_per_m2(2500.0), 3)
        41.626
        """
        return float(sum(p.thickness_mm * 1e-3 * (glass_density if p.is_glass else INTERLAYER_DENSITY[p.kind])
                         for p in self.plies))

    def text(self) -> str:
        """The make-up as the order writes it (``8 HS / 1.52 PVB / 8 HS``)."""
        return " / ".join(p.text() for p in self.plies)

    def description(self) -> str:
        """In words, for the order and the report."""
        kinds = sorted({GLASS_KINDS[p.kind] for p in self.glass})
        if self.laminated:
            inter = " + ".join(sorted({p.kind for p in self.interlayers}))
            return f"laminated safety glass of {len(self.glass)} plies ({'; '.join(kinds)}), {inter} interlayer"
        return f"monolithic {kinds[0]}"


def parse_makeup(text: str, key: str = "panels.makeup") -> Makeup:
    """The :class:`Makeup` a make-up string names; a :class:`~ppfab.errors.DesignError` on ``key`` that says
    what is wrong otherwise.

    >>> m = parse_makeup("8 HS / 1.52 PVB / 8 HS")
    >>> m.thickness_mm, m.laminated, m.heat_soak, m.thickness_tolerance_mm
    (17.52, True, False, 0.7)
    >>> parse_makeup("10 ft").text()
    '10 FT'
    """
    grammar = ("write plies outside first, separated by '/', each '<mm> <kind>': glass FL, HS, FT or FT-HST, "
               "interlayers PVB, SGP or EVA (e.g. \"8 HS / 1.52 PVB / 8 HS\")")
    parts = str(text).split("/")
    plies: list[Ply] = []
    for k, raw in enumerate(parts):
        m = _PLY.match(raw)
        if m is None:
            raise DesignError(key, f"ply {k + 1} {raw.strip()!r} is not '<mm> <kind>': {grammar}")
        t, kind = float(m.group(1)), m.group(2).upper()
        if kind not in GLASS_KINDS and kind not in INTERLAYER_DENSITY:
            raise DesignError(key, f"ply {k + 1}: unknown kind {m.group(2)!r}: {grammar}")
        if not 0.0 < t <= 25.0:
            raise DesignError(key, f"ply {k + 1}: {t:g} mm is outside 0-25 mm")
        if kind in INTERLAYER_DENSITY:
            steps = t / INTERLAYER_STEP_MM
            if abs(steps - round(steps)) > 1e-6:
                raise DesignError(key, f"ply {k + 1}: a {kind} interlayer of {t:g} mm; interlayers come in "
                                       f"multiples of {INTERLAYER_STEP_MM} mm (0.76, 1.52, …)")
        plies.append(Ply(t, kind))
    for k, p in enumerate(plies):
        glass_next = k % 2 == 0
        if p.is_glass != glass_next:
            raise DesignError(key, f"ply {k + 1} ({p.text()}): glass plies and interlayers must alternate, "
                                   f"starting and ending with glass: {grammar}")
    if not plies[-1].is_glass:
        raise DesignError(key, f"the make-up ends with an interlayer ({plies[-1].text()}): {grammar}")
    return Makeup(tuple(plies))


def check_overhead(makeup: Makeup, inclination_from_vertical_deg: float, panel: str) -> None:
    """Refuse a monolithic make-up for overhead glazing (more than :data:`OVERHEAD_FROM_VERTICAL_DEG` from the
    vertical): ``panel`` is the steepest-lying pane, named in the message."""
    if inclination_from_vertical_deg > OVERHEAD_FROM_VERTICAL_DEG and not makeup.laminated:
        raise DesignError("panels.makeup", f"{makeup.text()!r} is monolithic, but pane {panel} lies "
                                           f"{inclination_from_vertical_deg:.0f}° from the vertical: overhead "
                                           f"glazing (more than {OVERHEAD_FROM_VERTICAL_DEG:g}°, DIN 18008-1) must "
                                           "be laminated safety glass, e.g. makeup = \"8 HS / 1.52 PVB / 8 HS\"")
