"""True-shape rows: outlines pushed together along a row and rows dropped into the row below.

A sheet is filled bottom to top with rows (bands).  Within a row every part stands on the row's
base line in one of its poses (for a part that may turn freely: each long hull edge down or up,
its minimum-area frame), and parts are placed left to right, each pushed against the ones before.
Neighbouring sheared quads or trapezoids turned by 180° meet along their slanted edges, so the
row wastes only its two end triangles, not one per part.

The row is cut into horizontal slabs of height ``q``.  Per pose (:class:`BandProfiles`):

* ``lx[o, k]`` — the leftmost point of the outline in slab ``k`` (``+inf`` where it has none),
* ``rx[o, k]`` — the rightmost point of its *halo* (outline offset by the spacing) in slab ``k``
  (``−inf`` where none), slab ``k`` of the halo lying ``r`` slabs lower than slab ``k`` of the pose.

Both are exact extents over each slab (:func:`~.stack.column_extents` on the transposed
outlines), hence conservative.  A row keeps a *frontier* ``F[k]`` = the rightmost halo point in
each of its slabs (0 on an empty row: the sheet's left edge).  A pose pushed in from the right
comes to rest at

    x = max(0, max_k (F[k] − lx[o, k])),

every point of its outline right of every halo in the row, so it is at least the spacing away
from the others.  The candidate of least *waste* wins: the row area it consumes (between the old
and the new frontier, the space above a part lower than the row counted as consumed) per unit of
its own area, less a bonus for large parts.  The winner is then settled exactly
(:func:`~.shapes.slide_distance`): pushed left to first contact, removing the slab rounding.

A sheet tries a few row heights for each row (the heights of the remaining poses at a few
quantiles) and keeps the row of highest area per row height.  In ``irregular`` sheets each finished
row is then dropped part by part onto the rows below (exact sliding).

``guillotine`` sheets keep every row separable by straight cuts that run edge to edge, as glass
is scored and broken: rows are cut across the sheet (no dropping), and within a row each new part
gets a cut line along its left edge (offset by half the spacing) that must leave every part placed
before on its left across the whole row height; the cut line joins the frontier, so no later part
crosses it.  A convex part is then trimmed out of its cell by its own edge lines.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .catalog import Catalog
from .reach import fillable
from .budget import Work
from .rows import Piece, Sheet
from .shapes import HALO_EXTRA, slide_distance
from .stack import column_extents

END_Q = 10.0                  # grid of the look-ahead over row lengths and sheet heights, mm
SLABS = 40                    # slabs over the median pose height
LEAN_WINDOW = 1024            # the tallest poses searched for a left side parallel to the frontier
SHORTLIST = 48                # candidates evaluated exactly per batch (the ones closest below the row height)
# work units (≈ 1 µs each on the reference machine)
COST_STEP, COST_CELL, COST_SLIDE, COST_ROW, COST_REACH = 30.0, 1.16 / 400.0, 70.0, 23.0, 116.0
COST_PROFILE = 30.0            # per pose: slab profiles and the filler's arrays


@dataclass(eq=False)
class BandProfiles:
    """Row-slab profiles of every pose of a :class:`~.catalog.Catalog` (see the module docstring).

    Attributes
    ----------
    q : slab height, mm; r : slabs a halo reaches beyond its pose
    nk : (O,) slabs of each pose; lx : (O, K) leftmost outline point per slab, ``+inf`` padded
    rx : (O, K + 2r) rightmost halo point per slab (halo slab ``k`` = pose slab ``k − r``), ``−inf`` padded
    """

    q: float
    r: int
    nk: np.ndarray
    lx: np.ndarray
    rx: np.ndarray


def build_band_profiles(cat: Catalog, slabs: int = SLABS) -> BandProfiles:
    """Slab profiles of all poses of ``cat`` (slab height = median pose height / ``slabs``)."""
    h = np.array([o.h for o in cat.orients])
    q = max(float(np.median(h)) / slabs, 1.0)
    reach = max(max(-float(o.halo[:, 1].min()), float(o.halo[:, 1].max()) - o.h) for o in cat.orients)
    r = int(math.ceil(max(reach, 0.0) / q - 1e-12))
    nk = np.ceil(h / q - 1e-9).astype(np.int64)
    nk = np.maximum(nk, 1)
    lx = column_extents([o.poly[:, ::-1] for o in cat.orients], q, np.zeros(len(nk)), nk)[0]
    rx = column_extents([o.halo[:, ::-1] for o in cat.orients], q, np.full(len(nk), -r * q), nk + 2 * r)[1]
    return BandProfiles(q, r, nk, lx, rx)


@dataclass(frozen=True)
class BandConfig:
    """Knobs of one sheet (varied by the search)."""

    alpha: float = 1.0          # part values: area^alpha (shared search interface)
    bonus: float = 0.05         # waste bonus per unit of (part area / mean part area): larger parts first
    jitter: float = 0.0         # random perturbation of the waste scores
    heights: int = 3            # row heights tried per row
    spread: float = 0.6         # quantile range of remaining pose heights the row heights come from
    shortlist: int = SHORTLIST
    ends: float = 1.0           # weight of the row-end look-ahead (length no remaining part can fill)
    lean: int = 32              # poses added to the first batch for the best match of lean (0: none)
    first: int = 4              # first-row heights for which the whole sheet is completed (the fullest kept)
    exact: bool = True          # settle parts by exact sliding (left along the row, rows dropped); else the
                                # slab positions (conservative, a few mm looser) are kept
    tops: float = 1.0           # weight of the sheet-top look-ahead (height no remaining row can fill)


class BandFiller:
    """Fills sheets with true-shape rows (see the module docstring)."""

    def __init__(self, cat: Catalog, work: Work, guillotine: bool = False, profiles: BandProfiles | None = None):
        self.cat = cat
        self.work = work
        self.guillotine = guillotine
        if profiles is None:
            profiles = build_band_profiles(cat)
            work.add(COST_PROFILE * len(cat.orients))
        self.prof = profiles
        self.Lu = cat.L - cat.spacing
        self.Hu = cat.H - cat.spacing
        self.s = cat.spacing
        self.o_w = np.array([o.w for o in cat.orients])
        self.o_h = np.array([o.h for o in cat.orients])
        self.o_area = cat.part_area[cat.o_part]
        self.mean_area = float(cat.part_area.mean())
        P = self.prof
        k = np.arange(P.lx.shape[1])
        top = np.clip(P.nk - 1 + P.r, 0, P.rx.shape[1] - 1)
        self.rtop = P.rx[np.arange(len(P.nk)), top]                       # rightmost halo point at a pose's top slab
        self.rtop = np.where(np.isfinite(self.rtop), self.rtop, self.o_w + self.s)
        self.k = k
        # halo right extents aligned with the pose's slabs, the space above its top counted as taken: (O, K)
        K = P.lx.shape[1]
        rxa = np.full((len(P.nk), K), -np.inf)
        m = min(K, P.rx.shape[1] - P.r)
        rxa[:, :m] = P.rx[:, P.r:P.r + m]
        self.rxa = np.where(k[None, :] >= P.nk[:, None], np.maximum(rxa, self.rtop[:, None]), rxa)
        self.row_gap = self.s + HALO_EXTRA + 1e-3        # a row starts above the halos of the row below
        self.halo_box = np.array([[*o.halo.min(axis=0), *o.halo.max(axis=0)] for o in cat.orients])
        self.w_base = self.o_w - np.where(np.isfinite(P.lx[:, 0]), P.lx[:, 0], 0.0)
        top = np.maximum(P.nk - 1, 0)
        lx_top = P.lx[np.arange(len(P.nk)), top]
        self.left_lean = np.where(P.nk > 1, (lx_top - P.lx[:, 0]) / np.maximum(P.nk - 1, 1), 0.0)   # slope per slab
        self.by_h = np.argsort(self.o_h, kind="stable")
        self.h_sorted = self.o_h[self.by_h]
        self.tol = 0.01
        # the left edge of each pose: the hull edge whose outward normal points most to −x (for cut lines)
        self._left_edges: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    # -- search interface ---------------------------------------------------------------------
    def part_values(self, cfg: BandConfig, rng: np.random.Generator | None) -> np.ndarray:
        return (self.cat.part_area / self.mean_area) ** cfg.alpha

    def initial_config(self) -> BandConfig:
        return BandConfig()

    @staticmethod
    def cost_key(cfg: BandConfig) -> tuple:
        """Configurations compare by cost in this order (larger = dearer)."""
        return (cfg.first, cfg.heights, cfg.exact, cfg.shortlist)

    def cheaper(self, cfg: BandConfig) -> BandConfig | None:
        """The next configuration down the cost ladder (fewer trials, then no exact settling), or ``None``."""
        for step in (BandConfig(first=2, heights=2), BandConfig(first=1, heights=1),
                     BandConfig(first=1, heights=1, exact=False, ends=0.0, tops=0.0, lean=0, shortlist=24)):
            if self.cost_key(step) < self.cost_key(cfg):
                return replace(step, bonus=cfg.bonus, jitter=cfg.jitter)
        return None

    def random_config(self, rng: np.random.Generator) -> BandConfig:
        return BandConfig(bonus=float(rng.choice([0.0, 0.02, 0.05, 0.1, 0.2])),
                          jitter=float(rng.choice([0.0, 0.0, 0.02, 0.05])),
                          heights=int(rng.choice([2, 3, 5])),
                          spread=float(rng.choice([0.3, 0.6, 1.0])),
                          first=int(rng.choice([2, 4, 6])))

    # -- one row --------------------------------------------------------------------------------
    def _row_heights(self, rem: np.ndarray, h_left: float, cfg: BandConfig, rng: np.random.Generator | None) -> list[float]:
        c = self.cat
        live = rem[c.o_part] & (self.o_h <= h_left + 1e-9) & (self.o_w <= self.Lu + 1e-9)
        hs = np.unique(self.o_h[live])
        if len(hs) == 0:
            return []
        qs = np.linspace(1.0, 1.0 - cfg.spread, cfg.heights)
        if rng is not None and cfg.jitter > 0:
            qs = np.clip(qs + rng.uniform(-0.05, 0.05, len(qs)), 0.0, 1.0)
        pick = np.unique(np.round(qs * (len(hs) - 1)).astype(int))[::-1]
        return [float(hs[i]) for i in pick]

    def _candidates(self, rem: np.ndarray, hr: float, F: np.ndarray, cfg: BandConfig):
        """Batches of poses to evaluate for a row of height ``hr``: the tallest that fit below ``hr`` first.

        Poses are kept sorted by height, so the candidates are read backwards from the row height in
        windows that double until a batch is full (removed parts and too-wide poses skipped).  The first
        batch also holds the poses, among the :data:`LEAN_WINDOW` tallest, whose left side runs most
        nearly parallel to the row's frontier (a sheared quad after one leaning the same way, a
        trapezoid turned 180° after one upright): the pairs that meet along their slanted edges.
        """
        c = self.cat
        room = self.Lu - float(F.min())
        room0 = self.Lu - float(F[0])          # every pose stands on slab 0: it ends at least w − lx[0] right of F[0]
        end = int(np.searchsorted(self.h_sorted, hr + 1e-9, side="right"))
        m = cfg.shortlist
        win = 4 * m
        first = True
        while end > 0:
            start = max(end - (max(win, LEAN_WINDOW) if first else win), 0)
            idx = self.by_h[start:end][::-1]
            ok = idx[rem[c.o_part[idx]] & (self.o_w[idx] <= room + 1e-9) & (self.w_base[idx] <= room0 + 1e-9)]
            self.work.add(COST_CELL * (end - start) * 20)
            if first and len(ok) > m and cfg.lean > 0:
                n = len(F)
                lean = (F[n - 1] - F[0]) / max(n - 1, 1)            # frontier slope per slab
                key = np.abs(self.left_lean[ok] - lean)
                near = np.argpartition(key, cfg.lean - 1)[: cfg.lean] if len(ok) > cfg.lean else np.arange(len(ok))
                head = np.unique(np.r_[ok[:m], ok[near]])
                yield head
                ok = ok[~np.isin(ok, head)]
                end = start
                win = 2 * max(win, LEAN_WINDOW)
                first = False
                for i in range(0, len(ok), m):
                    yield ok[i: i + m]
                continue
            first = False
            for i in range(0, len(ok), m):
                yield ok[i: i + m]
            end = start
            win *= 2

    def _evaluate(self, o: np.ndarray, F: np.ndarray, nr: int, cfg: BandConfig,
                  rng: np.random.Generator | None, ends: np.ndarray | None = None,
                  hr: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Rest positions ``x (C,)`` and scores ``(C,)`` (``inf`` where the pose does not fit the row)."""
        P = self.prof
        lx = P.lx[o, :nr]
        x = np.maximum((F[None, :] - lx).max(axis=1), 0.0)
        Fn = np.maximum(F[None, :], x[:, None] + self.rxa[o, :nr])
        consumed = (Fn.sum(axis=1) - F.sum()) * P.q
        area = self.o_area[o]
        score = consumed / area - cfg.bonus * area / self.mean_area
        if ends is not None:            # the row length left after this part, and how much of it others can fill
            left = np.clip(self.Lu - (F.sum() + consumed / P.q) / nr, 0.0, self.Lu)
            cell = np.minimum((left / END_Q).astype(np.int64), len(ends) - 1)
            score = score + cfg.ends * (left - ends[cell]) * hr / area
        if cfg.jitter > 0 and rng is not None:
            score = score + cfg.jitter * rng.random(len(score))
        fits = x + self.o_w[o] <= self.Lu + 1e-9
        self.work.add(COST_STEP + COST_CELL * lx.size * 3)
        return x, np.where(fits, score, np.inf)

    def _halos_in(self, pieces: list[Piece], y0: float, y1: float) -> list[np.ndarray]:
        c = self.cat
        out = []
        for p in pieces:
            hl = c.orients[p.orient].halo
            if p.Y + float(hl[:, 1].min()) < y1 and p.Y + float(hl[:, 1].max()) > y0:
                out.append(hl + np.array([p.X, p.Y]))
        return out

    def _cut_line(self, o: int) -> tuple[np.ndarray, np.ndarray]:
        """A point and a direction of the left cut line of pose ``o`` (its left hull edge, in pose coordinates)."""
        if o not in self._left_edges:
            poly = self.cat.orients[o].poly
            e = np.roll(poly, -1, axis=0) - poly
            n = np.stack([e[:, 1], -e[:, 0]], axis=1)                 # outward normals of a CCW polygon
            ln = np.hypot(n[:, 0], n[:, 1])
            k = int(np.argmin(np.where(ln > 1e-9, n[:, 0] / np.maximum(ln, 1e-12), np.inf)))
            d = e[k] / max(float(ln[k]), 1e-12)
            self._left_edges[o] = (poly[k] - 0.5 * self.s * n[k] / max(float(ln[k]), 1e-12), d)
        return self._left_edges[o]

    def _cut_x(self, o: int, X: float, Y: float, ys: np.ndarray) -> np.ndarray:
        """x of the left cut line of pose ``o`` at ``(X, Y)`` at heights ``ys``."""
        p, d = self._cut_line(o)
        p = p + np.array([X, Y])
        if abs(d[1]) < 1e-9:                    # a horizontal left edge cannot cut the row: no constraint
            return np.full(len(ys), -np.inf)
        return p[0] + (ys - p[1]) * d[0] / d[1]

    def _guillotine_shift(self, o: int, X: float, Y: float, hr: float, row: list[Piece]) -> float:
        """How far right pose ``o`` must move so its left cut line clears every part placed before in the row."""
        if not row:
            return 0.0
        c = self.cat
        pts = np.concatenate([c.orients[p.orient].poly + np.array([p.X, p.Y]) for p in row])
        need = pts[:, 0] - self._cut_x(o, X, Y, pts[:, 1])
        return float(max(need.max(), 0.0))

    def fill_row(self, rem: np.ndarray, yb: float, hr: float, cfg: BandConfig,
                 rng: np.random.Generator | None, below: list[Piece]) -> tuple[list[Piece], float]:
        """Parts in one row of height at most ``hr`` with its base at ``yb``: ``(pieces, part area)``.

        ``rem`` is not changed.  ``below`` are the pieces of the rows underneath (for the drop).
        """
        c, P = self.cat, self.prof
        nr = int(math.ceil(hr / P.q - 1e-9))
        F = np.zeros(nr)
        rem = rem.copy()
        row: list[Piece] = []
        area = 0.0
        ends = None
        if cfg.ends > 0:
            live = rem[c.o_part] & (self.o_h <= hr + 1e-9) & (self.o_h >= 0.7 * hr) & (self.o_w <= self.Lu + 1e-9)
            if live.any():
                ends = fillable(self.o_area[live] / self.o_h[live] + self.s, self.Lu, END_Q, 8)
                self.work.add(COST_REACH)
        while True:
            best = None
            for batch in self._candidates(rem, hr, F, cfg):
                xs, score = self._evaluate(batch, F, nr, cfg, rng, ends, hr)
                if np.isfinite(score).any():
                    b = int(np.argmin(score))
                    best = (int(batch[b]), float(xs[b]))
                    break
            if best is None:
                break
            o, x = best
            halos = self._halos_in(row, yb, yb + hr) if cfg.exact else []
            if halos:
                t = slide_distance(c.orients[o].poly + np.array([x, yb]), halos, (-1.0, 0.0), self.tol)
                self.work.add(COST_SLIDE)
                x = max(x - min(t, x), 0.0)
            if self.guillotine:
                shift = self._guillotine_shift(o, x, yb, hr, row)
                self.work.add(COST_SLIDE)
                if x + shift + self.o_w[o] > self.Lu + 1e-9:
                    rem[c.o_part[o]] = False            # does not fit with its cut: try the others
                    continue
                x += shift
            row.append(Piece(o, float(x), float(yb)))
            rem[c.o_part[o]] = False
            area += float(self.o_area[o])
            F = np.maximum(F, x + self.rxa[o, :nr])
            if self.guillotine:
                ys = yb + (np.arange(nr) + 1.0) * P.q
                cut = np.maximum(self._cut_x(o, x, yb, ys), self._cut_x(o, x, yb, ys - P.q))
                F = np.maximum(F, cut)
        return row, area

    # -- one sheet --------------------------------------------------------------------------------
    def _drop(self, row: list[Piece], placed: list[Piece]) -> list[Piece]:
        """Lower each piece of a finished row onto the pieces below it (exact sliding), left to right.

        A halo may overlap a neighbour placed against the *other* halo (at bevelled corners), so each
        test starts from a state known to be clear: the piece's outline against the halos of the pieces
        placed before it (rows below, row neighbours to its left, already lowered), and its halo
        against the outlines of the neighbours to its right (which were pushed against its halo).
        """
        c = self.cat
        out: list[Piece] = []
        below = list(placed)
        bo = np.array([q.orient for q in below], dtype=np.int64)
        bx = np.array([q.X for q in below])
        lo_b = bx + self.halo_box[bo, 0] if len(below) else np.zeros(0)
        hi_b = bx + self.halo_box[bo, 2] if len(below) else np.zeros(0)
        for i, p in enumerate(row):
            po = c.orients[p.orient]
            at = np.array([p.X, p.Y])
            x0, x1 = p.X - self.s, p.X + po.w + self.s
            near = np.flatnonzero((lo_b < x1) & (hi_b > x0))
            before = [c.orients[below[k].orient].halo + np.array([below[k].X, below[k].Y]) for k in near]
            before += [c.orients[q.orient].halo + np.array([q.X, q.Y]) for q in out
                       if q.X + self.halo_box[q.orient, 0] < x1 and q.X + self.halo_box[q.orient, 2] > x0]
            after = [c.orients[q.orient].poly + np.array([q.X, q.Y]) for q in row[i + 1:]
                     if q.X + self.halo_box[q.orient, 0] < x1 and q.X + self.halo_box[q.orient, 2] > x0]
            t = min(slide_distance(po.poly + at, before, (0.0, -1.0), self.tol),
                    slide_distance(po.halo + at, after, (0.0, -1.0), self.tol))
            self.work.add(2 * COST_SLIDE + COST_CELL * 20 * len(below))
            out.append(Piece(p.orient, p.X, p.Y - float(min(t, p.Y))))
        return out

    def _complete(self, rem: np.ndarray, cfg: BandConfig, rng: np.random.Generator | None,
                  first: float | None) -> list[Piece]:
        """Rows from the bottom of an empty sheet to its top (``rem`` updated); the first row of height
        at most ``first`` when given, every other row the best of a few trial heights."""
        c = self.cat
        pieces: list[Piece] = []
        yb = 0.0
        while True:
            h_left = self.Hu - yb
            heights = [first] if (first is not None and not pieces) else self._row_heights(rem, h_left, cfg, rng)
            trials = []
            for hr in heights:
                row, area = self.fill_row(rem, yb, hr, cfg, rng, pieces)
                self.work.add(COST_ROW)
                if row:
                    top = max(p.Y + self.o_h[p.orient] for p in row) - yb
                    trials.append((area, top, row))
            if not trials:
                break
            if len(trials) > 1 and cfg.tops > 0:
                live = rem[c.o_part] & (self.o_h <= h_left + 1e-9)
                tops = fillable(self.o_h[live] + self.row_gap, max(h_left, END_Q), END_Q, 4)
                self.work.add(COST_REACH)
                eff = float(np.median([a / ((t + self.row_gap) * self.Lu) for a, t, _ in trials]))

                def value(tr: tuple) -> float:
                    rest = h_left - tr[1] - self.row_gap
                    more = tops[min(int(rest / END_Q), len(tops) - 1)] if rest > 0 else 0.0
                    return tr[0] + cfg.tops * eff * self.Lu * more
                row = max(trials, key=value)[2]
            else:
                row = max(trials, key=lambda tr: tr[0] / ((tr[1] + self.row_gap) * self.Lu))[2]
            if not self.guillotine and pieces and cfg.exact:
                row = self._drop(row, pieces)
            pieces.extend(row)
            rem[c.o_part[[p.orient for p in row]]] = False
            # the next row starts above every halo on the sheet (a lowered row may end below a tall part under it)
            yb = max(yb, max(p.Y + self.halo_box[p.orient, 3] for p in row) + 1e-3)
            if yb >= self.Hu:
                break
        return pieces

    def fill_sheet(self, rem: np.ndarray, cfg: BandConfig, values: np.ndarray,
                   rng: np.random.Generator | None) -> Sheet | None:
        """Rows of parts from ``rem`` on one empty sheet (``rem`` is updated); ``None`` if none fits.

        The sheet is completed for each of ``cfg.first`` first-row heights and the fullest is kept.
        Every further row is the best of a few trial heights: its part area plus the area the rows
        above can be expected to hold (the row efficiency of the trials times the sheet height still
        fillable by stacking remaining pose heights, :func:`~.reach.fillable`).
        """
        c = self.cat
        firsts: list[float | None] = [None]
        if cfg.first > 1:
            firsts = list(self._row_heights(rem, self.Hu, replace(cfg, heights=cfg.first), rng)) or [None]
        best: tuple[float, list[Piece], np.ndarray] | None = None
        for h1 in firsts:
            r = rem.copy()
            pieces = self._complete(r, cfg, rng, h1)
            area = float(c.part_area[[c.o_part[p.orient] for p in pieces]].sum()) if pieces else 0.0
            if pieces and (best is None or area > best[0] + 1e-9):
                best = (area, pieces, r)
        if best is None:
            return None
        rem[:] = best[2]
        return Sheet(best[1], best[0])
