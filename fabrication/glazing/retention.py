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
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ppfab.errors import DesignError
from ppfab.frame import Frame

from ..contract import (cover_cap_id, pressure_gasket_id, pressure_plate_id, screw_set_id, setting_block_id,
                        stop_id)
from .params import GlazingParams
from .retention_strength import PlateBending, RetentionBolt, plate_bending, plate_material
from .screws import SCREWS_IN_GLASS_MM, screw_spacing, clearing_gap, screw_clearance, screw_stations
from .seat import PaneSeat
from .slope import pane_slope_deg
from .strips import Strip

if TYPE_CHECKING:  # pragma: no cover
    from ..panels import Panel
    from ppfab.support.structure import SupportStructure

    from . import Glazing

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
NUT_HEIGHT = 0.8
"""A clamping screw's length above the plate, in diameters: the nut (ISO 4032: ``m ≈ 0.8·d``)."""
DENSITY = {"setting_block": 1300.0, "stop": 7850.0, "pressure_gasket": 1200.0, "pressure_plate": 2700.0,
           "cover_cap": 2700.0, "screw": 8000.0}
"""kg/m³ of each retention kind: silicone 80 Shore A, S355, EPDM, aluminium (EN 1999-1-1 3.2.5), stainless steel
(EN 10088-1, A2/A4)."""
CAP_WALL = 2.0
"""mm: the wall of a cover cap, an extruded channel over the plate: its mass is ``(width + 2·height)·wall``
per mm of length (the model draws the cap as the prism it fills)."""


def material_of(kind: str, p: GlazingParams) -> str:
    """The material cell (retention.csv, parts.csv) of a retention part of ``kind``."""
    return {"setting_block": p.setting_block_material, "stop": "S355", "pressure_gasket": "EPDM 70 Shore A",
            "screw": f"stainless steel {p.retention_bolt}"}.get(kind, p.pressure_plate_material)


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
    cramped: tuple["CrampedBlock", ...] = ()
    crowded: tuple["CrowdedBlock", ...] = ()


AcrossFace = tuple[np.ndarray, np.ndarray, np.ndarray, float]
"""The glass across a joint at its edge: a point on the bottom edge of its edge face ``(3,)``, the face's outward
unit normal ``(3,)`` (towards the joint), the pane's unit normal ``(3,)`` and its thickness (mm)."""


@dataclass(frozen=True)
class CrowdedBlock:
    """A setting block of pane ``panel`` that finds no station on its edge clear of the blocks and stops of the
    pane across the same joint (a valley: both panes' down-slope edges on strip ``strip``), ``length_mm`` long."""

    panel: str
    strip: str
    length_mm: float


@dataclass(frozen=True)
class CrampedBlock:
    """A pane whose setting block has less than :data:`MIN_BLOCK_MM` of height below the pane across the joint
    (a kink closes the joint over it): ``room_mm`` the height it has (negative: the pane across comes down to the
    block's foot), ``widen_mm`` how much wider the joint must be for the block to stand :data:`MIN_BLOCK_MM`."""

    panel: str
    room_mm: float
    widen_mm: float


MIN_BLOCK_MM = 1.0
"""The lowest setting block or stop ppfab places (mm)."""


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


def _below_face(points3: np.ndarray, normal: np.ndarray, face: "AcrossFace | None", cap: float = math.inf) -> float:
    """How far (mm) the convex footprint ``points3 (k, 3)`` may rise along ``normal`` (a prism growing from it)
    before it enters the glass across the joint: the part of that pane's slab (between its bottom and top faces)
    on the inner side of its edge face (:data:`AcrossFace`); ``inf`` when it never does.

    The first height of contact is a small linear programme: the least ``h ≥ 0`` with a point ``Σ λ_i p_i + h·n``
    (``λ`` convex weights of the footprint's corners) inside the slab and behind the edge face — exact for the
    convex block against the pane's edge region, where only the edge face, not its infinite plane, bounds the
    glass.  The glass lies behind that plane, so the height at which the footprint reaches the plane is a lower
    bound: when it is ``cap`` or more (the block is never that tall) it is returned without the programme."""
    if face is None:
        return math.inf
    pts = np.asarray(points3, dtype=float)
    origin, m, up, thick = face
    rate = float(normal @ m)
    ahead = (pts - origin) @ m                            # ≥ 0: in front of the edge face's plane
    if rate >= -1e-12:                                    # rising does not bring the footprint nearer the plane
        plane = math.inf if float(ahead.min()) >= 0.0 else 0.0
    else:
        plane = float((ahead / -rate).min())
    if plane >= cap:
        return plane
    from scipy.optimize import linprog

    k = len(pts)
    # variables: λ (k), h; rows: m·(x − o) ≤ 0, −up·(x − o) ≤ 0, up·(x − o) ≤ t
    a_m = np.r_[pts @ m - origin @ m, normal @ m]
    a_up = np.r_[pts @ up - origin @ up, normal @ up]
    res = linprog(np.r_[np.zeros(k), 1.0], A_ub=np.stack([a_m, -a_up, a_up]), b_ub=np.array([0.0, 0.0, thick]),
                  A_eq=np.r_[np.ones(k), 0.0][None], b_eq=np.array([1.0]),
                  bounds=[(0.0, None)] * (k + 1), method="highs")
    return float(res.x[-1]) if res.status == 0 else math.inf


def _clear_of(s: float, towards: float, lb: float, length: float, along,
              avoid: Sequence[tuple[float, float]]) -> float | None:
    """A block centred ``s`` mm along its edge (``lb`` long) moved until its span along the strip (``along(t)``:
    strip ``x`` of the point ``t`` mm along the edge) is clear of every interval of ``avoid`` by
    :data:`JOINT_SPARE`: first by ``towards`` (±1: to the edge's middle, at most to it), then the other way (at
    most to the edge's end).  ``None`` when no station on either stretch is clear."""
    def hit(t: float) -> tuple[float, float, float, float] | None:
        x = sorted((float(along(t - 0.5 * lb)), float(along(t + 0.5 * lb))))
        for u, v in avoid:
            if x[0] < v + JOINT_SPARE and u - JOINT_SPARE < x[1]:
                return x[0], x[1], u, v
        return None

    ends = (0.5 * lb, length - 0.5 * lb)
    for way in (towards, -towards):
        bound = 0.5 * length if way == towards else (ends[1] if way > 0 else ends[0])
        t = s
        for _ in range(len(avoid) + 2):
            h = hit(t)
            if h is None:
                return t
            x0, x1, u, v = h
            t = t + way * max(v + JOINT_SPARE - x0, x1 - (u - JOINT_SPARE))   # the larger way out: always enough
            if (way > 0 and t > bound) or (way < 0 and t < bound):
                t = bound
                if hit(t) is None:
                    return t
                break
    return None


def _widen_for_block(points3: np.ndarray, normal: np.ndarray, out3: np.ndarray, face: "AcrossFace") -> float:
    """How much wider (mm) the joint must be for a block on ``points3`` to stand :data:`MIN_BLOCK_MM` under the
    glass across: the joint widened by ``Δ`` moves each pane's edge ``Δ / 2`` away from it (the block along
    ``−out3``, the face across along its normal), found by bisection on :func:`_below_face`."""
    origin, m, up, thick = face

    def room(delta: float) -> float:
        moved = (origin - 0.5 * delta * m, m, up, thick)
        return _below_face(points3 - 0.5 * delta * out3, normal, moved) - 0.5 * JOINT_SPARE

    lo, hi = 0.0, 1.0
    while room(hi) < MIN_BLOCK_MM and hi < 1000.0:
        lo, hi = hi, 2.0 * hi
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if room(mid) >= MIN_BLOCK_MM else (mid, hi)
    return hi


def setting_blocks(panel: "Panel", seat: float, strip: Strip | None, edge: int, p: GlazingParams,
                   stops: bool, across: AcrossFace | None = None,
                   cramped: list[CrampedBlock] | None = None,
                   avoid: Sequence[tuple[float, float]] = (),
                   crowded: list[CrowdedBlock] | None = None) -> list[Prism]:
    """The two setting blocks of a pane (and their stops when ``stops``) on outline edge ``edge``; ``across``
    is the glass across the joint (:data:`AcrossFace`): where a kink brings it over the joint, a block or stop
    reaches only to :data:`JOINT_SPARE` / 2 below it.  A block with less room than :data:`MIN_BLOCK_MM` is still
    placed that high, and noted in ``cramped``.  ``avoid``: intervals along the strip's ``x`` (mm) taken by the
    blocks of the pane across the same joint (a valley, where both panes' down-slope edges lie on one strip):
    each block moves from its quarter point towards the edge's middle (failing that, towards its end) until it is
    clear of them and of the pane's own first block by :data:`JOINT_SPARE`; one that finds no such station stays
    at its quarter point and is noted in ``crowded``."""
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
    taken = list(avoid)
    for k, s in enumerate((0.25 * L, 0.75 * L), start=1):
        if avoid and strip is not None:
            def along(t: float, strip: Strip = strip) -> float:
                return float(strip.frame.to2d(f.to3d(a + t * d))[0])

            clear = _clear_of(s, 1.0 if k == 1 else -1.0, lb, L, along, taken)
            if clear is None:
                if crowded is not None:
                    crowded.append(CrowdedBlock(owner, sid, lb))
            else:
                s = clear
            x0, x1 = sorted((along(s - 0.5 * lb), along(s + 0.5 * lb)))
            taken.append((x0, x1))
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
            reach = _below_face(f.to3d(rect) + base * N, N, across, top - base + 0.5 * JOINT_SPARE) - 0.5 * JOINT_SPARE
            room = min(top - base, reach)
            if room < MIN_BLOCK_MM and cramped is not None and across is not None:
                cramped.append(CrampedBlock(owner, room, _widen_for_block(f.to3d(rect) + base * N, N, f.vec3d(o),
                                                                         across)))
            height = max(room, MIN_BLOCK_MM)
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
    cramped: list[CrampedBlock] = []
    crowded: list[CrowdedBlock] = []
    blocks_on: dict[str, list[tuple[float, float]]] = {}
    placed: dict[str, list[tuple[float, float]]] = {}         # blocks and stops along each strip, as placed
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
                across = (ring[q], m / np.linalg.norm(m), other.frame.normal, float(other.thickness_mm))
        seat = seat_of.get(panel.part_id, 0.0)
        blocks = setting_blocks(panel, seat, strip, k, p, stops, across, cramped,
                                placed.get(strip.part_id, []) if strip is not None else (), crowded)
        parts += blocks
        down[panel.part_id] = (k, strip, slope)
        if strip is not None:
            r = 0.5 * (bolt.diameter if bolt else 0.0) + JOINT_SPARE
            for b in blocks:
                along = strip.frame.to2d(b.frame.to3d(b.outline))[:, 0]
                blocks_on.setdefault(strip.part_id, []).append((float(along.min()) - r, float(along.max()) + r))
                placed.setdefault(strip.part_id, []).append((float(along.min()), float(along.max())))
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
                spacing.setdefault(panel.part_id, []).append(screw_spacing(xs, x1 - x0))
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
    return Retention(p, bolt, tuple(parts), stations, tuple(out), tuple(screw_sets), bending, tuple(cramped),
                     tuple(crowded))


def refuse_blocks_in_glass(retention: "Retention | None", gap: float) -> None:
    """Raise :class:`~ppfab.errors.DesignError` (``panels.gap``) naming the panes whose setting blocks have less
    than :data:`MIN_BLOCK_MM` of room under the pane across their joint (a kink closes the joint over them: the
    block would stand in that glass) and the joint that gives them room: before any file is written, where the
    build's clash check would refuse the files after writing them.  Blocks that find no station clear of the
    blocks of the pane across a valley joint are refused first (``glazing.setting_block_length``)."""
    if retention is None:
        return
    if retention.crowded:
        crowd = sorted({(x.panel, x.strip): x for x in retention.crowded}.values(), key=lambda x: x.panel)
        raise DesignError("glazing.setting_block_length",
                          f"{len(crowd)} pane(s) find no station for a setting block clear of the blocks of the pane "
                          "across their valley joint (both panes' down-slope edges on one strip): "
                          + ", ".join(f"{x.panel} on {x.strip} ({x.length_mm:.0f} mm blocks)"
                                      for x in crowd[:6])
                          + "; shorten [glazing] setting_block_length (now "
                          + f"{retention.params.setting_block_length:g} mm)")
    if not retention.cramped:
        return
    worst: dict[str, CrampedBlock] = {}
    for c in retention.cramped:
        if c.panel not in worst or c.widen_mm > worst[c.panel].widen_mm:
            worst[c.panel] = c
    order = sorted(worst.values(), key=lambda c: (-c.widen_mm, c.panel))
    need = math.ceil(gap + max(c.widen_mm for c in order) + 0.01)
    raise DesignError("panels.gap", f"{len(order)} pane(s) have no room for their setting blocks, where a kink closes "
                                    "the joint over them (the pane across comes down to the block): "
                                    + ", ".join(f"{c.panel} ({c.room_mm:.2f} mm of {MIN_BLOCK_MM:g})" for c in order[:6])
                                    + f"; widen [panels] gap to at least {need} mm (from {gap:g}) or give these "
                                    "panes a bracket under the edge")


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


def retention_of(panels: Sequence["Panel"], seats: Sequence[PaneSeat], glazing: "Glazing | None",
                 support: "SupportStructure", gap: float) -> Retention | None:
    """The :class:`Retention` of a build's panes (``seats``: where each rests, in panel order) on the glazing
    strips over the support structure's edges; ``None`` without glazing strips or with ``retention = "none"``.
    ``gap``: the joint width between panes (mm)."""
    from .bite import pane_edges

    g = glazing
    if g is None or not g.strips or g.params.retention == "none":
        return None
    by_edge = {s.edge: s for s in g.strips}
    pes = {(panel.part_id, q): by_edge[e] for panel, q, e in pane_edges(panels, support.vertices, support.edges)
           if e in by_edge}
    bites: dict[str, float] = {}
    for b in g.bites:
        bites[b.panel] = min(bites.get(b.panel, math.inf), b.bite)
    return make_retention(panels, tuple(seats), g.strips, pes, g.params, float(gap), bites)


def retention_mass_kg(retention: Retention | None) -> float:
    """kg: every retention part (its prisms and screws, as their ``parts.csv`` rows give them); 0 without
    retention."""
    if retention is None:
        return 0.0
    return float(sum(p.mass_kg for p in retention.parts) + sum(s.mass_kg for s in retention.screws))
