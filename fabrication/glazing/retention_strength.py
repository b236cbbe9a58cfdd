"""How strong a pressure plate and its clamping screws are: the screw's tension resistance (EN 1993-1-8) and the
plate's bending between its screws under wind suction (EN 1993-1-1, EN 1993-1-4, EN 1999-1-1), for
:mod:`.retention`, which places them, and ``ppfab verify``'s retention check, which restates them."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Sequence

from ppfab.errors import DesignError

STRESS_AREA = {"M5": 14.2, "M6": 20.1, "M8": 36.6, "M10": 58.0, "M12": 84.3}
"""Tensile stress area ``A_s`` of a metric thread, mm² (ISO 898-1)."""
ULTIMATE = {"A2-70": 700.0, "A4-70": 700.0, "A4-80": 800.0, "8.8": 800.0}
"""Ultimate tensile strength ``f_ub`` of the screw's grade, N/mm² (ISO 3506-1, ISO 898-1)."""
K2, GAMMA_M2 = 0.9, 1.25
"""EN 1993-1-8 Table 3.4 and Table 2.1: tension resistance factor and partial factor of a bolt."""
PLATE_MATERIALS = {"EN AW-6060 T66": (150.0, 1.1, 70000.0), "EN AW-6063 T6": (170.0, 1.1, 70000.0),
                   "EN AW-6082 T6": (260.0, 1.1, 70000.0), "S235": (235.0, 1.0, 210000.0),
                   "S355": (355.0, 1.0, 210000.0), "1.4401": (220.0, 1.1, 200000.0),
                   "1.4404": (220.0, 1.1, 200000.0), "1.4301": (210.0, 1.1, 200000.0)}
"""A pressure plate's material → (``f_y`` or ``f_o`` N/mm², partial factor, ``E`` N/mm²): steel EN 1993-1-1
(``γ_M0`` 1.0), stainless steel EN 1993-1-4 (``γ_M0`` 1.1), aluminium EN 1999-1-1 Table 3.2b (``f_o`` for 5–25 mm
extrusions, ``γ_M1`` 1.1)."""
PLATE_DEFLECTION_RATIO = 200.0
"""A pressure plate may bend between its screws by at most span/200 under the characteristic wind suction (the
gasket under it must stay compressed; a cantilever end counts at twice its length)."""


def plate_material(text: str) -> tuple[float, float, float]:
    """``(strength, partial factor, E)`` of the pressure plate material ``text`` (:data:`PLATE_MATERIALS`, the
    first key the text contains); raises :class:`~ppfab.errors.DesignError` naming the key for any other."""
    for key, value in PLATE_MATERIALS.items():
        if key.lower() in text.lower():
            return value
    raise DesignError("pressure_plate_material", f"{text!r} is not a plate material ppfab can check for bending: "
                                                 f"name one of {', '.join(PLATE_MATERIALS)}")


@dataclass(frozen=True)
class PlateBending:
    """A pressure plate between its screws under the wind suction of the panes it clamps.

    ``load`` is the design line load (N/mm): each pane's ``γ_Q·q·A`` over its perimeter (its edges share it by
    length), summed over the panes on the strip; ``span`` the largest distance between screws and ``end`` the
    longer overhang past the end screws (mm).  The moment is the larger of a simply supported span's
    ``w·s²/8`` and a cantilever's ``w·a²/2``; the stress ``M / (b·t²/6)`` is checked against ``f/γ``
    (:data:`PLATE_MATERIALS`) and the deflection under the characteristic load ``w/γ_Q`` —
    ``5·w·s⁴/(384·E·I)`` over a span, ``w·a⁴/(8·E·I)`` at an end, ``I = b·t³/12`` — against
    :data:`PLATE_DEFLECTION_RATIO` (the governing of the two is reported)."""

    plate: str
    load: float
    span: float
    end: float
    stress: float
    stress_limit: float
    deflection: float
    deflection_limit: float

    @property
    def utilisation(self) -> float:
        """The larger of stress over its limit and deflection over its limit."""
        return max(self.stress / self.stress_limit, self.deflection / max(self.deflection_limit, 1e-12))

    def failures(self) -> list[str]:
        out = []
        if self.stress > self.stress_limit + 1e-9:
            out.append(f"pressure plate {self.plate} bends to {self.stress:.0f} N/mm² between its screws, above "
                       f"f/γ = {self.stress_limit:.0f} N/mm²")
        if self.deflection > self.deflection_limit + 1e-9:
            out.append(f"pressure plate {self.plate} deflects {self.deflection:.2f} mm between its screws, above "
                       f"span/{PLATE_DEFLECTION_RATIO:g} = {self.deflection_limit:.2f} mm")
        return out


def plate_bending(plate: str, load: float, stations: Sequence[float], length: float, width: float,
                  thickness: float, material: tuple[float, float, float], load_factor: float) -> PlateBending:
    """The :class:`PlateBending` of a plate ``length`` long with screws at ``stations`` (mm from its start).

    >>> b = plate_bending("CP", 1.0, (125.0, 375.0), 500.0, 50.0, 8.0, (150.0, 1.1, 70000.0), 1.5)
    >>> round(b.stress, 3), b.span, b.end
    (14.648, 250.0, 125.0)
    """
    f, gamma, e = material
    xs = sorted(stations)
    span = max([b - a for a, b in zip(xs, xs[1:])], default=0.0) if xs else length
    end = max(xs[0], length - xs[-1]) if xs else 0.0
    moment = max(load * span ** 2 / 8.0, load * end ** 2 / 2.0)
    stress = moment / (width * thickness ** 2 / 6.0)
    inertia = width * thickness ** 3 / 12.0
    wk = load / load_factor
    d_span, l_span = 5.0 * wk * span ** 4 / (384.0 * e * inertia), span / PLATE_DEFLECTION_RATIO
    d_end, l_end = wk * end ** 4 / (8.0 * e * inertia), 2.0 * end / PLATE_DEFLECTION_RATIO
    d, lim = (d_span, l_span) if d_span * max(l_end, 1e-12) >= d_end * max(l_span, 1e-12) else (d_end, l_end)
    return PlateBending(plate, load, span, end, stress, f / gamma, d, lim)


@dataclass(frozen=True)
class RetentionBolt:
    """A clamping screw as ``retention_bolt`` names it: ``"M8 A4-70"`` → size ``M8`` (diameter 8 mm), grade."""

    size: str
    grade: str

    @property
    def diameter(self) -> float:
        return float(self.size[1:])

    @property
    def tension_resistance_kN(self) -> float:
        """``F_t,Rd = k₂ · f_ub · A_s / γ_M2`` in kN.

        >>> round(RetentionBolt("M8", "A4-70").tension_resistance_kN, 2)
        18.45
        """
        return K2 * ULTIMATE[self.grade] * STRESS_AREA[self.size] / GAMMA_M2 / 1000.0

    @classmethod
    def parse(cls, text: str) -> "RetentionBolt":
        m = re.fullmatch(r"\s*(M\d+)\s+(\S+)\s*", text)
        if m is None or m.group(1) not in STRESS_AREA or m.group(2) not in ULTIMATE:
            raise DesignError("retention_bolt", f"{text!r} is not a clamping screw ppfab can check: write "
                                                f"'<size> <grade>' with size one of {', '.join(STRESS_AREA)} and grade "
                                                f"one of {', '.join(ULTIMATE)} (e.g. 'M8 A4-70')")
        return cls(m.group(1), m.group(2))
