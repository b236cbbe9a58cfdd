"""The ``conjugate`` net: the conjugate net of a height field nearest two guide directions.

Two tangent directions ``a``, ``b`` are conjugate when ``II(a, b) = 0`` (§3.1 of the paper: the polylines of a
mesh with planar quads discretise a conjugate net).  In plan coordinates of ``z = f(x, y)`` the second form is
``II = ∇²f / sqrt(1 + |∇f|²)`` (:mod:`.curvature`), so the direction conjugate to ``u`` is the plan direction
perpendicular to ``II u``:

    w(u) = J II u,   J = [[0, −1], [1, 0]]   (the plan rotation by 90°),

and every conjugate pair at a point is ``(u(θ), w(u(θ)))`` for one angle ``θ ∈ [0, π)``.  At each point the pair
nearest the guides ``g1``, ``g2`` (unit plan directions; by default the plan frame's axes) minimises

    E(θ) = sin²∠(u(θ), g1) + sin²∠(w(θ), g2) + OPEN · cos²∠(u, w) + TIE · max(0, −(u·g1)(u·g2))

(plan angles of lines: the sign of a direction is free; :data:`OPEN` prefers the more open of pairs about as
near the guides, :data:`TIE` takes mirror-image pairs the same way round everywhere).  Each pair is reached once with family 1 along
``u(θ)`` and once with family 2 along it (so that a ruling of a parabolic part — ``II u = 0``, every direction
conjugate to it — can be either family); ``E`` is sampled every ``π / SAMPLES`` and refined around the best
sample, and where the whole second form vanishes (a flat part: every pair is conjugate) the guides themselves
are the pair.  The field is
pointwise: it is as smooth as the fitted second form, whose spline is already smoothed over the panel size.

Where the chosen pair closes to less than :data:`MIN_PAIR_ANGLE_DEG` (near an asymptotic direction of a saddle
part, where a direction is conjugate to itself) the quads would degenerate: :func:`conjugate_net` refuses with
the place in mm.  The curves of the two families are traced and intersected by :mod:`.traced`, as the principal
net's.  Liu et al. (2011) and Zadravec, Schiftner & Wallner (2010) optimise a smooth conjugate direction field
over a triangle mesh; on a height-field roof the pointwise pair of the smoothed second form is that field
without the solve.

Examples
--------
>>> import numpy as np
>>> I = np.eye(2)[None]; II = np.array([[[0.02, 0.0], [0.0, 0.01]]])      # principal axes along x and y
>>> d1, d2, e = conjugate_pair(I, II, np.array([1.0, 0.0]), np.array([0.0, 1.0]))
>>> np.round(np.abs(d1[0]), 6).tolist(), np.round(np.abs(d2[0]), 6).tolist(), float(np.round(e[0], 9))
([1.0, 0.0], [0.0, 1.0], 0.0)
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..errors import DesignError, GeometryError
from .curvature import forms
from .heightfield import HeightField
from .plan import PlanFrame
from .sections import EDGE_MARGIN, FLAT, SectionsNet, grid_inside
from .traced import DirectionField, traced_net

SAMPLES = 90
"""Angles ``θ`` sampled over ``[0, π)`` (every 2°) before the best one is refined (three times, each over one step
either side in 11 samples: to 0.016°)."""

RULING = 0.05
"""``u`` with ``|II u| < RULING · |II|`` (near the ruling of a parabolic point) is not a candidate."""

OPEN = 0.5
"""Weight of ``cos²∠(d1, d2)`` in ``E``: of pairs about as near the guides, the more open one (square panels)."""

TIE = 0.1
"""``E`` grows by ``TIE · max(0, −(d1·g1)(d1·g2))`` where the family-1 direction leaves the acute angle between the
guides: of two pairs mirror images of each other with (nearly) equal ``E`` (a saddle whose guides are its
asymptotic directions: the pairs ``(θ, π − θ)`` and ``(π − θ, θ)``, whose ``E`` the fit's noise sets apart by up
to 1e-2) the same one is taken everywhere, so the two families do not trade places from point to point.  The
term is continuous in ``d1``: it moves a pair near a guide by about ``TIE / 2`` rad, and never makes it jump."""

MIN_PAIR_ANGLE_DEG = 15.0
"""A conjugate pair closer than this (plan angle) refuses the net: its quads would be slivers."""

MIN_GUIDE_ANGLE_DEG = 15.0
"""The two guides must be at least this far apart in plan."""

BALANCED = 0.25
"""Edges within ``±BALANCED`` of the spacing need no re-seeding (:func:`~.traced.traced_net`)."""


def _pair_cost(second: np.ndarray, theta: np.ndarray, g1: np.ndarray, g2: np.ndarray,
               weights: tuple[float, float] = (1.0, 1.0)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``E`` of the conjugate pairs at points ``second (k, 2, 2)`` for angles ``theta (k, s)`` and guides ``g1``,
    ``g2`` (``(2,)`` or per point ``(k, 2)``) with the weights of their terms (a family the designer leaves
    free: 0): cost ``(k, s)``, ``d1`` and ``d2`` ``(k, s, 2)``.

    ``theta`` in ``[0, π)`` stands for family 1 along ``u(θ)`` (family 2 its conjugate), ``θ + π`` in
    ``[π, 2π)`` for family 2 along ``u(θ)`` (family 1 its conjugate): the second half reaches the pairs whose
    family 1 is a ruling (every direction conjugate to it), which the first cannot.  A ``u`` with ``II u``
    nearly 0 has no defined conjugate: cost ``inf``."""
    second_half = theta >= np.pi
    u = np.stack([np.cos(theta), np.sin(theta)], axis=-1)
    iu = np.einsum("kij,ksj->ksi", second, u)
    w = np.stack([-iu[..., 1], iu[..., 0]], axis=-1)                    # J II u
    norm = np.linalg.norm(w, axis=-1)
    size = np.linalg.norm(second, axis=(1, 2))[:, None]
    ok = norm > RULING * size
    w = w / np.where(ok, norm, 1.0)[..., None]
    d1 = np.where(second_half[..., None], w, u)
    d2 = np.where(second_half[..., None], u, w)
    g1 = np.broadcast_to(g1, (len(second), 2))
    g2 = np.broadcast_to(g2, (len(second), 2))
    d1g1 = np.einsum("ksi,ki->ks", d1, g1)
    d1g2 = np.einsum("ksi,ki->ks", d1, g2)
    d2g2 = np.einsum("ksi,ki->ks", d2, g2)
    cost = weights[0] * (1.0 - d1g1 ** 2) + weights[1] * (1.0 - d2g2 ** 2) + OPEN * np.einsum("ksi,ksi->ks", d1, d2) ** 2 \
        + TIE * np.maximum(0.0, -d1g1 * d1g2)
    return np.where(ok, cost, np.inf), d1, d2


def conjugate_pair(first: np.ndarray, second: np.ndarray, g1: np.ndarray, g2: np.ndarray,
                   flat: float = FLAT, weights: tuple[float, float] = (1.0, 1.0),
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The conjugate pair nearest the guides at each point.

    Parameters
    ----------
    first, second : (k, 2, 2) the fundamental forms in plan coordinates (``first`` is not needed for
        conjugacy, which depends on ``II`` alone; it is taken for a uniform signature with
        :func:`~.curvature.principal`)
    g1, g2 : (2,) or (k, 2) unit plan guides of family 1 and family 2 (one for all points, or one per point)
    flat : a second form smaller than this (Frobenius, 1/mm) is flat: the guides are the pair there
    weights : of the two guide terms of ``E`` (``(1, 0)``: family 2 free, its guide only breaks ties)

    Returns
    -------
    d1, d2 : (k, 2) unit plan directions, ``d1ᵀ II d2 = 0``
    cost : (k,) ``E`` of the pair (0: the guides themselves are conjugate)
    """
    del first
    ii = np.asarray(second, dtype=float)
    k = len(ii)
    step = np.pi / SAMPLES
    theta = np.broadcast_to(np.arange(2 * SAMPLES) * step, (k, 2 * SAMPLES))
    cost, _, _ = _pair_cost(ii, theta, g1, g2, weights)
    centre = theta[np.arange(k), np.argmin(cost, axis=1)]
    half = np.floor(centre / np.pi) * np.pi                 # stay in the half (the parametrisation) found
    for _ in range(3):                                      # refine: finer sampling within one step either side
        fine = centre[:, None] + np.linspace(-step, step, 11)[None, :]
        fine = half[:, None] + np.mod(fine - half[:, None], np.pi)
        c, _, _ = _pair_cost(ii, fine, g1, g2, weights)
        centre = fine[np.arange(k), np.argmin(c, axis=1)]
        step /= 5.0
    c, a, b = _pair_cost(ii, centre[:, None], g1, g2, weights)
    d1, d2, e = a[:, 0], b[:, 0], c[:, 0]
    flat_pt = (np.linalg.norm(ii, axis=(1, 2)) < flat) | ~np.isfinite(e)
    if flat_pt.any():
        d1 = np.where(flat_pt[:, None], np.broadcast_to(g1, d1.shape), d1)
        d2 = np.where(flat_pt[:, None], np.broadcast_to(g2, d2.shape), d2)
        e = np.where(flat_pt, 0.0, e)
    return d1, d2, e


def plan_guides(frame: PlanFrame, guides: Sequence[Sequence[float]] | None) -> tuple[np.ndarray, np.ndarray]:
    """The two guides as unit plan directions of ``frame``: world vectors projected on its plan (default: the
    frame's ``x`` and ``y`` axes).

    Raises
    ------
    DesignError : a guide that is not three finite numbers, is within 10° of vertical, or two guides closer
        than :data:`MIN_GUIDE_ANGLE_DEG` in plan
    """
    if guides is None:
        return np.array([1.0, 0.0]), np.array([0.0, 1.0])
    out = []
    for g in guides:
        v = np.asarray(g, dtype=float)
        if v.shape != (3,) or not np.all(np.isfinite(v)) or not np.linalg.norm(v):
            raise DesignError("surface.guides", "each guide must be three finite numbers, not all zero, e.g. "
                                                "[[1, 0, 0], [0, 1, 0]]")
        local = frame.axes @ (v / np.linalg.norm(v))
        if np.hypot(local[0], local[1]) < np.sin(np.radians(10.0)):
            raise DesignError("surface.guides", f"{list(g)} is within 10° of vertical: a guide is a direction "
                                                "in plan, e.g. [1, 0, 0]")
        out.append(local[:2] / np.hypot(local[0], local[1]))
    g1, g2 = out
    angle = float(np.degrees(np.arccos(min(1.0, abs(float(g1 @ g2))))))
    if angle < MIN_GUIDE_ANGLE_DEG:
        raise DesignError("surface.guides", f"the two guides are {angle:.1f}° apart in plan (at least "
                                            f"{MIN_GUIDE_ANGLE_DEG:g}°): give two directions across each other")
    return g1, g2


GUIDE_REACH = 0.25
"""Between guide curves their directions are blended with weights ``1 / (d² + (GUIDE_REACH · spacing)²)`` (``d``
the plan distance to each curve): near a curve mostly its own direction, between two curves a mix that turns
gradually."""


def _curve_tangents(curve: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A plan polyline ``(m, 2)`` without repeated points: its segments' starts and ends ``(m − 1, 2)`` each, and the
    doubled-angle tangent ``(cos 2φ, sin 2φ)`` at each vertex ``(m, 2)`` (the mean of its segments' at an inner
    vertex), for tangents that turn continuously along the curve."""
    seg = np.diff(curve, axis=0)
    phi = np.arctan2(seg[:, 1], seg[:, 0])
    dbl = np.stack([np.cos(2 * phi), np.sin(2 * phi)], axis=1)
    at = np.concatenate([dbl[:1], 0.5 * (dbl[:-1] + dbl[1:]), dbl[-1:]])
    return at, dbl


def curve_guides(frame: PlanFrame, curves: Sequence[Sequence[Sequence[float]]], points: np.ndarray, spacing: float,
                 key: str = "surface.row_guides") -> np.ndarray:
    """Unit plan guide directions ``(N, 2)`` at plan ``points (N, 2)`` from guide curves: polylines of world points
    ``[x, y, z]`` (mm), projected on the plan of ``frame``.  The direction at a point is each curve's tangent at
    the curve's nearest point (turning linearly between the curve's vertices), blended over the curves as line
    directions (doubled angles) with weights ``1 / (d² + (GUIDE_REACH · spacing)²)``.

    Raises
    ------
    DesignError : a curve that is not a list of at least two points of three finite numbers, or whose points
        coincide in plan
    """
    plan: list[np.ndarray] = []
    for i, c in enumerate(curves):
        a = np.asarray(c, dtype=float)
        if a.ndim != 2 or a.shape[1] != 3 or len(a) < 2 or not np.all(np.isfinite(a)):
            raise DesignError(f"{key}[{i}]", "a guide curve is a list of at least two points [x, y, z] (mm), e.g. "
                                             "[[0, 0, 0], [5000, 1000, 0], [10000, 0, 0]]")
        q = frame.to_local(a)[:, :2]
        keep = np.r_[True, np.linalg.norm(np.diff(q, axis=0), axis=1) > 1e-6 * max(spacing, 1.0)]
        q = q[keep]
        if len(q) < 2:
            raise DesignError(f"{key}[{i}]", "its points coincide in plan: a guide curve runs across the roof "
                                             "in plan (a vertical line guides nothing)")
        plan.append(q)
    if not plan:
        raise DesignError(key, "give at least one guide curve, or leave the key out")
    pts = np.asarray(points, dtype=float)
    eps2 = (GUIDE_REACH * spacing) ** 2
    total = np.zeros((len(pts), 2))
    nearest = np.full(len(pts), np.inf)
    near_dir = np.zeros((len(pts), 2))
    for q in plan:
        at, _ = _curve_tangents(q)
        a, b = q[:-1], q[1:]
        ab = b - a
        best_d = np.full(len(pts), np.inf)
        best_dir = np.zeros((len(pts), 2))
        for lo in range(0, len(pts), 4096):                 # points in chunks: (chunk, segments) at a time
            p = pts[lo:lo + 4096]
            t = np.clip(np.einsum("psi,si->ps", p[:, None, :] - a[None], ab) / np.einsum("si,si->s", ab, ab), 0, 1)
            foot = a[None] + t[..., None] * ab[None]
            d = np.linalg.norm(p[:, None, :] - foot, axis=2)
            k = np.argmin(d, axis=1)
            rows = np.arange(len(p))
            tk = t[rows, k][:, None]
            best_d[lo:lo + 4096] = d[rows, k]
            best_dir[lo:lo + 4096] = (1.0 - tk) * at[k] + tk * at[k + 1]
        w = 1.0 / (best_d ** 2 + eps2)
        total += w[:, None] * best_dir
        closer = best_d < nearest
        nearest = np.where(closer, best_d, nearest)
        near_dir = np.where(closer[:, None], best_dir, near_dir)
    # opposite line directions can cancel between two crossing curves: there the nearest curve's direction
    weak = np.linalg.norm(total, axis=1) < 1e-9 * np.linalg.norm(total, axis=1).max(initial=1.0)
    total = np.where(weak[:, None], near_dir, total)
    half = 0.5 * np.arctan2(total[:, 1], total[:, 0])
    return np.stack([np.cos(half), np.sin(half)], axis=1)


def guide_field(frame: PlanFrame, points: np.ndarray, spacing: float,
                guides: Sequence[Sequence[float]] | None = None,
                row_guides: Sequence[Sequence[Sequence[float]]] | None = None,
                column_guides: Sequence[Sequence[Sequence[float]]] | None = None,
                inside: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, tuple[float, float]]:
    """The guides ``g1, g2`` ``(N, 2)`` at plan ``points (N, 2)`` and the weights of their terms in ``E``: a
    family's guide curves where given, else its guide direction (``guides``), else — the other family guided by
    curves — the family is free (weight 0: the conjugate of the guided family, as open as the surface allows; its
    guide, the plan direction across the other's, only breaks ties); with neither, the plan axes.

    Raises
    ------
    DesignError : bad guides or guide curves; row and column guides closer than :data:`MIN_GUIDE_ANGLE_DEG` in
        plan at a point (of ``inside (N,)`` where given: the surface's) — the place, mm
    """
    n = len(points)
    if row_guides is None and column_guides is None:
        g1, g2 = plan_guides(frame, guides)
        return np.broadcast_to(g1, (n, 2)).copy(), np.broadcast_to(g2, (n, 2)).copy(), (1.0, 1.0)
    fixed = plan_guides(frame, guides) if guides is not None else None
    turn = np.array([[0.0, -1.0], [1.0, 0.0]])
    rows = curve_guides(frame, row_guides, points, spacing, "surface.row_guides") if row_guides is not None else None
    cols = curve_guides(frame, column_guides, points, spacing, "surface.column_guides") \
        if column_guides is not None else None
    weights = (1.0 if rows is not None or fixed is not None else 0.0,
               1.0 if cols is not None or fixed is not None else 0.0)
    if rows is None:
        assert cols is not None
        rows = np.broadcast_to(fixed[0], (n, 2)).copy() if fixed is not None else cols @ turn
    if cols is None:
        cols = np.broadcast_to(fixed[1], (n, 2)).copy() if fixed is not None else rows @ turn.T
    g1, g2 = rows, cols
    angle = np.degrees(np.arccos(np.clip(np.abs(np.einsum("ki,ki->k", g1, g2)), 0.0, 1.0)))
    if inside is not None:
        angle = np.where(inside, angle, 90.0)
    if n and float(angle.min()) < MIN_GUIDE_ANGLE_DEG:
        k = int(np.argmin(angle))
        raise DesignError("surface.column_guides" if column_guides is not None else "surface.guides",
                          f"the row and column guides are {angle[k]:.1f}° apart in plan at (x, y) = "
                          f"{_world_xy(frame, points[k])} mm (at least {MIN_GUIDE_ANGLE_DEG:g}°): guide the "
                          f"columns across the rows")
    return g1, g2, weights


def _world_xy(frame: PlanFrame, p: np.ndarray) -> str:
    w = frame.to_world(np.array([p[0], p[1], 0.0]))
    return f"({w[0]:.0f}, {w[1]:.0f})"


def grid_pair(hf: HeightField, g1: np.ndarray, g2: np.ndarray, weights: tuple[float, float] = (1.0, 1.0),
              ) -> tuple[np.ndarray, np.ndarray]:
    """The conjugate pair nearest the guides (``(2,)``, or ``(N, 2)`` per node) at the nodes of the fit's plan
    grid: ``d1, d2`` ``(N, 2)``, in the order of :func:`~.sections.grid_inside`.  A second form below a thousandth of the surface's typical one (the
    90th percentile on the grid), or below :data:`~.sections.FLAT`, is flat: the guides are the pair there."""
    X, Y = np.meshgrid(hf.x, hf.y, indexing="ij")
    first, second = forms(hf, X.ravel(), Y.ravel())
    flat = max(1e-3 * float(np.percentile(np.linalg.norm(second, axis=(1, 2)), 90)), FLAT)
    d1, d2, _ = conjugate_pair(first, second, g1, g2, flat, weights)
    return d1, d2


def conjugate_field(hf: HeightField, d1: np.ndarray, d2: np.ndarray) -> DirectionField:
    """The pair of :func:`grid_pair` as a :data:`~.traced.DirectionField`: interpolated bilinearly between the
    grid's nodes (``spacing / 8`` apart) as doubled-angle vectors ``(cos 2φ, sin 2φ)`` (a line field: ``φ`` and
    ``φ + π`` are one line), so tracing a curve costs an interpolation per step rather than a search over
    angles."""
    from scipy.interpolate import RegularGridInterpolator

    shape = (len(hf.x), len(hf.y), 2)
    doubled = []
    for d in (d1, d2):
        phi = np.arctan2(d[:, 1], d[:, 0])
        doubled.append(np.stack([np.cos(2 * phi), np.sin(2 * phi)], axis=-1).reshape(shape))
    table = RegularGridInterpolator((hf.x, hf.y), np.concatenate(doubled, axis=-1), bounds_error=False,
                                    fill_value=None)

    def field(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        v = table(p)
        out = []
        for c, s in ((v[:, 0], v[:, 1]), (v[:, 2], v[:, 3])):
            phi = 0.5 * np.arctan2(s, c)
            out.append(np.stack([np.cos(phi), np.sin(phi)], axis=-1))
        return out[0], out[1]
    return field


def pair_survey(d1: np.ndarray, d2: np.ndarray, g1: np.ndarray, g2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per point of the pair ``d1, d2 (k, 2)``: the plan angle between its two directions ``(k,)`` and the
    larger angle of either from its guide ``(k,)``, degrees."""
    def line_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.degrees(np.arccos(np.clip(np.abs(np.einsum("ki,ki->k", a, b)), 0.0, 1.0)))
    pair = line_angle(d1, d2)
    off = np.maximum(line_angle(d1, np.broadcast_to(g1, d1.shape)), line_angle(d2, np.broadcast_to(g2, d2.shape)))
    return pair, off


def conjugate_net(hf: HeightField, frame: PlanFrame, loops: Sequence[np.ndarray], spacing: float,
                  min_face: float = 0.25, guides: Sequence[Sequence[float]] | None = None,
                  row_guides: Sequence[Sequence[Sequence[float]]] | None = None,
                  column_guides: Sequence[Sequence[Sequence[float]]] | None = None,
                  ) -> tuple[SectionsNet, np.ndarray, str, float]:
    """Build the conjugate net nearest the guides (directions, or guide curves: :func:`guide_field`), trimmed to
    the plan region.

    Returns
    -------
    net : rows along family 1 (nearest the first guide), columns along family 2 (``planar_family = "none"``)
    twist : (F,) float — per kept face (row-major), ``|II(a, b)| / (|a||b| max|κ|)``, about 0
    seeding : ``"uniform"`` or ``"strips"`` (:func:`~.traced.traced_net`)
    guide_deviation_deg : the largest plan angle of a direction of the pair from its guide inside the outline

    Raises
    ------
    DesignError : bad guides or guide curves (:func:`guide_field`)
    GeometryError : the pair closes to less than :data:`MIN_PAIR_ANGLE_DEG` inside the outline (the place in mm)
    """
    loops = [np.asarray(lp, dtype=float)[:, :2] for lp in loops]
    pts, ins = grid_inside(hf, loops, EDGE_MARGIN * spacing)
    g1, g2, weights = guide_field(frame, pts, spacing, guides, row_guides, column_guides, ins)
    d1, d2 = grid_pair(hf, g1, g2, weights)
    p = pts[ins]
    pair, off = pair_survey(d1[ins], d2[ins], g1[ins], g2[ins])
    if len(pair) and float(pair.min()) < MIN_PAIR_ANGLE_DEG:
        k = int(np.argmin(pair))
        w = frame.to_world(np.array([p[k, 0], p[k, 1], float(hf.f(p[k, 0], p[k, 1]))]))
        raise GeometryError(
            f"conjugate net: the conjugate pair nearest the guides closes to {pair[k]:.1f}° at (x, y) = "
            f"({w[0]:.0f}, {w[1]:.0f}) mm (a guide near an asymptotic direction of a saddle part); turn the "
            "guides ([surface] guides) or use net = 'sections'", element=f"({w[0]:.0f}, {w[1]:.0f})",
            value=float(pair[k]))
    net, twist, seeding = traced_net(hf, frame, loops, spacing, min_face, conjugate_field(hf, d1, d2),
                                     "conjugate", BALANCED)
    return net, twist, seeding, float(off.max()) if len(off) else 0.0
