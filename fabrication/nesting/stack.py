"""Strip stacking: long thin parts dropped onto a skyline, each nestling into the one below.

Beam plates are strips (≈ 200 mm deep, up to the sheet's length) bent into gentle arcs: their
bounding boxes waste the sagitta, and in rows of boxes they nest badly.  Stacked one on top of
the next (both bent the same way, apexes aligned) two strips are only a spacing apart all along
their length, so a sheet holds ``(H − sagitta) / (depth + s)`` of them whatever their curvature.

The sheet is cut into ``n`` column cells of width ``q`` (``q ≈ L / 300``).  Per pose of a part
(:class:`Profiles`):

* ``lo[o, k]`` — the lowest point of the outline in cell ``k`` (``+inf`` where it has none),
* ``hi[o, k]`` — the highest point of its *halo* (outline offset by the spacing) in cell
  ``k − r``, ``r`` = the cells a halo reaches beyond its box (``−inf`` where none).

Both are exact extents of the polygons over each slab (attained at vertices inside the slab or
where edges cross its sides), hence conservative.  A sheet keeps a *skyline* ``sky[c]`` = the
highest halo point over cell ``c`` (0 on the empty sheet).  A pose dropped at ``X = j q`` from
above comes to rest at

    Y = max(0, max_k (sky[j + k] − lo[o, k])),

where every point of the outline lies above every halo below it, so the new part is at least
``s`` from all others (the halo contains the round offset).  It is then settled exactly
(:func:`~.shapes.slide_distance` against the halos): lowered to first contact — removing the
quantisation — pushed left to contact (two short strips end to end in one row) and lowered
again; the skyline rises to ``max(sky, Y + hi)`` (still an upper envelope of all halos when the
push tucks a part under an overhang).

Each step of :meth:`StackFiller.fill_sheet` drops every remaining part in every allowed pose
at a few positions — flush left, flush right, flush with either end of the piece placed last,
just beyond either end of it, and with the vertex of its bottom profile under the vertex of the
last piece's top profile (the concentric position) — and keeps the drop of least score: the area
between the skyline and the part's underside per unit of part area, less a bonus for large
parts, plus a penalty for a high top.  Drops are ranked first on every 4th cell (vectorised
over all candidates), then evaluated exactly in that order, 32 at a time.  Turning a strip by
180° or mirroring it is just another pose, so bent strips stack convex side into concave side.
The sheet is done when nothing fits under its top edge.

The search over sheets (:mod:`.search`) is the same ruin and recreate as for rows; this module
only supplies the sheet filler and its randomised knobs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .catalog import Catalog
from .budget import Work
from .rows import Piece, Sheet
from .shapes import slide_distance

CELLS = 300                     # column cells across the usable length (q = L / CELLS)
ELONGATION = 6.0                # a part whose narrowest box is this many times longer than deep is a strip
# work units (≈ 1 µs each on the reference machine): per candidate cell evaluated, per step, per exact slide
COST_CELL, COST_STEP, COST_SLIDE = 3.0 / 220.0, 121.0, 182.0
COST_PROFILE = 39.0             # per pose: column profiles and the filler's arrays
STRIDE, SHORTLIST = 4, 32      # short-listing: every 4th cell for all candidates, all cells for the best 32


def column_extents(polys: list[np.ndarray], q: float, x_from: np.ndarray,
                   n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest point of each polygon over its slabs ``[x_from + c q, x_from + (c+1) q]``.

    Parameters
    ----------
    polys : P polygons ``(k_i, 2)``; q : slab width; x_from : (P,) left side of slab 0 of each
    n : (P,) slabs per polygon

    Returns
    -------
    ymin, ymax : (P, max n) — ``+inf`` / ``−inf`` in slabs a polygon does not reach (and in padding).
        Exact: the extremes of a polygon over a slab lie at its vertices inside the slab or where
        its edges cross the slab's sides, and those are the points examined.
    """
    k = np.array([len(p) for p in polys])
    a = np.concatenate(polys).astype(float, copy=False)
    start = np.cumsum(k) - k
    nxt = np.arange(len(a)) + 1
    nxt[start + k - 1] = start                      # each polygon's last vertex joins its first
    b = a[nxt]
    pid = np.repeat(np.arange(len(polys)), k)
    x0 = np.asarray(x_from, dtype=float)[pid]
    nn = np.asarray(n, dtype=np.int64)
    N = int(nn.max())
    ymin = np.full(len(polys) * N, np.inf)
    ymax = np.full(len(polys) * N, -np.inf)

    def put(owner: np.ndarray, cell: np.ndarray, y: np.ndarray) -> None:
        ok = (cell >= 0) & (cell < nn[owner])
        flat = owner[ok] * N + cell[ok]
        np.minimum.at(ymin, flat, y[ok])
        np.maximum.at(ymax, flat, y[ok])

    # vertices: in the slab that contains them (on a slab side they are also a crossing, below)
    put(pid, np.floor((a[:, 0] - x0) / q).astype(np.int64), a[:, 1])
    # crossings of edges with the slab sides x = x_from + g q: in the slabs g − 1 and g
    xl, xh = np.minimum(a[:, 0], b[:, 0]), np.maximum(a[:, 0], b[:, 0])
    g0 = np.ceil((xl - x0) / q - 1e-12).astype(np.int64)
    g1 = np.floor((xh - x0) / q + 1e-12).astype(np.int64)
    cnt = np.where(xh > xl, np.maximum(g1 - g0 + 1, 0), 0)
    if cnt.sum():
        e = np.repeat(np.arange(len(a)), cnt)
        g = g0[e] + (np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt))
        x = x0[e] + g * q
        t = np.clip((x - a[e, 0]) / (b[e, 0] - a[e, 0]), 0.0, 1.0)
        y = a[e, 1] + t * (b[e, 1] - a[e, 1])
        put(pid[e], g - 1, y)
        put(pid[e], g, y)
    return ymin.reshape(len(polys), N), ymax.reshape(len(polys), N)


def _vertex(profile: np.ndarray) -> float:
    """Cell (fractional) of the vertex of the parabola fitted to the finite cells of ``profile``.

    The apex of a bent strip's edge; the middle of the profile when it is straight or the vertex
    falls outside it.
    """
    k = np.flatnonzero(np.isfinite(profile))
    mid = 0.5 * (k[0] + k[-1]) if len(k) else 0.0
    if len(k) < 3:
        return float(mid)
    x = (k - mid) / max(k[-1] - k[0], 1)
    A = np.stack([x * x, x, np.ones_like(x)], axis=1)
    (a2, a1, _), *_ = np.linalg.lstsq(A, profile[k], rcond=None)
    if abs(a2) < 1e-9 or abs(a1 / (2 * a2)) > 0.5:
        return float(mid)
    return float(mid - a1 / (2 * a2) * max(k[-1] - k[0], 1))


@dataclass(eq=False)
class Profiles:
    """Column profiles of every pose of a :class:`~.catalog.Catalog` (see the module docstring).

    Attributes
    ----------
    q : cell width, mm; n : cells across the usable length; r : halo overhang, cells
    lo : (O, K) lowest outline point per cell, ``+inf`` padded; hi : (O, K + 2r) highest halo point
    k : (O,) cells of each pose; jmax : (O,) last cell a pose may start in
    v_lo, v_hi : (O,) vertex cells of the bottom profile and of the halo's top profile
    """

    q: float
    n: int
    r: int
    lo: np.ndarray
    hi: np.ndarray
    k: np.ndarray
    jmax: np.ndarray
    v_lo: np.ndarray
    v_hi: np.ndarray


def build_profiles(cat: Catalog, cells: int = CELLS) -> Profiles:
    """Column profiles of all poses of ``cat`` on ``cells`` cells across the usable length."""
    s = cat.spacing
    Lu = cat.L - s
    q = Lu / cells
    w = np.array([o.w for o in cat.orients])
    reach = max(max(-float(o.halo[:, 0].min()), float(o.halo[:, 0].max()) - o.w) for o in cat.orients)
    r = int(math.ceil(max(reach, 0.0) / q - 1e-12))          # cells a halo overhangs its box (mitres reach past s)
    ks = np.ceil(w / q - 1e-9).astype(np.int64)
    lo = column_extents([o.poly for o in cat.orients], q, np.zeros(len(ks)), ks)[0]
    hi = column_extents([o.halo for o in cat.orients], q, np.full(len(ks), -r * q), ks + 2 * r)[1]
    v_lo = np.array([_vertex(row) for row in lo])
    v_hi = np.array([_vertex(row) for row in hi]) - r
    jmax = np.maximum(np.floor((Lu - w) / q + 1e-9), 0).astype(np.int64)
    return Profiles(q, cells, r, lo, hi, ks, jmax, v_lo, v_hi)


def strip_parts(cat: Catalog) -> np.ndarray:
    """Parts whose narrowest pose box is at least :data:`ELONGATION` times longer than it is high, ``(P,)`` bool."""
    ratio = np.array([o.w / max(o.h, 1e-9) for o in cat.orients])
    best = np.maximum.reduceat(ratio, cat.part_start[:-1])
    return best >= ELONGATION


@dataclass(frozen=True)
class StackConfig:
    """Knobs of one stacked sheet (varied by the search)."""

    alpha: float = 1.0          # part values: area^alpha (kept for the shared search interface)
    bonus: float = 0.05         # score bonus per unit of (part area / mean part area): larger parts first
    jitter: float = 0.0         # random perturbation of scores
    height: float = 0.1         # score penalty per unit of (top of the part / sheet height): lowest first
    first: str = "longest"      # the first part of a sheet: "longest", "best" (least waste) or "random"


class StackFiller:
    """Fills sheets by dropping parts onto a skyline (see the module docstring)."""

    def __init__(self, cat: Catalog, work: Work, profiles: Profiles | None = None):
        self.cat = cat
        self.work = work
        if profiles is None:
            profiles = build_profiles(cat)
            work.add(COST_PROFILE * len(cat.orients))
        self.prof = profiles
        self.Hu = cat.H - cat.spacing
        self.o_h = np.array([o.h for o in cat.orients])
        self.halo_box = np.array([[*o.halo.min(axis=0), *o.halo.max(axis=0)] for o in cat.orients])   # (O, 4)
        self.mean_area = float(cat.part_area.mean())
        self.tol = 0.01

    # -- search interface ---------------------------------------------------------------------
    def part_values(self, cfg: StackConfig, rng: np.random.Generator | None) -> np.ndarray:
        return (self.cat.part_area / self.mean_area) ** cfg.alpha

    def random_config(self, rng: np.random.Generator) -> StackConfig:
        return StackConfig(bonus=float(rng.choice([0.0, 0.02, 0.05, 0.1, 0.2])),
                           jitter=float(rng.choice([0.0, 0.02, 0.05, 0.1])),
                           height=float(rng.choice([0.0, 0.1, 0.3, 1.0])),
                           first=str(rng.choice(["longest", "best", "random"])))

    @staticmethod
    def cost_key(cfg: StackConfig) -> tuple:
        """One cost level."""
        return ()

    def cheaper(self, cfg: StackConfig) -> StackConfig | None:
        """There is no cheaper stack: ``None``."""
        return None

    def initial_config(self) -> StackConfig:
        return StackConfig()

    # -- one sheet ------------------------------------------------------------------------------
    def _candidates(self, rem: np.ndarray, last: tuple[int, int] | None) -> tuple[np.ndarray, np.ndarray]:
        """Poses of the remaining parts and the cells they are dropped at: ``(o, j)`` each ``(C,)``."""
        c, P = self.cat, self.prof
        o = np.flatnonzero(rem[c.o_part] & (self.o_h <= self.Hu + 1e-9))
        jm = P.jmax[o]
        js = [np.zeros_like(o), jm]
        if last is not None:
            ol, jl = last
            js.append(np.full_like(o, jl))
            js.append(jl + P.k[ol] - P.k[o])
            js.append(np.round(jl + P.v_hi[ol] - P.v_lo[o]).astype(np.int64))
            js.append(np.full_like(o, jl + P.k[ol] + P.r))          # just right of the last piece
            js.append(jl - P.r - P.k[o])                            # just left of it
        J = np.clip(np.stack(js, axis=1), 0, jm[:, None])
        O = np.repeat(o, J.shape[1])
        J = J.reshape(-1)
        key = np.unique(O * (P.n + 1) + J)
        return key // (P.n + 1), key % (P.n + 1)

    def _drop(self, sky: np.ndarray, o: np.ndarray, j: np.ndarray, stride: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Rest height ``Y (C,)`` and the area wasted under each part ``(C,)`` for poses ``o`` dropped at cells ``j``.

        With ``stride > 1`` only every ``stride``-th cell of each pose is looked at: a quick,
        slightly optimistic estimate used to short-list candidates (never to place a part).
        """
        P = self.prof
        lo = P.lo[o, ::stride]
        idx = np.minimum(j[:, None] + np.arange(0, P.lo.shape[1], stride)[None, :], P.n - 1)
        s = sky[idx]
        y = np.maximum((s - lo).max(axis=1), 0.0)
        gap = np.where(np.isfinite(lo), y[:, None] + lo - s, 0.0).sum(axis=1) * (P.q * stride)
        self.work.add(COST_STEP + COST_CELL * lo.size)
        return y, gap

    def _slide(self, o: int, X: float, Y: float, pieces: list[Piece], d: tuple[float, float]) -> float:
        """How far pose ``o`` at ``(X, Y)`` moves along ``d`` before touching a halo (exact; capped by the walls)."""
        c = self.cat
        po = c.orients[o]
        ax = 0 if d[1] != 0.0 else 1            # lowering: halos overlapping in x; pushing left: in y
        lo, hi = (X, X + po.w) if ax == 0 else (Y, Y + po.h)
        band = []
        for p in pieces:
            off = p.X if ax == 0 else p.Y
            if off + self.halo_box[p.orient, ax] < hi and off + self.halo_box[p.orient, ax + 2] > lo:
                band.append(c.orients[p.orient].halo + np.array([p.X, p.Y]))
        self.work.add(COST_SLIDE)
        t = slide_distance(po.poly + np.array([X, Y]), band, d, self.tol)
        wall = Y if d[1] < 0 else X
        return float(min(t, wall))

    def _settle(self, o: int, X: float, Y: float, pieces: list[Piece]) -> tuple[float, float]:
        """Lower pose ``o`` from ``(X, Y)`` to first contact, then push it left and lower it again (exact)."""
        Y -= self._slide(o, X, Y, pieces, (0.0, -1.0))
        dx = self._slide(o, X, Y, pieces, (-1.0, 0.0))
        if dx > 1e-6:
            X -= dx
            Y -= self._slide(o, X, Y, pieces, (0.0, -1.0))
        return max(X, 0.0), max(Y, 0.0)

    def _raise(self, sky: np.ndarray, o: int, X: float, Y: float) -> None:
        """Raise the skyline over the halo of pose ``o`` placed at ``(X, Y)`` (``X`` anywhere, not only on a cell side).

        Shifted left by ``δ`` (``0 < δ < q``) from the cell side ``j q``, each cell ``c`` of the sheet
        sees only cells ``c`` and ``c + 1`` of the unshifted profile (one cell further left than
        before): their maximum bounds it.
        """
        P = self.prof
        j = int(math.ceil(X / P.q - 1e-9))
        hi = P.hi[o]
        lo_c = j - P.r
        if j * P.q - X > 1e-9:
            hi = np.maximum(np.r_[-np.inf, hi], np.r_[hi, -np.inf])
            lo_c -= 1
        a0, a1 = max(lo_c, 0), min(lo_c + len(hi), P.n)
        sky[a0:a1] = np.maximum(sky[a0:a1], Y + hi[a0 - lo_c: a1 - lo_c])

    def _score(self, cfg: StackConfig, o: np.ndarray, y: np.ndarray, gap: np.ndarray) -> np.ndarray:
        """Waste under the part per unit of its area, less the size bonus, plus the height penalty (lower is better)."""
        area = self.cat.part_area[self.cat.o_part[o]]
        return gap / area - cfg.bonus * area / self.mean_area + cfg.height * (y + self.o_h[o]) / self.Hu

    def _best_drop(self, sky: np.ndarray, o: np.ndarray, j: np.ndarray, cfg: StackConfig,
                   rng: np.random.Generator | None) -> tuple[int, int, float] | None:
        """The drop of least score that fits under the top edge: ``(pose, cell, Y)``, or ``None``.

        Many candidates are first ranked on every :data:`STRIDE`-th cell (an optimistic rest
        height: a candidate that fails there fails exactly too), then evaluated exactly in that
        order, :data:`SHORTLIST` at a time, until a batch holds one that fits.
        """
        if len(o) > SHORTLIST:
            y, gap = self._drop(sky, o, j, STRIDE)
            rough = np.where(y + self.o_h[o] <= self.Hu + 1e-9, self._score(cfg, o, y, gap), np.inf)
            order = np.argsort(rough, kind="stable")
            order = order[np.isfinite(rough[order])]
            batches = [np.sort(order[i: i + SHORTLIST]) for i in range(0, len(order), SHORTLIST)]
        else:
            batches = [np.arange(len(o))]
        for idx in batches:
            oo, jj = o[idx], j[idx]
            y, gap = self._drop(sky, oo, jj)
            fit = np.flatnonzero(y + self.o_h[oo] <= self.Hu + 1e-9)
            if len(fit) == 0:
                continue
            score = self._score(cfg, oo[fit], y[fit], gap[fit])
            if cfg.jitter > 0 and rng is not None:
                score = score + cfg.jitter * rng.random(len(score))
            b = fit[int(np.argmin(score))]
            return int(oo[b]), int(jj[b]), float(y[b])
        return None

    def fill_sheet(self, rem: np.ndarray, cfg: StackConfig, values: np.ndarray,
                   rng: np.random.Generator | None) -> Sheet | None:
        """Stack parts from ``rem`` on one empty sheet (``rem`` is updated); ``None`` if none fits.

        ``values`` (the search's part values) are not used: a stack takes whatever fits best.
        """
        c, P = self.cat, self.prof
        sky = np.zeros(P.n)
        sheet = Sheet()
        last: tuple[int, int] | None = None
        while rem.any():
            o, j = self._candidates(rem, last)
            if len(o) == 0:
                break
            if last is None and cfg.first != "best":          # the sheet's first part: longest or random
                parts = c.o_part[o]
                if cfg.first == "random" and rng is not None:
                    pick = np.unique(parts)[int(rng.integers(len(np.unique(parts))))]
                else:
                    pick = parts[int(np.argmax(c.o_w[o]))]
                o, j = o[parts == pick], j[parts == pick]
            drop = self._best_drop(sky, o, j, cfg, rng)
            if drop is None:
                break
            ob, jb, y = drop
            X, Y = self._settle(ob, jb * P.q, y, sheet.pieces)
            sheet.pieces.append(Piece(ob, X, Y))
            rem[c.o_part[ob]] = False
            self._raise(sky, ob, X, Y)
            last = (ob, int(round(X / P.q)))
        if not sheet.pieces:
            return None
        sheet.area = float(c.part_area[[c.o_part[p.orient] for p in sheet.pieces]].sum())
        return sheet
