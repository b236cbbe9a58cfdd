"""Where each pane sits: its underside resting on the gaskets, the one source of the panes' placed position.

A pane is its inset outline in the panel frame (origin, ``ex``, ``ey`` in the face's least-squares plane, normal
``N`` to the outside).  It rests on the gaskets of the glazing strips under its edges, whose top faces lie
``t_s + t_g`` (strip + gasket) above the mesh edge along the strip's ``up`` (:mod:`.strips`).  The placed pane
is the outline moved along ``N`` by its *seat* ``h``: the underside at ``z = h``, the top face at ``h + t``.

The gasket tops are not parallel to the pane: each is tilted by half the kink between the panes on its edge.
So no single height makes the whole underside touch.  The seat is the lowest height at which the pane
penetrates no gasket: for every face of a strip with its gasket that faces the pane (the gasket's top, and a
side where it leans under the pane: a running strip's square end beside a node can reach under the corner of
the next pane by a fraction of a millimetre, 0.17 mm on a real grid when only the tops counted) whose
projection along ``N`` into the pane's plane overlaps the pane's outline (the overlap polygon, by shapely),
the height along ``N`` of the face's plane above each vertex of the overlap; the pane's underside and a plane
meet in a line, so the highest of these vertices is the highest point of the box under the pane,

    z(v) = ((T − O − v₃)·u) / (N·u),    h = max over overlaps and their vertices of z(v),

with ``T`` a corner of the gasket top, ``u`` its normal, ``O`` the frame origin and ``v₃ = x·ex + y·ey``.  The
pane touches the highest gasket (gap 0) and stands off the others by ``h − max z`` of each (their *gap*);
on a ridge of the roof a gasket tilts up into the pane's span, in a valley away from it, so a pane between
a ridge edge and a valley edge stands off its valley gasket by some 30 mm × the sum of the two half-kinks'
sines.  The strip under a gasket has the same outline, so a pane clear of the gasket is clear of its strip.

Nominal seat ``t_s + t_g`` (the pane parallel to its face, on a gasket parallel to it): the bite
(:mod:`.bite`) projects the gaskets along ``N`` and does not depend on the seat.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Sequence

import numpy as np

from .strips import Strip

if TYPE_CHECKING:  # pragma: no cover
    from ..panels import Panel

SEAT_TOLERANCE = 0.1
"""mm: how far a placed pane may penetrate a gasket or strip, or stand off the gasket it bears on, in the
written models (``ppfab verify``'s clash check, tests/test_assembly_clash.py).  The seat itself is exact to
rounding; the tolerance absorbs the STEP file's decimals and the kernel's and the mesh readers' numerics."""


@dataclass(frozen=True)
class Contact:
    """A gasket under a pane: the strip's part id, the area (mm²) of the gasket top under the pane (projected
    along the pane's normal) and the gap (mm) between the pane's underside and the highest point of that
    gasket under it (0 for the gasket the pane bears on)."""

    strip: str
    area: float
    gap: float


@dataclass(frozen=True)
class PaneSeat:
    """The placed position of one pane: its underside lies ``offset`` mm above its face's plane along the
    outside normal; ``contacts`` are the gaskets under it, the one it bears on has ``gap`` 0."""

    panel: str
    offset: float
    contacts: tuple[Contact, ...]

    @property
    def largest_gap(self) -> float:
        """The largest gap (mm) of this pane over a gasket under it (0 without contacts)."""
        return max((c.gap for c in self.contacts), default=0.0)


def _faces(strip: Strip, gasket: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The faces a pane can come down on of the strip with its gasket, the box ``x0 ≤ x ≤ x1, |y| ≤ w/2,
    0 ≤ z ≤ t_s + t_g`` of the strip frame: the gasket's top and the four sides, each as ``(4, 3)`` corners and
    its outward unit normal."""
    f = strip.frame
    flat = f.to3d(strip.outline())                       # counter-clockwise: x0,-b  x1,-b  x1,b  x0,b
    top = strip.top_corners(gasket)
    out = [(top, f.normal)]
    for k, normal in enumerate((-f.ey, f.ex, f.ey, -f.ex)):
        a, b = k, (k + 1) % 4
        out.append((np.array([flat[a], flat[b], top[b], top[a]]), normal))
    return out


def seat_pane(panel: "Panel", strips: Sequence[Strip], gasket: float, nominal: float) -> PaneSeat:
    """The :class:`PaneSeat` of ``panel`` on the gaskets of ``strips`` (those near it; others are skipped by
    their overlap).  Without any gasket under it the pane keeps the ``nominal`` seat."""
    from shapely.geometry import Polygon

    f = panel.frame
    N = f.normal
    pane = Polygon(np.asarray(panel.outline, dtype=float))
    tops: list[tuple[str, float, float]] = []
    for s in strips:
        area, highest = 0.0, -np.inf
        for k, (face, u) in enumerate(_faces(s, gasket)):
            denom = float(N @ u)
            if denom <= 1e-6:                        # a face turned away from the pane cannot carry it
                continue
            under = Polygon(f.to2d(face)).convex_hull.intersection(pane)
            if under.is_empty or under.area <= 1e-9:
                continue
            ring = np.array(getattr(under, "exterior", under.convex_hull.exterior).coords)[:-1]
            v3 = f.to3d(ring)
            highest = max(highest, float((((face[0] - v3) @ u) / denom).max()))
            if k == 0:
                area = float(under.area)
        if np.isfinite(highest):
            tops.append((s.part_id, area, highest))
    if not tops:
        return PaneSeat(panel.part_id, float(nominal), ())
    h = max(z for _, _, z in tops)
    return PaneSeat(panel.part_id, h, tuple(Contact(pid, area, h - z) for pid, area, z in tops))


def seat_panes(panels: Sequence["Panel"], strips: Sequence[Strip], gasket: float) -> tuple[PaneSeat, ...]:
    """The :class:`PaneSeat` of every pane, in panel order (see the module docstring).  Broad phase: only the
    strips whose centre lies within the pane's radius plus the strip's half diagonal (a k-d tree)."""
    from scipy.spatial import cKDTree

    if not strips:
        return tuple(PaneSeat(p.part_id, 0.0, ()) for p in panels)
    nominal = strips[0].thickness + gasket
    centres = np.array([s.frame.to3d(np.array([0.5 * (s.x0 + s.x1), 0.0])) for s in strips])
    reach = max(0.5 * float(np.hypot(s.length, s.width)) for s in strips) + nominal + 1.0
    tree = cKDTree(centres)
    out = []
    for p in panels:
        ring = p.outline_3d()
        c = ring.mean(axis=0)
        r = float(np.linalg.norm(ring - c, axis=1).max())
        near = [strips[k] for k in sorted(tree.query_ball_point(c, r + reach))]
        out.append(seat_pane(p, near, gasket, nominal))
    return tuple(out)


def seat_range(nominal: float, width: float, tilt_deg: float, flatness: float) -> tuple[float, float]:
    """mm: where the gaskets of a pane's own edges can put its underside above its face — the nominal
    ``t_s + t_g`` ± half the strip width times the tangent of the steepest gasket tilt ``tilt_deg`` (at most 45°;
    the larger of ``glazing.max_tilt_deg`` and the bites' tilts) ± ``flatness`` (``panels.planarity_tolerance``:
    a face's corners off its plane).  The build refuses panes above it (:func:`refuse_lifted_panes`); the
    self-check holds every written pane to it (``seat_range`` of :mod:`fabrication.verify._solids`, from the
    files' values)."""
    spread = 0.5 * width * float(np.tan(np.radians(min(tilt_deg, 45.0))))
    return nominal - spread - flatness, nominal + spread + flatness


def refuse_lifted_panes(seats: Sequence[PaneSeat], limit: float, nominal: float) -> None:
    """Raise :class:`~ppfab.errors.DesignError` (``glazing.seat``) naming the panes seated above ``limit``
    (the top of :func:`seat_range`), each with the strip it bears on and how far it stands off its other gaskets: such a pane
    rests on a gasket under its corner — the end of a strip of the next span, where its beam kinks towards the
    glass under an obtuse corner — and stands off its own edges' gaskets; the self-check would refuse the
    written files (the pane off its face's seat range).  Before any file is written."""
    high = sorted((s for s in seats if s.offset > limit + 1e-9), key=lambda s: -s.offset)
    if not high:
        return
    from ppfab.errors import DesignError

    def one(s: PaneSeat) -> str:
        bearing = min(s.contacts, key=lambda c: c.gap)
        return (f"{s.panel} on {bearing.area:.0f} mm² of {bearing.strip}, {s.offset - nominal:.1f} mm above nominal "
                f"and up to {s.largest_gap:.1f} mm off its other gaskets")

    raise DesignError("glazing.seat", f"{len(high)} pane(s) would rest above the highest seat their own gaskets give "
                                      f"({limit:.1f} mm, nominal {nominal:g} mm): {'; '.join(one(s) for s in high[:4])}"
                                      " — a strip end under the pane's corner where its beam kinks towards the "
                                      "glass; make the kinks smaller (a smaller [surface] spacing, a smoother net) "
                                      "or let the glass rest on its edges in another way ([glazing] support)")
