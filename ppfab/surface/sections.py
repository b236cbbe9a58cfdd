"""The ``sections`` net: planar sections by parallel planes (or a pencil of planes, :mod:`.families`) and their
conjugate curves.

On a height field ``z = f(x, y)`` (the plan frame of :mod:`.plan`: sections are ``x = const``) a section has
the tangent ``∂y``; the direction ``w = (a, b)`` conjugate to it satisfies ``II(∂y, w) = f_xy·a + f_yy·b = 0``,
so the conjugate curves solve ``dy/dx = −f_xy / f_yy``.  They are integrated (classical Runge–Kutta, all
curves at once) from seeds spaced by ``spacing`` along the arc length of the middle section, and the
vertices are their crossings with the planes ``x = x_i``, spaced by ``spacing`` along the arc length of the
middle conjugate curve.  Row ``i`` of the grid therefore lies in its plane by construction (its vertices
have the same ``x``), before any optimisation.

Where the conjugate direction comes close to the section direction (``|f_xy| ≫ |f_yy|``: near a parabolic
line along the sections, where ``f_yy`` changes sign) the net degenerates: :func:`sections_net` refuses with
the location.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..errors import GeometryError
from ..mesh import QuadGrid, QuadMesh
from .heightfield import HeightField
from .families import ParallelPlanes, PlaneFamily, densify_loop
from .plan import PlanFrame
from .trim import faces_inside, inside

MAX_ANGLE_DEG = 75.0
"""The conjugate direction may turn at most this far from the plane normal ``x`` (towards the sections)."""

FLAT = 1e-10
"""Second derivatives (1/mm) below this are numerical noise: a radius of curvature of 10 000 km is flat."""

EDGE_MARGIN = 0.5
"""The degeneracy is looked for this many ``spacing`` or more inside the outline."""

SUBSTEPS_PER_SPACING = 12
"""Runge–Kutta steps per ``spacing`` of ``x``."""

BALANCE_DENSITY = 8
"""Curves and planes per ``spacing`` of the dense net the balanced seeds are chosen on."""


@dataclass(frozen=True)
class SectionsNet:
    """The net as built, trimmed, in world coordinates (mm).

    mesh : :class:`QuadGrid` when the kept faces form a rectangle of the grid, else :class:`QuadMesh`
    planar_family : the families whose polylines lie in planes before optimisation: ``"rows"`` (sections),
        ``"both"`` (pp), ``"none"`` (principal)
    planes : (R, 4) unit section planes ``n·p + d = 0`` of the rows of the full grid (None: rows not planar)
    planes_cols : (C, 4) planes of the columns of the full grid, when they are planar (pp)
    col_of_vertex : (N,) int — the column of the full grid each vertex of ``mesh`` lies in
    row_of_vertex : (N,) int — the section (index into ``planes``) each vertex of ``mesh`` lies in
    grid_faces : (m, n) bool — the faces of the full grid that were kept
    faces_total, dropped_outside, dropped_sliver, dropped_island : faces of the full grid; removed because
        they are not wholly inside the trim region, smaller than ``min_face`` of a square panel, or cut off
        from the largest connected part
    edge_lengths_rows, edge_lengths_cols : (F, 2) — per kept face (row-major order of ``grid_faces``) the
        lengths of its two edges along the rows (sections) and its two along the columns (conjugate curves), mm
    """

    mesh: QuadGrid | QuadMesh
    planes: np.ndarray | None
    row_of_vertex: np.ndarray
    grid_faces: np.ndarray
    faces_total: int
    dropped_outside: int
    dropped_sliver: int
    dropped_island: int
    edge_lengths_rows: np.ndarray
    edge_lengths_cols: np.ndarray
    planar_family: str = "rows"
    notes: tuple[str, ...] = field(default_factory=tuple)
    col_of_vertex: np.ndarray | None = None
    planes_cols: np.ndarray | None = None


def grid_inside(hf: HeightField, loops: Sequence[np.ndarray], margin: float) -> tuple[np.ndarray, np.ndarray]:
    """The nodes of the fit's plan grid, ``(N, 2)`` in row-major order of ``(hf.x, hf.y)``, and ``(N,)`` whether
    each lies inside the region ``loops`` and ``margin`` mm or more from its boundary (the fit is least sure at
    its edge); every node without loops."""
    X, Y = np.meshgrid(hf.x, hf.y, indexing="ij")
    pts = np.stack([X.ravel(), Y.ravel()], axis=1)
    ins = inside(pts, loops) if len(loops) else np.ones(len(pts), dtype=bool)
    if len(loops) and margin > 0:
        edge = np.concatenate([densify_loop(lp, margin / 4) for lp in loops])
        ins &= cKDTree(edge).query(pts)[0] >= margin
    return pts, ins


def _check_degenerate(hf: HeightField, frame: PlanFrame, loops: Sequence[np.ndarray], limit: float,
                      margin: float, fam: PlaneFamily | None = None) -> float:
    """Refuse when the conjugate direction comes within ``90° − MAX_ANGLE_DEG`` of the sections inside the
    region, ``margin`` mm or more from its boundary (the fit is least sure at its edge); return the curvature
    floor used to regularise the slope."""
    fam = fam if fam is not None else ParallelPlanes(frame)
    pts, ins = grid_inside(hf, loops, margin)
    p = pts[ins]
    fxx, fxy, fyy = hf.fxx(p[:, 0], p[:, 1]), hf.fxy(p[:, 0], p[:, 1]), hf.fyy(p[:, 0], p[:, 1])
    scale = float(np.max(np.abs(np.concatenate([fxx, fxy, fyy])))) if len(p) else 0.0
    floor = max(1e-3 * scale, FLAT)
    fyy, fxy = fam.second(hf, p[:, 0], p[:, 1])          # along the section, and mixed
    ratio = np.abs(fxy) / (np.abs(fyy) + floor)
    if len(p) and float(ratio.max()) > limit:
        k = int(np.argmax(ratio))
        w = frame.to_world(np.array([p[k, 0], p[k, 1], float(hf.f(p[k, 0], p[k, 1]))]))
        signs = " (f_yy changes sign: a parabolic line along the sections)" if \
            (fyy > floor).any() and (fyy < -floor).any() else ""
        raise GeometryError(
            f"sections net: the conjugate direction of the sections degenerates at (x, y) = ({w[0]:.0f}, "
            f"{w[1]:.0f}) mm{signs}; rotate the section planes ([surface] plane_normal) or choose another net",
            element=f"({w[0]:.0f}, {w[1]:.0f})", value=float(ratio.max()))
    return floor


def _rk4(hf: HeightField, fam: PlaneFamily, s0: float, t0: np.ndarray, s1: float, h: float, floor: float,
         limit: float) -> np.ndarray:
    """Integrate ``dt/ds`` of the curves conjugate to the sections from ``s0`` to ``s1`` for all ``t0`` at once."""
    n = max(1, int(np.ceil(abs(s1 - s0) / h)))
    ds = (s1 - s0) / n
    t = np.array(t0, dtype=float)
    s = s0
    for _ in range(n):
        k1 = fam.slope(hf, np.full_like(t, s), t, floor, limit)
        k2 = fam.slope(hf, np.full_like(t, s + ds / 2), t + ds / 2 * k1, floor, limit)
        k3 = fam.slope(hf, np.full_like(t, s + ds / 2), t + ds / 2 * k2, floor, limit)
        k4 = fam.slope(hf, np.full_like(t, s + ds), t + ds * k3, floor, limit)
        t = t + ds / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        s = s + ds
    return t


def _arc_positions(t: np.ndarray, pts: np.ndarray, centre: float, spacing: float) -> np.ndarray:
    """Parameters ``t`` (sorted) where the arc length of the polyline ``pts`` measured from ``t = centre`` is a
    multiple of ``spacing``, within the range of ``t``."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    s0 = float(np.interp(centre, t, s))
    k = np.arange(np.ceil((s[0] - s0) / spacing - 1e-9), np.floor((s[-1] - s0) / spacing + 1e-9) + 1)
    return np.interp(s0 + k * spacing, s, t)


def sections_net(hf: HeightField, frame: PlanFrame, loops: Sequence[np.ndarray], spacing: float,
                 min_face: float = 0.25, steps: tuple[float, float] = (1.0, 1.0),
                 balance: bool = False, family: PlaneFamily | None = None) -> SectionsNet:
    """Build the sections net of a height field, trimmed to the plan region.

    Parameters
    ----------
    hf : the surface as a height field in ``frame``
    frame : the plan frame (parallel sections are ``x = const``)
    loops : the trim region's loops in plan ``(k, 2)`` (frame coordinates); empty: the box of the fit
    spacing : target panel size, mm (along both families' arc length)
    min_face : faces smaller than this fraction of ``spacing²`` are dropped as slivers
    steps : the seed step along the middle section and the plane step along the middle conjugate curve, as
        fractions of ``spacing`` (:func:`ppfab.surface.remesh.remesh` balances them so that the edges that
        grow and shrink away from the middle straddle ``spacing``)
    balance : place every seed and plane so that the panels of its own strip straddle ``spacing``
        (:mod:`.balance`), instead of a uniform step along the middle lines
    family : the section planes (:mod:`.families`): parallel planes ``x = const`` of ``frame`` (the default) or
        a pencil through a vertical axis
    """
    fam = family if family is not None else ParallelPlanes(frame)
    limit = float(np.tan(np.radians(MAX_ANGLE_DEG)))
    loops = [np.asarray(lp, dtype=float)[:, :2] for lp in loops]
    floor = _check_degenerate(hf, frame, loops, limit, EDGE_MARGIN * spacing, fam)
    box = fam.box(hf, loops)
    s_lo, s_hi, t_lo, t_hi = box
    sc, tc = 0.5 * (s_lo + s_hi), 0.5 * (t_lo + t_hi)
    h = spacing / SUBSTEPS_PER_SPACING                       # integration step along t (mm)
    hs = fam.s_step(spacing, box) / SUBSTEPS_PER_SPACING     # … and along s
    lo_s, hi_s, lo_t, hi_t = fam.reach(hf, spacing, box)
    # seeds: along the middle section, spaced by arc length, over the region (and one spacing beyond)
    ts = np.linspace(lo_t, hi_t, max(50, int((hi_t - lo_t) / h) + 1))
    sec = _points(hf, fam, np.full_like(ts, sc), ts)
    # planes: along the middle conjugate curve, spaced by arc length, over the region (and one beyond)
    ss_r = np.linspace(sc, hi_s, max(2, int((hi_s - sc) / hs) + 1))
    ss_l = np.linspace(sc, lo_s, max(2, int((sc - lo_s) / hs) + 1))

    def trace(ss: np.ndarray) -> np.ndarray:
        out = [tc]
        for a, b in zip(ss[:-1], ss[1:]):
            out.append(float(_rk4(hf, fam, float(a), np.array([out[-1]]), float(b), hs, floor, limit)[0]))
        return np.array(out)

    ss = np.concatenate([ss_l[::-1], ss_r[1:]])
    tline = np.concatenate([trace(ss_l)[::-1], trace(ss_r)[1:]])
    curve = _points(hf, fam, ss, tline)
    if balance:
        # a dense net (eight curves and planes per panel) decides where the seeds and planes go
        from .balance import balanced_positions

        d_seeds = _arc_positions(ts, sec, tc, spacing * steps[0] / BALANCE_DENSITY)
        d_planes = _arc_positions(ss, curve, sc, spacing * steps[1] / BALANCE_DENSITY)
        if len(d_planes) < 2 or len(d_seeds) < 2:
            raise GeometryError(f"the surface is smaller than two panels of spacing {spacing:g} mm in one "
                                "direction; give a smaller [surface] spacing", value=spacing)
        dT = _march(hf, fam, d_seeds, d_planes, sc, hs, floor, limit)
        dense = _points(hf, fam, np.broadcast_to(d_planes[:, None], dT.shape), dT)
        ins = hf.inside_box(dense[..., 0], dense[..., 1])
        if loops:
            ins &= inside(dense[..., :2].reshape(-1, 2), loops).reshape(ins.shape)
        seeds, planes_s = balanced_positions(dense, ins, d_seeds, d_planes, tc, sc, spacing)
    else:
        seeds = _arc_positions(ts, sec, tc, spacing * steps[0])
        planes_s = _arc_positions(ss, curve, sc, spacing * steps[1])
    if len(planes_s) < 2 or len(seeds) < 2:
        raise GeometryError(f"the surface is smaller than two panels of spacing {spacing:g} mm in one "
                            "direction; give a smaller [surface] spacing", value=spacing)
    T = _march(hf, fam, seeds, planes_s, sc, hs, floor, limit)
    local = _points(hf, fam, np.broadcast_to(planes_s[:, None], T.shape), T)
    valid = hf.inside_box(local[..., 0], local[..., 1])
    world = frame.to_world(local)
    # rows lie in their planes exactly: every vertex of a row has its plane's s
    planes = np.stack([fam.plane(float(s)) for s in planes_s])
    return trim_grid(world, local, valid, planes, loops, spacing, min_face)


def _points(hf: HeightField, fam: PlaneFamily, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``(..., 3)`` plan-frame points of ``(s, t)`` on the height field."""
    x, y = fam.to_plan(s, t)
    return np.stack([x, y, hf.f(x, y)], axis=-1)


def _march(hf: HeightField, fam: PlaneFamily, seeds: np.ndarray, planes_s: np.ndarray, sc: float, h: float,
           floor: float, limit: float) -> np.ndarray:
    """``T (len(planes_s), len(seeds))``: the conjugate curves through ``(sc, seeds)`` at every plane, marching
    out from the middle."""
    T = np.empty((len(planes_s), len(seeds)))
    mid = min(int(np.searchsorted(planes_s, sc)), len(planes_s) - 1)
    t = _rk4(hf, fam, sc, seeds, float(planes_s[mid]), h, floor, limit)
    T[mid] = t
    for i in range(mid + 1, len(planes_s)):
        T[i] = t = _rk4(hf, fam, float(planes_s[i - 1]), t, float(planes_s[i]), h, floor, limit)
    t = T[mid]
    for i in range(mid - 1, -1, -1):
        T[i] = t = _rk4(hf, fam, float(planes_s[i + 1]), t, float(planes_s[i]), h, floor, limit)
    return T


def trim_grid(world: np.ndarray, local: np.ndarray, valid: np.ndarray, planes: np.ndarray | None,
              loops: Sequence[np.ndarray], spacing: float, min_face: float, planes_cols: np.ndarray | None = None,
              planar_family: str = "rows", what: str = "sections") -> SectionsNet:
    """Keep the faces of a full grid ``world (m+1, n+1, 3)`` inside the region, drop slivers and islands.

    local : the same points in the plan frame; valid : (m+1, n+1) bool, vertices that exist (in the fit's box,
    curves that cross); planes, planes_cols : the planes of the rows and columns, if they are planar
    """
    m, n = world.shape[0] - 1, world.shape[1] - 1
    ids = np.arange((m + 1) * (n + 1)).reshape(m + 1, n + 1)
    quads = np.stack([ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:], ids[:-1, 1:]], axis=-1).reshape(-1, 4)
    ok = valid.ravel()[quads].all(axis=1)
    plan = local[..., :2].reshape(-1, 2)[quads]
    if loops and ok.any():
        ok[ok] = faces_inside(plan[ok], loops)
    dropped_outside = int(quads.shape[0] - ok.sum())
    v = world.reshape(-1, 3)
    c = v[quads]
    area = 0.5 * np.linalg.norm(np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]), axis=1)
    sliver = ok & (area < min_face * spacing * spacing)
    ok &= ~sliver
    kept = np.flatnonzero(ok)
    island = 0
    if len(kept) > 1:
        # faces sharing an edge: neighbours in the grid
        fi, fj = np.divmod(kept, n)
        pos = {int(k): t for t, k in enumerate(kept)}
        a, b = [], []
        for t, (i, j) in enumerate(zip(fi.tolist(), fj.tolist())):
            for k2 in ((i + 1) * n + j if i + 1 < m else -1, i * n + j + 1 if j + 1 < n else -1):
                if k2 in pos:
                    a.append(t)
                    b.append(pos[k2])
        g = coo_matrix((np.ones(len(a)), (a, b)), shape=(len(kept), len(kept)))
        _, label = connected_components(g, directed=False)
        big = np.bincount(label).argmax()
        island = int(np.count_nonzero(label != big))
        ok[kept[label != big]] = False
    if not ok.any():
        raise GeometryError(f"no panel of the {what} net lies wholly inside the surface's outline; give a "
                            "smaller [surface] spacing")
    grid_faces = ok.reshape(m, n)
    rows_i = np.flatnonzero(grid_faces.any(axis=1))
    cols_j = np.flatnonzero(grid_faces.any(axis=0))
    i0, i1, j0, j1 = rows_i[0], rows_i[-1] + 1, cols_j[0], cols_j[-1] + 1
    row_index = np.broadcast_to(np.arange(m + 1)[:, None], (m + 1, n + 1)).ravel()
    col_index = np.broadcast_to(np.arange(n + 1)[None, :], (m + 1, n + 1)).ravel()
    mesh: QuadGrid | QuadMesh
    if grid_faces[i0:i1, j0:j1].all():
        block = world[i0:i1 + 1, j0:j1 + 1]
        mesh = QuadGrid(block, support_u=None if planes is None else planes[i0:i1 + 1],
                        support_w=None if planes_cols is None else planes_cols[j0:j1 + 1])
        row_of_vertex = np.repeat(np.arange(i0, i1 + 1), j1 - j0 + 1)
        col_of_vertex = np.tile(np.arange(j0, j1 + 1), i1 - i0 + 1)
    else:
        f = quads[ok]
        used = np.unique(f)
        remap = np.full(len(v), -1)
        remap[used] = np.arange(len(used))
        mesh = QuadMesh(v[used], remap[f])
        row_of_vertex = row_index[used]
        col_of_vertex = col_index[used]
    fk = quads[ok]
    # per kept face its two edges along the rows (v[i,j] → v[i,j+1], v[i+1,j] → v[i+1,j+1]) and its two
    # along the columns (v[i,j] → v[i+1,j], v[i,j+1] → v[i+1,j+1])
    er = np.linalg.norm(v[fk[:, [3, 2]]] - v[fk[:, [0, 1]]], axis=2)
    ec = np.linalg.norm(v[fk[:, [1, 2]]] - v[fk[:, [0, 3]]], axis=2)
    return SectionsNet(mesh, planes, row_of_vertex, grid_faces, int(m * n), dropped_outside,
                       int(sliver.sum()), island, er, ec, planar_family, col_of_vertex=col_of_vertex,
                       planes_cols=planes_cols)
