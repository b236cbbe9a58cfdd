"""The ``principal`` net: curvature lines of the height field, two families intersected into a quad net.

The principal directions solve ``II v = κ I v`` (:mod:`.curvature`); family 1 follows the larger
curvature ``κ1``, family 2 the smaller.  Each curve is traced in plan with classical Runge–Kutta (unit plan
steps of ``spacing / 12``, the direction's sign kept continuous) until it leaves the box of the fit.  The
curves of one family start on the middle curve of the other, spaced by ``spacing`` along its arc length;
vertex ``(i, j)`` is the crossing of curve ``i`` of one family with curve ``j`` of the other.  A principal
net is conjugate and orthogonal: its quads are nearly planar and nearly rectangular before optimisation.

At an umbilic (``κ1 = κ2``: the top of a dome of revolution, a flat part) the directions are undefined and
the curves turn around it: :func:`umbilics` finds them on the fit's grid, and :func:`principal_net`
refuses when one lies inside the outline, with its place in mm.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from scipy.spatial import cKDTree

from ..errors import GeometryError
from .curvature import forms, principal, quad_twist
from .heightfield import HeightField
from .plan import PlanFrame
from .sections import EDGE_MARGIN, FLAT, SUBSTEPS_PER_SPACING, SectionsNet, _arc_positions, _densify, region_box, \
    trim_grid
from .trim import inside

UMBILIC = 0.1
"""``|κ1 − κ2|`` below this fraction of the surface's typical ``max |κ|`` counts as umbilic."""


MAX_UMBILICS = 8
"""At most this many umbilics are located and reported."""


def umbilics(hf: HeightField, frame: PlanFrame, loops: Sequence[np.ndarray], margin: float) -> np.ndarray:
    """Umbilics: local minima of ``|κ1 − κ2|`` on the fit's plan grid below :data:`UMBILIC` of the 90th
    percentile of ``max(|κ1|, |κ2|)``, inside the outline and ``margin`` mm or more from it.

    Returns
    -------
    (U, 3) float — world points (mm), the most pronounced first; the whole region when the surface is flat
    """
    gx, gy = hf.x, hf.y
    X, Y = np.meshgrid(gx, gy, indexing="ij")
    k1, k2, _, _ = principal(*forms(hf, X, Y))
    gap = k1 - k2
    kmax = np.maximum(np.abs(k1), np.abs(k2))
    pts = np.stack([X.ravel(), Y.ravel()], axis=1)
    ins = inside(pts, loops).reshape(X.shape) if len(loops) else np.ones(X.shape, dtype=bool)
    if len(loops) and margin > 0:
        edge = np.concatenate([_densify(lp, margin / 4) for lp in loops])
        ins &= (cKDTree(edge).query(pts)[0] >= margin).reshape(X.shape)
    if not ins.any():
        return np.zeros((0, 3))
    scale = float(np.percentile(kmax[ins], 90))
    if scale < FLAT:
        k = np.argwhere(ins)[len(np.argwhere(ins)) // 2]
        loc = np.array([X[k[0], k[1]], Y[k[0], k[1]], float(hf.f(X[k[0], k[1]], Y[k[0], k[1]]))])
        return frame.to_world(loc)[None]
    # local minima over the 3 × 3 neighbourhood
    pad = np.pad(gap, 1, constant_values=np.inf)
    nb = np.stack([pad[1 + di:1 + di + gap.shape[0], 1 + dj:1 + dj + gap.shape[1]]
                   for di in (-1, 0, 1) for dj in (-1, 0, 1) if di or dj])
    low = ins & (gap <= nb.min(axis=0)) & (gap < UMBILIC * scale)
    idx = np.argwhere(low)
    idx = idx[np.argsort(gap[low])]
    cell = float(max(gx[1] - gx[0], gy[1] - gy[0]))
    found: list[np.ndarray] = []
    for i, j in idx:
        start = np.array([X[i, j], Y[i, j]])
        if any(np.hypot(*(start - q)) <= 4 * cell for q in found):     # half a spacing apart
            continue
        p = _refine(hf, start, cell)
        if all(np.hypot(*(p - q)) > 4 * cell for q in found):
            found.append(p)
        if len(found) >= MAX_UMBILICS:
            break
    if not found:
        return np.zeros((0, 3))
    xy = np.array(found)
    return frame.to_world(np.column_stack([xy, hf.f(xy[:, 0], xy[:, 1])]))


def _refine(hf: HeightField, p: np.ndarray, cell: float) -> np.ndarray:
    """The minimum of ``(κ1 − κ2)²`` near a grid point (Nelder–Mead within two cells of it)."""
    from scipy.optimize import minimize

    def gap2(q: np.ndarray) -> float:
        k1, k2, _, _ = principal(*forms(hf, np.array([q[0]]), np.array([q[1]])))
        return float((k1[0] - k2[0]) ** 2)

    res = minimize(gap2, p, method="Nelder-Mead",
                   options={"initial_simplex": [p, p + [cell, 0.0], p + [0.0, cell]], "xatol": 1.0,
                            "fatol": 0.0, "maxiter": 200})
    q = np.asarray(res.x, dtype=float)
    return q if np.hypot(*(q - p)) <= 2 * cell else p


def _direction(hf: HeightField, p: np.ndarray, family: int, prev: np.ndarray) -> np.ndarray:
    """Unit plan direction of ``family`` at plan points ``p (k, 2)``, signed along ``prev (k, 2)``."""
    _, _, d1, d2 = principal(*forms(hf, p[:, 0], p[:, 1]))
    d = d1 if family == 1 else d2
    s = np.sign(np.einsum("ij,ij->i", d, prev))
    return d * np.where(s == 0, 1.0, s)[:, None]


def trace(hf: HeightField, start: np.ndarray, family: int, h: float, length: float) -> np.ndarray:
    """The curvature lines of ``family`` through plan points ``start (k, 2)``, both ways until they leave the
    fit's box (or after ``length`` mm of plan): ``(k, 2S + 1, 2)``, the start in the middle; points beyond
    the box are NaN."""
    p0 = np.asarray(start, dtype=float)
    _, _, d1, d2 = principal(*forms(hf, p0[:, 0], p0[:, 1]))
    d0 = d1 if family == 1 else d2
    steps = int(np.ceil(length / h))
    halves = []
    for sign in (1.0, -1.0):
        p, prev = p0.copy(), sign * d0
        out = [p.copy()]
        alive = np.ones(len(p), dtype=bool)
        for _ in range(steps):
            k1 = _direction(hf, p, family, prev)
            k2 = _direction(hf, p + 0.5 * h * k1, family, k1)
            k3 = _direction(hf, p + 0.5 * h * k2, family, k2)
            k4 = _direction(hf, p + h * k3, family, k3)
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


def _crossing(a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """The first crossing of plan polylines ``a (p, 2)`` and ``b (q, 2)`` (NaN points break them), or None."""
    pa, qa = a[:-1], a[1:]
    pb, qb = b[:-1], b[1:]
    ok_a = np.isfinite(pa).all(1) & np.isfinite(qa).all(1)
    ok_b = np.isfinite(pb).all(1) & np.isfinite(qb).all(1)
    pa, qa, pb, qb = pa[ok_a], qa[ok_a], pb[ok_b], qb[ok_b]
    if not len(pa) or not len(pb):
        return None
    r, s = qa - pa, qb - pb
    den = r[:, None, 0] * s[None, :, 1] - r[:, None, 1] * s[None, :, 0]
    w = pb[None, :, :] - pa[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[..., 0] * s[None, :, 1] - w[..., 1] * s[None, :, 0]) / den
        u = (w[..., 0] * r[:, None, 1] - w[..., 1] * r[:, None, 0]) / den
    hit = np.argwhere((t >= 0) & (t <= 1) & (u >= 0) & (u <= 1) & (den != 0))
    if not len(hit):
        return None
    i, j = hit[0]
    out: np.ndarray = pa[i] + t[i, j] * r[i]
    return out


def principal_net(hf: HeightField, frame: PlanFrame, loops: Sequence[np.ndarray], spacing: float,
                  min_face: float = 0.25) -> tuple[SectionsNet, np.ndarray, np.ndarray]:
    """Build the principal net, trimmed to the plan region.

    Returns
    -------
    net : rows along curvature lines of family 1, columns of family 2 (``planar_family = "none"``)
    twist : (F,) float — per kept face (row-major), ``|II(a, b)| / (|a||b| max|κ|)``, about 0
    found : (U, 3) float — umbilics inside the region nearer than ``EDGE_MARGIN × spacing`` to its edge
        (empty: none; farther inside the net is refused)

    Raises
    ------
    GeometryError : an umbilic (or a flat surface) inside the outline, with its place in mm
    """
    loops = [np.asarray(lp, dtype=float)[:, :2] for lp in loops]
    inner = umbilics(hf, frame, loops, EDGE_MARGIN * spacing)
    if len(inner):
        w = inner[0]
        raise GeometryError(
            f"principal net: an umbilic (equal principal curvatures: the curvature lines turn around it) at "
            f"(x, y) = ({w[0]:.0f}, {w[1]:.0f}) mm inside the outline{' and ' + str(len(inner) - 1) + ' more' if len(inner) > 1 else ''}; "
            "use net = 'sections' or 'pp', or trim the surface away from it", element=f"({w[0]:.0f}, {w[1]:.0f})")
    found = umbilics(hf, frame, loops, 0.0)
    x_lo, x_hi, y_lo, y_hi = region_box(hf, loops)
    centre = np.array([[0.5 * (x_lo + x_hi), 0.5 * (y_lo + y_hi)]])
    h = spacing / SUBSTEPS_PER_SPACING
    length = float(np.hypot(hf.x[-1] - hf.x[0], hf.y[-1] - hf.y[0]))
    seeds = []
    for fam in (2, 1):          # seeds of family 1 lie on the middle curve of family 2, and vice versa
        mid = trace(hf, centre, fam, h, length)[0]
        ok = np.isfinite(mid).all(axis=1)
        centre_t = float(np.count_nonzero(ok[:len(ok) // 2]))      # the start is the middle point
        mid = mid[ok]
        t = np.arange(len(mid), dtype=float)
        pts = np.column_stack([mid, hf.f(mid[:, 0], mid[:, 1])])
        at = _arc_positions(t, pts, centre_t, spacing)
        seeds.append(np.stack([np.interp(at, t, mid[:, 0]), np.interp(at, t, mid[:, 1])], axis=1))
    if len(seeds[0]) < 2 or len(seeds[1]) < 2:
        raise GeometryError(f"the surface is smaller than two panels of spacing {spacing:g} mm in one "
                            "direction; give a smaller [surface] spacing", value=spacing)
    rows = trace(hf, seeds[0], 1, h, length)
    cols = trace(hf, seeds[1], 2, h, length)
    P = np.zeros((len(rows), len(cols), 2))
    valid = np.zeros((len(rows), len(cols)), dtype=bool)
    for i in range(len(rows)):
        for j in range(len(cols)):
            x = _crossing(rows[i], cols[j])
            if x is not None:
                P[i, j], valid[i, j] = x, True
    local = np.concatenate([P, hf.f(P[..., 0], P[..., 1])[..., None]], axis=-1)
    # faces turn counter-clockwise seen from above (as the sections net's)
    i0, j0 = np.unravel_index(int(np.argmax(valid[:-1, :-1] & valid[1:, :-1] & valid[:-1, 1:])),
                              (len(rows) - 1, len(cols) - 1))
    e1, e2 = P[i0 + 1, j0] - P[i0, j0], P[i0, j0 + 1] - P[i0, j0]
    if e1[0] * e2[1] - e1[1] * e2[0] < 0:
        local, valid = local[:, ::-1], valid[:, ::-1]
    local = np.ascontiguousarray(local)
    world = frame.to_world(local)
    net = trim_grid(world, local, valid, None, loops, spacing, min_face, None, "none", "principal")
    kept = np.argwhere(net.grid_faces)
    fi, fj = kept[:, 0], kept[:, 1]
    corners = np.stack([local[fi, fj], local[fi + 1, fj], local[fi + 1, fj + 1], local[fi, fj + 1]], axis=1)
    return net, quad_twist(hf, corners), found
