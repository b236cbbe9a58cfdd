"""Where the clamping screws of a pressure plate go and whether they stay out of the glass: their stations along
the plate, their clear distance to the panes beside the joint, the joint width that clears them, and the build's
refusal of screws standing in the glass (:mod:`.retention` places the plates and their
:class:`~.retention.ScrewSet`)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Sequence

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from ..panels import Panel
    from .retention import Retention

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


def screw_stations(length: float, pitch: float, keep_out: Sequence[tuple[float, float]]) -> tuple[float, ...]:
    """Screw positions along a plate ``[0, length]``: evenly at most ``pitch`` apart and ``pitch/2`` from the ends,
    each moved out of the ``keep_out`` intervals to the nearer side, then a screw added midway in every gap still
    wider than ``pitch`` (while one fits outside the intervals), an end's gap counting at twice its distance as
    :func:`screw_spacing` and ``ppfab verify`` count it — a screw moved off an interval towards the middle can
    leave an end more than ``pitch/2`` from its screw (143.5 mm at a 250 mm pitch on the default at 44 × 30).

    >>> screw_stations(1000.0, 250.0, [(60.0, 130.0)])      # the first screw moved off a block to 130 mm
    (60.0, 130.0, 375.0, 625.0, 875.0)

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
        # the gaps as :func:`screw_spacing` counts them: between neighbours, and each end at twice its distance
        pts = [0.0] + xs + [length]
        last = len(pts) - 2
        gaps = [((2.0 if k in (0, last) else 1.0) * (pts[k + 1] - pts[k]), k) for k in range(len(pts) - 1)]
        wide = [(g, k) for g, k in gaps if g > pitch + 1e-6]
        if not wide:
            break
        _, k = max(wide)
        x = free(0.5 * (pts[k] + pts[k + 1]))
        if any(abs(x - y) < 1e-6 for y in xs):
            break
        xs = sorted(xs + [x])
    return tuple(round(x, 3) for x in xs if 0.0 <= x <= length)


def screw_spacing(stations: Sequence[float], length: float) -> float:
    """The largest distance between neighbouring screws, with each end counting at twice its distance (a screw
    ``pitch/2`` from an end spaces like a neighbour ``pitch`` away)."""
    if not stations:
        return math.inf
    inner = [b - a for a, b in zip(stations, stations[1:])]
    return max(inner + [2.0 * stations[0], 2.0 * (length - stations[-1])])


SCREWS_IN_GLASS_MM = 0.25
"""mm: how far a clamping screw may stand in the glass beside its joint before the build refuses (the tolerance
of the erection check for parts in place, :data:`fabrication.verify.erection.TOLERANCE`)."""


def clearing_gap(gap: float, clearance: float) -> int:
    """The whole-millimetre joint (mm) that gives a screw standing ``−clearance`` mm in the glass beside a ``gap``
    joint half a millimetre of room: the joint widened by twice the depth, each pane's edge moving half of it."""
    return math.ceil(gap - 2.0 * clearance + 0.5)


def refuse_screws_in_glass(retention: "Retention | None", gap: float) -> None:
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
