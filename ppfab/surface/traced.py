"""Nets of two families of curves traced on a height field: the machinery of the ``principal`` and ``conjugate``
nets.

A :data:`DirectionField` gives at plan points two unit plan directions (family 1 and family 2: curvature
directions, or a conjugate pair).  Each curve is traced in plan with classical Runge–Kutta (unit plan steps of
``spacing / 12``, the direction's sign kept continuous: a line field has no orientation) until it leaves the box
of the fit; the curves of one family start on the middle curve of the other, spaced by ``spacing`` along its
arc length, and vertex ``(i, j)`` is the crossing of curve ``i`` of one family with curve ``j`` of the other.
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np

from ..errors import GeometryError
from .balance import strip_positions
from .curvature import quad_twist
from .families import region_box
from .heightfield import HeightField
from .plan import PlanFrame
from .sections import SUBSTEPS_PER_SPACING, SectionsNet, _arc_positions, trim_grid
from .trim import inside

DirectionField = Callable[[np.ndarray], "tuple[np.ndarray, np.ndarray]"]
"""``field(p)`` for plan points ``p (k, 2)``: the unit plan directions ``(d1, d2)``, each ``(k, 2)``, of the two
families there (a line field: the sign is free)."""

BALANCED = 0.25
"""Edges within ``±BALANCED`` of the spacing need no re-seeding."""


def _direction(field: DirectionField, p: np.ndarray, family: int, prev: np.ndarray) -> np.ndarray:
    """Unit plan direction of ``family`` at plan points ``p (k, 2)``, signed along ``prev (k, 2)``."""
    d1, d2 = field(p)
    d = d1 if family == 1 else d2
    s = np.sign(np.einsum("ij,ij->i", d, prev))
    return d * np.where(s == 0, 1.0, s)[:, None]


def trace(hf: HeightField, field: DirectionField, start: np.ndarray, family: int, h: float,
          length: float) -> np.ndarray:
    """The integral curves of ``family`` of ``field`` through plan points ``start (k, 2)``, both ways until they
    leave the fit's box (or after ``length`` mm of plan): ``(k, 2S + 1, 2)``, the start in the middle; points
    beyond the box are NaN."""
    p0 = np.asarray(start, dtype=float)
    d1, d2 = field(p0)
    d0 = d1 if family == 1 else d2
    steps = int(np.ceil(length / h))
    halves = []
    for sign in (1.0, -1.0):
        p, prev = p0.copy(), sign * d0
        out = [p.copy()]
        alive = np.ones(len(p), dtype=bool)
        for _ in range(steps):
            k1 = _direction(field, p, family, prev)
            k2 = _direction(field, p + 0.5 * h * k1, family, k1)
            k3 = _direction(field, p + 0.5 * h * k2, family, k2)
            k4 = _direction(field, p + h * k3, family, k3)
            step = (k1 + 2 * k2 + 2 * k3 + k4) / 6
            p = p + h * step
            prev = step
            alive &= hf.inside_box(p[:, 0], p[:, 1])
            q = p.copy()
            q[~alive] = np.nan
            out.append(q)
            if not alive.any():
                break
        halves.append(np.stack(out, axis=1))
    fwd, back = halves
    pad = abs(fwd.shape[1] - back.shape[1])
    filler = np.full((len(p0), pad, 2), np.nan)
    if fwd.shape[1] < back.shape[1]:
        fwd = np.concatenate([fwd, filler], axis=1)
    else:
        back = np.concatenate([back, filler], axis=1)
    return np.concatenate([back[:, :0:-1], fwd], axis=1)


def _crossings(a: np.ndarray, curves: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The first crossing of the plan polyline ``a (p, 2)`` with each of ``curves (C, q, 2)`` (NaN points
    break them): ``(C, 2)`` points and ``(C,)`` whether there is one."""
    C, q = curves.shape[0], curves.shape[1]
    out, found = np.zeros((C, 2)), np.zeros(C, dtype=bool)
    pa, qa = a[:-1], a[1:]
    ok_a = np.isfinite(pa).all(1) & np.isfinite(qa).all(1)
    pa, qa = pa[ok_a], qa[ok_a]
    pb, qb = curves[:, :-1].reshape(-1, 2), curves[:, 1:].reshape(-1, 2)
    owner = np.repeat(np.arange(C), q - 1)
    ok_b = np.isfinite(pb).all(1) & np.isfinite(qb).all(1)
    pb, qb, owner = pb[ok_b], qb[ok_b], owner[ok_b]
    if not len(pa) or not len(pb):
        return out, found
    # only segment pairs whose boxes overlap
    lo_a, hi_a = np.minimum(pa, qa), np.maximum(pa, qa)
    lo_b, hi_b = np.minimum(pb, qb), np.maximum(pb, qb)
    ia, ib = np.nonzero((lo_a[:, None, 0] <= hi_b[None, :, 0]) & (lo_b[None, :, 0] <= hi_a[:, None, 0]) &
                        (lo_a[:, None, 1] <= hi_b[None, :, 1]) & (lo_b[None, :, 1] <= hi_a[:, None, 1]))
    r, s = qa[ia] - pa[ia], qb[ib] - pb[ib]
    den = r[:, 0] * s[:, 1] - r[:, 1] * s[:, 0]
    w = pb[ib] - pa[ia]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[:, 0] * s[:, 1] - w[:, 1] * s[:, 0]) / den
        u = (w[:, 0] * r[:, 1] - w[:, 1] * r[:, 0]) / den
    hit = np.flatnonzero((t >= 0) & (t <= 1) & (u >= 0) & (u <= 1) & (den != 0))
    # the first crossing along ``a`` for each curve: hits sorted by the segment of ``a``, first per owner
    hit = hit[np.lexsort((t[hit], ia[hit]))]
    _, first = np.unique(owner[ib[hit]], return_index=True)
    k = hit[first]
    out[owner[ib[k]]] = pa[ia[k]] + t[k, None] * r[k]
    found[owner[ib[k]]] = True
    return out, found


def traced_net(hf: HeightField, frame: PlanFrame, loops: Sequence[np.ndarray], spacing: float, min_face: float,
               field: DirectionField, name: str, balanced: float = BALANCED) -> tuple[SectionsNet, np.ndarray, str]:
    """The net of the two families of integral curves of ``field``, trimmed to the plan region ``loops``.

    The curves of one family start on the middle curve of the other, ``spacing`` apart along its arc length;
    vertex ``(i, j)`` is the crossing of curve ``i`` of family 1 with curve ``j`` of family 2.  When an edge is
    off the spacing by more than ``balanced``, the seeds are chosen again strip by strip (:mod:`.balance`) on a
    net twice as dense, kept when it narrows the range without losing more than a fifth of the quads.

    Returns
    -------
    net : rows along family 1, columns along family 2 (``planar_family = "none"``, ``kind`` = ``name``)
    twist : (F,) float — per kept face (row-major), ``|II(a, b)| / (|a||b| max|κ|)`` in the fitted surface
    seeding : ``"uniform"`` (``spacing`` along the middle curves) or ``"strips"``
    """
    loops = [np.asarray(lp, dtype=float)[:, :2] for lp in loops]
    x_lo, x_hi, y_lo, y_hi = region_box(hf, loops)
    centre = np.array([[0.5 * (x_lo + x_hi), 0.5 * (y_lo + y_hi)]])
    h = spacing / SUBSTEPS_PER_SPACING
    length = float(np.hypot(hf.x[-1] - hf.x[0], hf.y[-1] - hf.y[0]))
    middles = []
    for fam in (2, 1):          # seeds of family 1 lie on the middle curve of family 2, and vice versa
        mid = trace(hf, field, centre, fam, h, length)[0]
        ok = np.isfinite(mid).all(axis=1)
        centre_t = float(np.count_nonzero(ok[:len(ok) // 2]))      # the start is the middle point
        mid = mid[ok]
        t = np.arange(len(mid), dtype=float)
        middles.append((t, mid, np.column_stack([mid, hf.f(mid[:, 0], mid[:, 1])]), centre_t))

    def seeds_at(k: int, step: float) -> tuple[np.ndarray, np.ndarray]:
        """Parameters on middle curve ``k`` ``step`` apart in arc length, and the plan points there."""
        t, mid, pts, centre_t = middles[k]
        at = _arc_positions(t, pts, centre_t, step)
        return at, np.stack([np.interp(at, t, mid[:, 0]), np.interp(at, t, mid[:, 1])], axis=1)

    def build(rows_seeds: np.ndarray, cols_seeds: np.ndarray) -> tuple[SectionsNet, np.ndarray]:
        if len(rows_seeds) < 2 or len(cols_seeds) < 2:
            raise GeometryError(f"the surface is smaller than two panels of spacing {spacing:g} mm in one "
                                "direction; give a smaller [surface] spacing", value=spacing)
        local, valid, _ = _grid(hf, field, rows_seeds, cols_seeds, h, length)
        world = frame.to_world(local)
        return trim_grid(world, local, valid, None, loops, spacing, min_face, None, "none", name), local

    net, local = build(seeds_at(0, spacing)[1], seeds_at(1, spacing)[1])
    seeding = "uniform"
    if _worst(net, spacing) > np.log(1.0 / (1.0 - balanced)):
        # seeds chosen strip by strip on a net twice as dense (:mod:`.balance`), kept when it narrows the range
        (ta, sa), (tb, sb) = seeds_at(0, spacing / 2), seeds_at(1, spacing / 2)
        d_local, d_valid, flip = _grid(hf, field, sa, sb, h, length)
        d_world = frame.to_world(d_local)
        ins = d_valid.copy()
        if loops:
            ins &= inside(d_local[..., :2].reshape(-1, 2), loops).reshape(ins.shape)
        along_cols = np.linalg.norm(np.diff(d_world, axis=0), axis=-1)          # between neighbouring rows
        along_rows = np.linalg.norm(np.diff(d_world, axis=1), axis=-1).T
        pos_r = strip_positions(along_cols, ins[1:] & ins[:-1], float(np.interp(middles[0][3], ta, np.arange(len(ta)))),
                                spacing)
        ib = np.arange(len(tb))
        start_c = float(np.interp(middles[1][3], tb, ib))
        ins_c = (ins[:, 1:] & ins[:, :-1]).T
        if flip:                                   # _grid turned the columns round: back to the seeds' order
            along_rows, ins_c, start_c = along_rows[::-1], ins_c[::-1], float(len(tb) - 1 - start_c)
        pos_c = strip_positions(along_rows, ins_c, start_c, spacing)
        if flip:
            pos_c = len(tb) - 1 - pos_c[::-1]
        new_a = np.interp(pos_r, np.arange(len(ta)), ta)
        new_b = np.interp(pos_c, ib, tb)
        (t0, m0, _, _), (t1, m1, _, _) = middles
        other, o_local = build(np.stack([np.interp(new_a, t0, m0[:, 0]), np.interp(new_a, t0, m0[:, 1])], axis=1),
                               np.stack([np.interp(new_b, t1, m1[:, 0]), np.interp(new_b, t1, m1[:, 1])], axis=1))
        if _worst(other, spacing) < _worst(net, spacing) and other.grid_faces.sum() >= 0.8 * net.grid_faces.sum():
            net, local, seeding = other, o_local, "strips"
    kept = np.argwhere(net.grid_faces)
    fi, fj = kept[:, 0], kept[:, 1]
    corners = np.stack([local[fi, fj], local[fi + 1, fj], local[fi + 1, fj + 1], local[fi, fj + 1]], axis=1)
    return net, quad_twist(hf, corners), seeding


def _grid(hf: HeightField, field: DirectionField, rows_seeds: np.ndarray, cols_seeds: np.ndarray, h: float,
          length: float) -> tuple[np.ndarray, np.ndarray, bool]:
    """The crossings of the family-1 curves through ``rows_seeds (R, 2)`` with the family-2 curves through
    ``cols_seeds (C, 2)``: plan-frame points ``(R, C, 3)`` on the surface and whether each exists, the columns
    in the order that turns the faces counter-clockwise seen from above (as the sections net's), and whether
    that reversed them."""
    rows = trace(hf, field, rows_seeds, 1, h, length)
    cols = trace(hf, field, cols_seeds, 2, h, length)
    P = np.zeros((len(rows), len(cols), 2))
    valid = np.zeros((len(rows), len(cols)), dtype=bool)
    for i in range(len(rows)):
        P[i], valid[i] = _crossings(rows[i], cols)
    local = np.concatenate([P, hf.f(P[..., 0], P[..., 1])[..., None]], axis=-1)
    flip = _turns_clockwise(P, valid)
    if flip:
        local, valid = local[:, ::-1], valid[:, ::-1]
    return np.ascontiguousarray(local), np.ascontiguousarray(valid), flip


def _turns_clockwise(P: np.ndarray, valid: np.ndarray) -> bool:
    """Whether the first complete face of the plan grid ``P (R, C, 2)`` turns clockwise."""
    if P.shape[0] < 2 or P.shape[1] < 2:
        return False
    i0, j0 = np.unravel_index(int(np.argmax(valid[:-1, :-1] & valid[1:, :-1] & valid[:-1, 1:])),
                              (P.shape[0] - 1, P.shape[1] - 1))
    e1, e2 = P[i0 + 1, j0] - P[i0, j0], P[i0, j0 + 1] - P[i0, j0]
    return bool(e1[0] * e2[1] - e1[1] * e2[0] < 0)


def _worst(net: SectionsNet, spacing: float) -> float:
    """The largest ``|log(edge / spacing)|`` over the kept edges."""
    e = np.concatenate([net.edge_lengths_rows.ravel(), net.edge_lengths_cols.ravel()]) / spacing
    return float(np.abs(np.log(e)).max())
