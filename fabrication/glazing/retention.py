"""What holds every pane: setting blocks and stops under its down-slope edge, pressure plates over its edges.

**Setting blocks.**  A pane's weight ``W = m·g`` has the component ``W·sin α`` along its slope (``α`` the pane's
angle to the horizontal, :func:`.slope.pane_slope_deg`) and ``W·cos α`` onto the gaskets.  The slope component
is carried by two setting blocks against the glass edge face of the pane's *down-slope edge* — the outline edge
whose outward normal points most down the slope (``−z`` made parallel to the pane) — centred at a quarter of the
edge length from its corners (common glazing practice), each ``setting_block_length`` long and
``setting_block_width`` wide across the joint.  Each block rests on the gasket of that edge's strip (its base
the highest point of the gasket top under it, as the pane's seat is found in :mod:`.seat`) and reaches to 1 mm
below the glass's top face.  Its bearing pressure is

    p = W·sin α / (2 · ℓ_b · h),   at most ``setting_block_pressure``,

with ``ℓ_b`` the block length and ``h`` the height over which it bears on the glass edge (the glass thickness
less 1 mm; less where a kink tilts the edge face of the pane across the joint over the block, which then
reaches only to 1 mm below that face: a block bearing on less than half the glass is warned about).

**Stops.**  Panes steeper than ``stop_min_slope_deg`` get a steel stop in the joint behind each block (from
``setting_block_width`` to ``setting_block_width + stop_width`` beyond the glass edge), on the same gasket, fixed
through it into the strip.  The joint must hold block and stop with 2 mm to spare: ``w_b + w_s + 2 ≤ gap``.

**Pressure plates.**  With ``retention = "pressure_plate"`` every strip carrying a pane gets, in the strip's own
frame (:class:`.strips.Strip`) and over the strip's length where its panes lie, stopping :data:`PLATE_END_GAP`
short of their ends (a plate running on to the node meets the corner of the next span's pane, which a kink there
lifts into it), an EPDM pressure gasket, an aluminium pressure plate
and a cover cap, each ``pressure_plate_width`` wide.  The gasket's underside lies at the highest point of the
glass top faces under it (the panes on both sides of the joint are kinked against each other: it touches the
higher and stands off the other by its *gap*, which the gasket takes up when the screws are tightened).  Its
*clamp bite* on each pane is the area of the pane's top face under the plate (projected along the strip's
normal) over the length along the strip that area spans.

The plate is clamped by screws on the joint's centre line at most ``bolt_pitch`` apart and half of that from the
plate's ends, shifted out of the setting blocks and stops.  Each pane's wind suction ``γ_Q · q · A`` is shared
by its edges in proportion to their length; a plate carries the shares of the panes on its strip and its screws
resist ``F_t,Rd = k₂ · f_ub · A_s / γ_M2`` each (EN 1993-1-8 Table 3.4, ``k₂ = 0.9``, ``γ_M2 = 1.25``).
Between its screws the plate bends under the same line load (:class:`PlateBending`: stress against ``f/γ``,
deflection against span/200).  The screws of a plate are one :class:`ScrewSet` (one parts-list row).

With ``retention = "silicone"`` there are no plates: the structural silicone's bite must be at least
``h_c = γ_Q · q · a / (2 · σ_des)`` (ETAG 002 §5.1.4.2.1, ``a`` the pane's shorter side, taken as the smallest
width of its outline over its edge normals), and the pane's smallest bite on its strips (:mod:`.bite`) must hold
that bead.
"""

from __future__ import annotations

import logging
import math
import re
import weakref
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ppfab.errors import DesignError
from ppfab.frame import Frame

from ..contract import (cover_cap_id, pressure_gasket_id, pressure_plate_id, screw_set_id, setting_block_id,
                        stop_id)
from .params import GlazingParams
from .seat import PaneSeat
from .slope import pane_slope_deg
from .strips import Strip

if TYPE_CHECKING:  # pragma: no cover
    from ..panels import Panel
    from ..pipeline.records import Build

log = logging.getLogger("ppfab")

G = 9.81
"""m/s²: gravity, for a pane's weight."""
BLOCK_BELOW_TOP = 1.0
"""mm: how far a setting block's and a stop's top stays below the glass's top face (clear of the pressure gasket)."""
PLATE_END_GAP = 20.0
"""mm: how far a pressure plate stops short of the end of its panes' edges (where the plates of the other spans
at the node begin, and a kink lifts the corner of the next span's pane)."""
JOINT_SPARE = 2.0
"""mm: the least room left in the joint beside setting block and stop, and beside a screw."""
STRESS_AREA = {"M5": 14.2, "M6": 20.1, "M8": 36.6, "M10": 58.0, "M12": 84.3}
"""Tensile stress area ``A_s`` of a metric thread, mm² (ISO 898-1)."""
ULTIMATE = {"A2-70": 700.0, "A4-70": 700.0, "A4-80": 800.0, "8.8": 800.0}
"""Ultimate tensile strength ``f_ub`` of the screw's grade, N/mm² (ISO 3506-1, ISO 898-1)."""
K2, GAMMA_M2 = 0.9, 1.25
"""EN 1993-1-8 Table 3.4 and Table 2.1: tension resistance factor and partial factor of a bolt."""
NUT_HEIGHT = 0.8
"""A clamping screw's length above the plate, in diameters: the nut (ISO 4032: ``m ≈ 0.8·d``)."""
DENSITY = {"setting_block": 1300.0, "stop": 7850.0, "pressure_gasket": 1200.0, "pressure_plate": 2700.0,
           "cover_cap": 2700.0, "screw": 8000.0}
"""kg/m³ of each retention kind: silicone 80 Shore A, S355, EPDM, aluminium (EN 1999-1-1 3.2.5), stainless steel
(EN 10088-1, A2/A4)."""
CAP_WALL = 2.0
"""mm: the wall of a cover cap, an extruded channel over the plate: its mass is ``(width + 2·height)·wall``
per mm of length (the model draws the cap as the prism it fills)."""
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


def material_of(kind: str, p: GlazingParams) -> str:
    """The material cell (retention.csv, parts.csv) of a retention part of ``kind``."""
    return {"setting_block": p.setting_block_material, "stop": "S355", "pressure_gasket": "EPDM 70 Shore A",
            "screw": f"stainless steel {p.retention_bolt}"}.get(kind, p.pressure_plate_material)


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


@dataclass(frozen=True, eq=False)
class Prism:
    """A retention part as a prism: part id, the pane or strip it belongs to, its frame, outline ``(4, 2)`` in
    frame coordinates, base ``z0`` and height (mm) along the frame's normal, and its kind (``setting_block``,
    ``stop``, ``pressure_gasket``, ``pressure_plate``, ``cover_cap``)."""

    part_id: str
    kind: str
    owner: str
    strip: str
    beam: str
    frame: Frame
    outline: np.ndarray
    z0: float
    height: float

    def corners(self) -> np.ndarray:
        """``(8, 3)`` corners: the outline at ``z0`` then at ``z0 + height``."""
        flat = self.frame.to3d(self.outline)
        n = self.frame.normal
        return np.concatenate([flat + self.z0 * n, flat + (self.z0 + self.height) * n])

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.outline[1] - self.outline[0]))

    @property
    def width(self) -> float:
        return float(np.linalg.norm(self.outline[2] - self.outline[1]))

    @property
    def mass_kg(self) -> float:
        """kg: the prism's volume at its kind's :data:`DENSITY`; a cover cap as a channel of :data:`CAP_WALL`."""
        if self.kind == "cover_cap":
            section = min((self.width + 2.0 * self.height) * CAP_WALL, self.width * self.height)
        else:
            section = self.width * self.height
        return section * self.length * DENSITY[self.kind] * 1e-9

    def box_frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(origin, x_dir, y_dir, normal)`` of the prism as a box: the origin a corner of its underside, the
        prism ``[0, length] × [0, width] × [0, height]`` along the three (right-handed) axes."""
        c = self.corners()
        n = self.frame.normal
        x, y = c[1] - c[0], c[3] - c[0]
        origin = c[0]
        if float(np.cross(x, y) @ n) < 0:
            origin, x, y = c[1], c[0] - c[1], c[2] - c[1]
        return origin, x / np.linalg.norm(x), y / np.linalg.norm(y), np.asarray(n, dtype=float)


@dataclass(frozen=True, eq=False)
class ScrewSet:
    """The clamping screws of one pressure plate: studs welded on the strip's top face in the joint's centre
    line, through gasket and plate, each ``length`` from the strip's top (``z0`` along the strip frame's normal)
    to a nut's height above the plate.  ``stations`` are mm along the strip's ``x`` from ``x0`` (the plate's
    start), as retention.csv lists them."""

    part_id: str
    plate: str
    strip: str
    beam: str
    frame: Frame
    x0: float
    z0: float
    length: float
    diameter: float
    stations: tuple[float, ...]
    clearance_mm: float = math.inf
    """The least clear distance between a screw and the glass of the panes beside its joint
    (:func:`screw_clearance`; negative: the screw would go into the glass)."""

    def axes(self) -> np.ndarray:
        """``(n, 2, 3)``: every screw's axis, from its foot on the strip to its top."""
        n = self.frame.normal
        foot = self.frame.to3d(np.array([[self.x0 + x, 0.0] for x in self.stations]).reshape(-1, 2)) + self.z0 * n
        return np.stack([foot, foot + self.length * n], axis=1)

    @property
    def mass_kg(self) -> float:
        """kg of all the screws: cylinders of the nominal diameter at :data:`DENSITY` ``["screw"]``."""
        return len(self.stations) * math.pi * 0.25 * self.diameter ** 2 * self.length * DENSITY["screw"] * 1e-9


@dataclass(frozen=True)
class PaneRestraint:
    """The restraint of one pane: slope (°), weight (kg), its down-slope outline edge and the strip under it,
    the load on each setting block (N) and its bearing pressure (N/mm²), whether it has stops, its wind uplift
    (design, kN), the screws of the plates on its edges that carry it (their share, may be fractional), the
    uplift those screws resist (kN), the smallest clamp bite (mm; NaN without plates) and the largest screw
    spacing (mm) on its edges, and the largest :attr:`PlateBending.utilisation` of the plates over it."""

    panel: str
    slope_deg: float
    weight_kg: float
    down_edge: int
    strip: str
    block_load_N: float
    block_pressure: float
    stops: bool
    uplift_kN: float
    screws: float
    resistance_kN: float
    clamp_bite_mm: float
    max_spacing_mm: float
    silicone_bite_mm: float
    strip_bite_mm: float = math.nan
    block_contact_mm: float = math.nan
    plate_utilisation: float = math.nan

    def failures(self, p: GlazingParams) -> list[str]:
        """What this pane's restraint does not satisfy, in words (empty: it holds)."""
        out = []
        if self.block_pressure > p.setting_block_pressure + 1e-9:
            out.append(f"setting block pressure {self.block_pressure:.2f} N/mm² above glazing.setting_block_pressure "
                       f"= {p.setting_block_pressure:g}")
        if p.retention == "silicone" and not self.strip_bite_mm >= self.silicone_bite_mm - 1e-9:
            out.append(f"structural silicone bite {self.silicone_bite_mm:.1f} mm needed, the pane bites "
                       f"{self.strip_bite_mm:.1f} mm on its strips")
        if p.retention == "pressure_plate":
            if self.uplift_kN > self.resistance_kN + 1e-9:
                out.append(f"wind uplift {self.uplift_kN:.2f} kN above its screws' {self.resistance_kN:.2f} kN")
            if not self.clamp_bite_mm >= p.min_clamp_bite - 1e-9:
                out.append(f"clamp bite {self.clamp_bite_mm:.1f} mm below glazing.min_clamp_bite = "
                           f"{p.min_clamp_bite:g} mm")
            if self.plate_utilisation > 1.0 + 1e-9:
                out.append(f"a pressure plate over it bends beyond its limit between the screws (utilisation "
                           f"{self.plate_utilisation:.2f}, retention.csv)")
            if self.max_spacing_mm > p.bolt_pitch + 1e-6:
                out.append(f"screws {self.max_spacing_mm:.0f} mm apart, more than glazing.bolt_pitch = "
                           f"{p.bolt_pitch:g} mm")
        return out


@dataclass(frozen=True, eq=False)
class Retention:
    """Setting blocks, stops and pressure-plate layers of a build (``parts``), the screw stations (mm along the
    strip's ``x``) of every pressure plate by plate id, and every pane's :class:`PaneRestraint`."""

    params: GlazingParams
    bolt: RetentionBolt | None
    parts: tuple[Prism, ...]
    stations: dict[str, tuple[float, ...]]
    panes: tuple[PaneRestraint, ...]
    screws: tuple[ScrewSet, ...] = ()
    bending: dict[str, PlateBending] | None = None


def down_edge(panel: "Panel") -> int:
    """The outline edge ``k`` (vertex ``k`` to ``k + 1``) whose outward normal points most down the slope; on a
    level pane (no slope direction) the edge with the lowest midpoint."""
    f = panel.frame
    q = np.asarray(panel.outline, dtype=float)
    d = np.roll(q, -1, axis=0) - q
    out2 = np.stack([d[:, 1], -d[:, 0]], axis=1) / np.linalg.norm(d, axis=1, keepdims=True)   # right of a CCW edge
    down = f.vec2d(np.array([0.0, 0.0, -1.0]))
    if float(np.linalg.norm(down)) < 1e-9:
        mid = f.to3d(0.5 * (q + np.roll(q, -1, axis=0)))
        return int(np.argmin(mid[:, 2]))
    return int(np.argmax(out2 @ down))


def _gasket_height(points3: np.ndarray, normal: np.ndarray, strip: Strip, gasket: float) -> float:
    """The highest point, along ``normal`` from ``points3``, of the strip's gasket top plane above them."""
    top = strip.top_corners(gasket)
    u = strip.frame.normal
    denom = float(normal @ u)
    if denom <= 1e-6:
        return -math.inf
    return float((((top[0] - points3) @ u) / denom).max())


def _below_face(points3: np.ndarray, normal: np.ndarray, face: tuple[np.ndarray, np.ndarray] | None) -> float:
    """How far (mm) ``points3`` may rise along ``normal`` before one of them reaches the plane ``face`` (a point
    on it and its unit normal, pointing to the side the points are on); ``inf`` when none comes nearer."""
    if face is None:
        return math.inf
    origin, m = face
    rate = float(normal @ m)
    if rate >= -1e-9:
        return math.inf
    return float((((points3 - origin) @ m) / -rate).min())


def setting_blocks(panel: "Panel", seat: float, strip: Strip | None, edge: int, p: GlazingParams,
                   stops: bool, across: tuple[np.ndarray, np.ndarray] | None = None) -> list[Prism]:
    """The two setting blocks of a pane (and their stops when ``stops``) on outline edge ``edge``; ``across``
    is the edge face of the pane across the joint (a point on it and its outward unit normal): where a kink
    tilts that face over the joint, a block or stop reaches only to :data:`JOINT_SPARE` / 2 below it."""
    f = panel.frame
    N = f.normal
    q = np.asarray(panel.outline, dtype=float)
    a, b = q[edge], q[(edge + 1) % len(q)]
    L = float(np.linalg.norm(b - a))
    d = (b - a) / L
    o = np.array([d[1], -d[0]])
    lb = min(p.setting_block_length, 0.4 * L)
    top = seat + panel.thickness_mm - BLOCK_BELOW_TOP
    out = []
    owner = panel.part_id
    sid = strip.part_id if strip is not None else ""
    beam = strip.beam_id if strip is not None else ""
    for k, s in enumerate((0.25 * L, 0.75 * L), start=1):
        layers = [("setting_block", setting_block_id(owner, k), 0.0, p.setting_block_width)]
        if stops:
            layers.append(("stop", stop_id(owner, k), p.setting_block_width, p.setting_block_width + p.stop_width))
        for kind, pid, w0, w1 in layers:
            rect = np.array([a + (s - 0.5 * lb) * d + w0 * o, a + (s + 0.5 * lb) * d + w0 * o,
                             a + (s + 0.5 * lb) * d + w1 * o, a + (s - 0.5 * lb) * d + w1 * o])
            base = seat
            if strip is not None:
                base = min(max(seat, _gasket_height(f.to3d(rect), N, strip, p.gasket_thickness)), top - 1.0)
            if base < seat:
                base = seat
            reach = _below_face(f.to3d(rect) + base * N, N, across) - 0.5 * JOINT_SPARE
            height = max(min(top - base, reach), 1.0)
            out.append(Prism(pid, kind, owner, sid, beam, f, rect, base, height))
    return out


def _below_gasket(part: Prism, strip: Frame, underside: float) -> Prism:
    """``part`` (a setting block or stop, a prism along its pane's normal ``N``) no higher than
    :data:`BLOCK_BELOW_TOP` under the pressure gasket's underside, the plane ``underside`` mm along the strip
    frame's normal ``n``: each top corner ``P + h·N`` needs ``(P + h·N − o)·n ≤ underside − BLOCK_BELOW_TOP``."""
    n, N = strip.normal, part.frame.normal
    feet = part.frame.to3d(part.outline) + part.z0 * N
    room = (underside - BLOCK_BELOW_TOP - (feet - strip.origin) @ n) / max(float(N @ n), 1e-9)
    cap = float(room.min())
    return part if cap >= part.height else replace(part, height=max(cap, 1.0))


def screw_clearance(axes: np.ndarray, diameter: float, panes: Sequence[tuple["Panel", int, float]]) -> float:
    """How far (mm) the glass beside the clamping screws' joint could move towards them, in the pane's plane, before
    it touches one; negative: the screw is in the glass, and the pane's edge would have to move back that much —
    ``[panels] gap`` widened by twice it.  The screws are cylinders of ``diameter`` on ``axes (n, 2, 3)`` (foot,
    top).

    ``panes``: each pane on the strip, its outline edge ``k`` over the strip and its seat (mm above its face plane).
    Seen along the edge, in coordinates ``p = ((x − a)·m, (x − a)·N)`` about the edge's point ``a`` (``m`` the
    outward unit normal of the edge in the pane's plane, ``N`` the pane's normal), the glass is the half-strip
    ``p_m ≤ 0, 0 ≤ p_N − seat ≤ t``.  Moved by ``c`` along ``m`` it touches the screw's axis thickened by ``r`` when
    ``c = p_m − r·√(u_m² + u_N²)/|u_N|`` at the axis's point on the glass's underside or top (``u`` the axis's
    direction: the disc of radius ``r`` across the tilted axis reaches that far along ``m`` at one level of
    ``N``), whichever is less; ``c`` is linear along the axis, so these two ends of its part in the glass's slab
    bound it.  A kink that tilts the edge face over the joint (a valley) closes it at the glass's top by about
    ``t·tan(κ/2)``."""
    axes = np.asarray(axes, dtype=float).reshape(-1, 2, 3)
    r = 0.5 * diameter
    least = math.inf
    for panel, k, seat in panes:
        N = panel.frame.normal
        ring = panel.outline_3d()
        a, b = ring[k], ring[(k + 1) % len(ring)]
        edge = float(np.linalg.norm(b - a))
        e = (b - a) / edge
        m = np.cross(e, N)
        m /= np.linalg.norm(m)
        t = panel.thickness_mm
        for foot, top in axes:
            if not 0.0 <= float((foot - a) @ e) <= edge:
                continue                              # this screw is beside another pane of the strip
            u = top - foot
            length = float(np.linalg.norm(u))
            u = u / length
            u_m, u_N = float(u @ m), float(u @ N)
            if abs(u_N) < 1e-9:
                continue
            h0 = float((foot - a) @ N) - seat
            reach = r * math.hypot(u_m, u_N) / abs(u_N)
            for level in (0.0, t):
                s = min(max((level - h0) / u_N, 0.0), length)
                x = foot + s * u
                if -1e-9 <= float((x - a) @ N) - seat <= t + 1e-9:
                    least = min(least, float((x - a) @ m) - reach)
    return least


def joint_clearing_screws(kink_deg: float, pane_thickness: float, seat: float, diameter: float,
                          spare: float = 2.0) -> float:
    """mm: a joint width (``[panels] gap``) at which clamping screws of ``diameter`` in the joint's centre line stay
    out of the glass where two panes kink by ``kink_deg`` (a valley: it closes the joint towards the glass's top).

    Each pane's edge face leans over the joint by ``(seat + t)·tan(κ/2)`` at the glass's top, and the screw, at
    ``κ/2`` to the pane, takes ``r / cos(κ/2)`` of the half-joint in the pane's plane:
    ``gap = 2·((seat + t)·tan(κ/2) + r / cos(κ/2)) + spare``, with ``spare`` the flat joint's fit (10 mm for M8).
    ``seat``: the pane's underside above the strip's underside (strip + gasket thickness), an upper bound of
    the screw's foot below the glass.  :func:`screw_clearance` measures the real geometry; this bound is for
    proposing a design before there is one (``ppfab new``): ``smallest_roof`` (20° kinks, 17.52 mm glass,
    8 + 3 mm seat, M8) gives 20.2 mm, where 18 mm clears its screws by 0.20 mm.

    >>> round(joint_clearing_screws(0.0, 17.52, 11.0, 8.0), 6)
    10.0
    >>> round(joint_clearing_screws(20.0, 17.52, 11.0, 8.0), 1)
    20.2
    """
    b = math.radians(0.5 * max(float(kink_deg), 0.0))
    return 2.0 * ((seat + pane_thickness) * math.tan(b) + 0.5 * diameter / math.cos(b)) + spare


def _pane_top_under(strip_frame: Frame, rect: np.ndarray, panel: "Panel", top: float) -> tuple[float, float] | None:
    """Over the footprint ``rect`` (strip frame), the highest point (along the strip's normal) of the pane's top
    face ``top`` mm above its face plane, and the clamp bite (area over length along the strip); ``None`` when
    the pane does not lie under the footprint."""
    from shapely.geometry import Polygon

    u = strip_frame.normal
    N = panel.frame.normal
    denom = float(N @ u)
    if denom <= 1e-6:
        return None
    ring = panel.outline_3d() + top * N
    under = Polygon(strip_frame.to2d(ring)).intersection(Polygon(rect))
    if under.is_empty or under.area <= 1e-6:
        return None
    xy = np.array(getattr(under, "exterior", under.convex_hull.exterior).coords)[:-1]
    x0, _, x1, _ = under.bounds
    z = ((ring[0] - strip_frame.to3d(xy)) @ N) / denom
    return float(z.max()), float(under.area / max(x1 - x0, 1e-9))


def screw_stations(length: float, pitch: float, keep_out: Sequence[tuple[float, float]]) -> tuple[float, ...]:
    """Screw positions along a plate ``[0, length]``: evenly at most ``pitch`` apart and ``pitch/2`` from the ends,
    each moved out of the ``keep_out`` intervals to the nearer side, then a screw added midway in every gap still
    wider than ``pitch`` (while one fits outside the intervals).

    >>> screw_stations(1000.0, 250.0, [])
    (125.0, 375.0, 625.0, 875.0)
    """
    n = max(1, math.ceil(length / pitch - 1e-9))
    xs = [(k + 0.5) * length / n for k in range(n)]

    def free(x: float) -> float:
        for lo, hi in keep_out:
            if lo < x < hi:
                return lo if x - lo <= hi - x else hi
        return x

    xs = sorted(free(x) for x in xs)
    for _ in range(64):
        pts = [0.0 if not xs or xs[0] > 0.5 * pitch else xs[0]] + xs
        gaps = [(pts[k + 1] - pts[k], k) for k in range(len(pts) - 1)]
        wide = [(g, k) for g, k in gaps if g > pitch + 1e-6]
        if not wide:
            break
        _, k = max(wide)
        x = free(0.5 * (pts[k] + pts[k + 1]))
        if any(abs(x - y) < 1e-6 for y in xs):
            break
        xs = sorted(xs + [x])
    return tuple(round(x, 3) for x in xs if 0.0 <= x <= length)


def _spacing(stations: Sequence[float], length: float) -> float:
    """The largest distance between neighbouring screws, with each end counting at twice its distance (a screw
    ``pitch/2`` from an end spaces like a neighbour ``pitch`` away)."""
    if not stations:
        return math.inf
    inner = [b - a for a, b in zip(stations, stations[1:])]
    return max(inner + [2.0 * stations[0], 2.0 * (length - stations[-1])])


def make_retention(panels: Sequence["Panel"], seats: Sequence[PaneSeat], strips: Sequence[Strip],
                   pane_edge_strips: dict[tuple[str, int], Strip], p: GlazingParams, gap: float,
                   strip_bites: dict[str, float] | None = None) -> Retention:
    """Setting blocks, stops, pressure plates and every pane's restraint (module docstring).  ``pane_edge_strips``
    maps ``(panel id, outline edge)`` to the strip under that edge; ``gap`` is the joint width (``[panels] gap``);
    ``strip_bites`` each pane's smallest bite on its strips (mm, for ``retention = "silicone"``).

    Raises :class:`~ppfab.errors.DesignError` when setting block, stop or screw do not fit in the joint."""
    need = p.setting_block_width + p.stop_width + JOINT_SPARE
    if need > gap + 1e-9:
        raise DesignError("setting_block_width", f"setting block {p.setting_block_width:g} mm and stop "
                                                 f"{p.stop_width:g} mm and {JOINT_SPARE:g} mm to spare do not fit in "
                                                 f"the {gap:g} mm joint: narrow them or widen [panels] gap")
    bolt = None
    if p.retention == "pressure_plate":
        bolt = RetentionBolt.parse(p.retention_bolt)
        if bolt.diameter + JOINT_SPARE > gap + 1e-9:
            raise DesignError("retention_bolt", f"a {bolt.size} screw with {JOINT_SPARE:g} mm to spare does not fit "
                                                f"in the {gap:g} mm joint: use a smaller one or widen [panels] gap")
    seat_of = {s.panel: s.offset for s in seats}
    parts: list[Prism] = []
    blocks_on: dict[str, list[tuple[float, float]]] = {}
    down: dict[str, tuple[int, Strip | None, float]] = {}
    contact: dict[str, float] = {}
    panel_of = {x.part_id: x for x in panels}
    by_strip: dict[str, list[tuple["Panel", int]]] = {}
    for (pid, k), s in pane_edge_strips.items():
        by_strip.setdefault(s.part_id, []).append((panel_of[pid], k))
    for panel in panels:
        k = down_edge(panel)
        strip = pane_edge_strips.get((panel.part_id, k))
        slope = pane_slope_deg(panel.frame.normal)
        stops = slope > p.stop_min_slope_deg
        across = None
        for other, q in by_strip.get(strip.part_id, []) if strip is not None else []:
            if other.part_id != panel.part_id:
                ring = other.outline_3d() + seat_of.get(other.part_id, 0.0) * other.frame.normal
                e = ring[(q + 1) % len(ring)] - ring[q]
                m = np.cross(e, other.frame.normal)            # outward of a counter-clockwise outline
                across = (ring[q], m / np.linalg.norm(m))
        seat = seat_of.get(panel.part_id, 0.0)
        blocks = setting_blocks(panel, seat, strip, k, p, stops, across)
        parts += blocks
        down[panel.part_id] = (k, strip, slope)
        if strip is not None:
            r = 0.5 * (bolt.diameter if bolt else 0.0) + JOINT_SPARE
            for b in blocks:
                along = strip.frame.to2d(b.frame.to3d(b.outline))[:, 0]
                blocks_on.setdefault(strip.part_id, []).append((float(along.min()) - r, float(along.max()) + r))
    stations: dict[str, tuple[float, ...]] = {}
    bites: dict[str, list[float]] = {}
    spacing: dict[str, list[float]] = {}
    screws: dict[str, float] = {}
    screw_sets: list[ScrewSet] = []
    bending: dict[str, PlateBending] = {}
    plate_use: dict[str, float] = {}
    if p.retention == "pressure_plate":
        material = plate_material(p.pressure_plate_material)
        by_id = {s.part_id: s for s in strips}
        for sid, on in sorted(by_strip.items()):
            s = by_id[sid]
            half = 0.5 * p.pressure_plate_width
            # over its own panes only: a plate running on to the node would meet the corner of a pane of the next
            # span, which a kink there lifts into it
            spans = [s.frame.to2d(panel.outline_3d())[:, 0] for panel, _ in on]
            x0 = max(s.x0, min(float(a.min()) for a in spans)) + PLATE_END_GAP
            x1 = min(s.x1, max(float(a.max()) for a in spans)) - PLATE_END_GAP
            if x1 - x0 <= 1.0:
                continue
            rect = np.array([[x0, -half], [x1, -half], [x1, half], [x0, half]])
            under = {panel.part_id: _pane_top_under(s.frame, rect, panel, seat_of.get(panel.part_id, 0.0)
                                                    + panel.thickness_mm) for panel, _ in on}
            heights = [u[0] for u in under.values() if u is not None]
            if not heights:
                continue
            z = max(heights)
            layers = (("pressure_gasket", pressure_gasket_id(sid), p.pressure_gasket_thickness),
                      ("pressure_plate", pressure_plate_id(sid), p.pressure_plate_thickness),
                      ("cover_cap", cover_cap_id(sid), p.cover_cap_height))
            plate_top = z
            for kind, pid, t in layers:
                parts.append(Prism(pid, kind, sid, sid, s.beam_id, s.frame, rect, z, t))
                z += t
                if kind == "pressure_plate":
                    plate_top = z
            xs = screw_stations(x1 - x0, p.bolt_pitch, [(lo - x0, hi - x0) for lo, hi in blocks_on.get(sid, [])])
            stations[pressure_plate_id(sid)] = xs
            assert bolt is not None
            one = ScrewSet(screw_set_id(sid), pressure_plate_id(sid), sid, s.beam_id, s.frame, x0, s.thickness,
                           plate_top - s.thickness + NUT_HEIGHT * bolt.diameter, bolt.diameter, xs)
            one = replace(one, clearance_mm=screw_clearance(one.axes(), bolt.diameter,
                                                            [(panel, k, seat_of.get(panel.part_id, 0.0))
                                                             for panel, k in on]))
            screw_sets.append(one)
            line = sum(p.load_factor * p.wind_suction * 1e-3 * panel.area_mm2 / _perimeter(panel) for panel, _ in on)
            bending[pressure_plate_id(sid)] = plate_bending(
                pressure_plate_id(sid), line, xs, x1 - x0, p.pressure_plate_width, p.pressure_plate_thickness,
                material, p.load_factor)
            for panel, _ in on:
                plate_use[panel.part_id] = max(plate_use.get(panel.part_id, 0.0),
                                               bending[pressure_plate_id(sid)].utilisation)
            for panel, _ in on:
                u = under[panel.part_id]
                bites.setdefault(panel.part_id, []).append(u[1] if u is not None else 0.0)
                spacing.setdefault(panel.part_id, []).append(_spacing(xs, x1 - x0))
            # each pane's share of the plate's screws: by the tributary of its edge (half a joint each side)
            for panel, _ in on:
                screws[panel.part_id] = screws.get(panel.part_id, 0.0) + len(xs) / len(on)
    # a block or stop in the joint stands clear of the pressure gasket over it, not only of its own pane's top:
    # beside a ridge the pane's top plane, carried past its edge into the joint, rises above the gasket's
    # underside (the highest glass top under it) by the gap's share times tan(κ/2) — 0.37 mm into it on a real
    # dome whose panes kink by 22°
    under_gasket = {x.strip: x.z0 for x in parts if x.kind == "pressure_gasket"}
    frame_of = {x.part_id: x.frame for x in strips}
    parts = [_below_gasket(x, frame_of[x.strip], under_gasket[x.strip])
             if x.kind in ("setting_block", "stop") and x.strip in under_gasket else x for x in parts]
    for b in parts:                                  # the height over which each pane bears on its blocks
        if b.kind == "setting_block":
            base = seat_of.get(b.owner, 0.0)
            bears = min(b.z0 + b.height, base + panel_of[b.owner].thickness_mm) - max(b.z0, base)
            contact[b.owner] = min(contact.get(b.owner, bears), bears)
    out = []
    for panel in panels:
        k, strip, slope = down[panel.part_id]
        w = panel.weight_kg * G
        lb = min(p.setting_block_length, 0.4 * float(np.linalg.norm(np.roll(panel.outline, -1, axis=0)[k]
                                                                    - panel.outline[k])))
        load = 0.5 * w * math.sin(math.radians(slope))
        uplift = p.load_factor * p.wind_suction * panel.area_mm2 * 1e-6
        n = screws.get(panel.part_id, 0.0)
        res = n * bolt.tension_resistance_kN if bolt is not None else 0.0
        short = _shortest_width(np.asarray(panel.outline, dtype=float))
        sil = p.load_factor * p.wind_suction * 1e-3 * short / (2.0 * p.silicone_design_stress)
        out.append(PaneRestraint(panel.part_id, slope, panel.weight_kg, k, strip.part_id if strip else "", load,
                                 load / (lb * max(contact[panel.part_id], 1.0)), slope > p.stop_min_slope_deg,
                                 uplift, n, res, min(bites.get(panel.part_id, [math.nan])),
                                 max(spacing.get(panel.part_id, [0.0])), sil,
                                 (strip_bites or {}).get(panel.part_id, math.nan), contact[panel.part_id],
                                 plate_use.get(panel.part_id, math.nan)))
    tight = sorted((x for x in screw_sets if 0.0 < -x.clearance_mm <= SCREWS_IN_GLASS_MM),
                   key=lambda x: x.clearance_mm)
    if tight:
        log.warning("%d pressure plate(s) have clamping screws touching the glass beside their joint, where a kink "
                    "closes the joint towards the glass's top: %s, within the %g mm the build allows; widen [panels] "
                    "gap to at least %.0f mm for room", len(tight),
                    ", ".join(f"{x.part_id} ({-x.clearance_mm:.2f} mm)" for x in tight[:8]), SCREWS_IN_GLASS_MM,
                    clearing_gap(gap, tight[0].clearance_mm))
    low = [(x, c) for x in panels if (c := contact[x.part_id]) < 0.5 * x.thickness_mm]
    if low:
        log.warning("%d pane(s) bear on their setting blocks over less than half the glass edge, where a kink closes "
                    "the joint over the block: %s; widen [panels] gap there or give them a bracket under the edge",
                    len(low), ", ".join(f"{x.part_id} ({c:.1f} of {x.thickness_mm:g} mm)" for x, c in low[:8]))
    return Retention(p, bolt, tuple(parts), stations, tuple(out), tuple(screw_sets), bending)


def _perimeter(panel: "Panel") -> float:
    """mm: the length of a pane's outline."""
    q = np.asarray(panel.outline, dtype=float)
    return float(np.linalg.norm(np.roll(q, -1, axis=0) - q, axis=1).sum())


def _shortest_width(outline: np.ndarray) -> float:
    """The smallest width (mm) of a convex outline over the directions of its edge normals."""
    d = np.roll(outline, -1, axis=0) - outline
    n = np.stack([d[:, 1], -d[:, 0]], axis=1) / np.linalg.norm(d, axis=1, keepdims=True)
    proj = outline @ n.T
    return float((proj.max(axis=0) - proj.min(axis=0)).min())


_CACHE: "weakref.WeakKeyDictionary[Any, Retention]" = weakref.WeakKeyDictionary()


def build_retention(build: "Build") -> Retention | None:
    """The :class:`Retention` of a build, computed once per build's glazing; ``None`` without glazing strips or
    with ``retention = "none"``."""
    from .bite import pane_edges
    from .seat import build_seats

    g = build.glazing
    if g is None or not g.strips or g.params.retention == "none":
        return None
    r = _CACHE.get(g)
    if r is None:
        by_edge = {s.edge: s for s in g.strips}
        support = build.support
        pes = {(panel.part_id, q): by_edge[e] for panel, q, e in pane_edges(build.panels.panels, support.vertices,
                                                                            support.edges) if e in by_edge}
        bites: dict[str, float] = {}
        for b in g.bites:
            bites[b.panel] = min(bites.get(b.panel, math.inf), b.bite)
        r = make_retention(build.panels.panels, build_seats(build), g.strips, pes, g.params,
                           float(build.design.panels.gap), bites)
        _CACHE[g] = r
    return r


SCREWS_IN_GLASS_MM = 0.25
"""mm: how far a clamping screw may stand in the glass beside its joint before the build refuses (the tolerance
of the erection check for parts in place, :data:`fabrication.verify.erection.TOLERANCE`)."""


def clearing_gap(gap: float, clearance: float) -> int:
    """The whole-millimetre joint (mm) that gives a screw standing ``−clearance`` mm in the glass beside a ``gap``
    joint half a millimetre of room: the joint widened by twice the depth, each pane's edge moving half of it."""
    return math.ceil(gap - 2.0 * clearance + 0.5)


def refuse_screws_in_glass(retention: Retention | None, gap: float) -> None:
    """Raise :class:`~ppfab.errors.DesignError` (``panels.gap``) naming the pressure plates whose clamping screws
    stand more than :data:`SCREWS_IN_GLASS_MM` in the glass (a kink closing the joint towards the glass's top)
    and the joint that clears them: before any file is written, where the build's verify would refuse them
    after writing every file (glass takes no steel)."""
    from ppfab.errors import DesignError

    if retention is None:
        return
    deep = sorted((x for x in retention.screws if -x.clearance_mm > SCREWS_IN_GLASS_MM), key=lambda x: x.clearance_mm)
    if deep:
        raise DesignError("panels.gap", f"{len(deep)} pressure plate(s) have clamping screws standing in the glass "
                                        "beside their joint, where a kink closes it towards the glass's top: "
                                        + ", ".join(f"{x.part_id} ({-x.clearance_mm:.2f} mm)" for x in deep[:6])
                                        + f"; glass takes no steel: widen [panels] gap to at least "
                                        f"{clearing_gap(gap, deep[0].clearance_mm):.0f} mm (from {gap:g}), "
                                        "or clamp with a smaller [glazing] retention_bolt")


def retention_mass_kg(build: "Build") -> float:
    """kg: every retention part of a build (its prisms and screws, as their ``parts.csv`` rows give them); 0
    without retention."""
    r = build_retention(build)
    if r is None:
        return 0.0
    return float(sum(p.mass_kg for p in r.parts) + sum(s.mass_kg for s in r.screws))
