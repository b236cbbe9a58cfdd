"""Filling one sheet with rows: a knapsack per row, a search over row heights, nestling.

A sheet is filled bottom to top with rows (the first-stage cuts of a guillotine plan run
along the sheet's length).  For a row of height at most ``Hc`` every remaining part takes
its narrowest pose of height ``<= Hc``; a 0/1 knapsack over the quantised box widths
(capacity = the sheet length) picks the parts of largest total value (Σ area^α); the row's
height is its tallest box.  A sheet tries several first-row heights and stacks further rows
greedily into the height left; the plan of largest total value wins.

*Guillotine* sheets keep the boxes: rows are cut across the sheet, parts across each row,
and every part is trimmed inside its box (edge to edge for convex parts).

*Irregular* sheets keep only the planned row heights.  Each row is filled again from the
pool with the knapsack capacity stretched by a few per cent; its parts are ordered, and
turned to a twin pose with the same box (e.g. 180°), to maximise the exact nestling gains
between neighbours (:func:`~.shapes.pair_gains`); each part slides left against what is
placed (:func:`~.shapes.slide_distance`).  The first stretch whose nestled row really fits
is kept, and the length still free is offered again.

Positions are box corners in the planning frame of :mod:`.catalog`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .budget import Work
from .catalog import Catalog
from .shapes import pair_gains, slide_distance

# work units (≈ 1 µs each on the reference machine) charged per operation: see .budget
COST_DP_CALL, COST_DP_ITEM, COST_SLIDE, COST_GAINS, COST_ORDER = 140.0, 4.65, 280.0, 700.0, 186.0


@dataclass
class Piece:
    """A placed pose ``orient`` with its box corner at ``(X, Y)`` in the planning frame."""

    orient: int
    X: float
    Y: float


@dataclass
class Sheet:
    """The pieces on one sheet and their total part area (mm²)."""

    pieces: list[Piece] = field(default_factory=list)
    area: float = 0.0


@dataclass(frozen=True)
class PlanConfig:
    """Knobs of one sheet plan (varied by the search)."""

    alpha: float = 1.0          # value = area^alpha: > 1 favours large parts
    n_heights: int = 16         # first-row heights tried
    top_k: int = 64             # parts offered to a row knapsack
    quantum: float = 5.0        # knapsack width quantum, mm
    jitter: float = 0.0         # random perturbation of part values (0 = none)
    stretch: tuple[float, ...] = (0.04, 0.025, 0.012, 0.0)   # irregular rows: length stretches tried


class SheetFiller:
    """Plans and realises sheets for a :class:`~.catalog.Catalog`."""

    def __init__(self, cat: Catalog, irregular: bool, work: Work):
        self.cat = cat
        self.irregular = irregular
        self.work = work
        self.tol = 0.01
        self._gains: dict[tuple[int, int], float] = {}

    # -- knapsack rows ------------------------------------------------------------------------
    def _row_poses(self, rem: np.ndarray, hc: float, cap: float) -> np.ndarray:
        """The narrowest pose of height <= hc of every remaining part (pose indices)."""
        c = self.cat
        fit = rem[c.o_part] & (c.o_h <= hc + 1e-9) & (c.o_w <= cap + 1e-9)
        idx = np.flatnonzero(fit)
        if len(idx) == 0:
            return idx
        srt = idx[np.lexsort((-c.o_h[idx], c.o_w[idx], c.o_part[idx]))]
        first = np.r_[True, c.o_part[srt][1:] != c.o_part[srt][:-1]]
        return srt[first]

    def best_row(self, rem: np.ndarray, hc: float, cap: float, cfg: PlanConfig,
                 values: np.ndarray) -> tuple[float, list[int]]:
        """0/1 knapsack: poses for a row of height <= ``hc`` and length <= ``cap`` of largest value.

        Widths are rounded up and the capacity down to ``cfg.quantum``, so a chosen row always fits.
        """
        c = self.cat
        poses = self._row_poses(rem, hc, cap)
        self.work.add(COST_DP_CALL)
        if len(poses) == 0:
            return 0.0, []
        parts = c.o_part[poses]
        if len(poses) > cfg.top_k:
            eff = c.part_area[parts] / (c.o_w[poses] * hc)
            keep = np.sort(np.argsort(-eff, kind="stable")[: cfg.top_k])
            poses, parts = poses[keep], parts[keep]
        q = cfg.quantum
        cells = int(math.floor(cap / q + 1e-9))
        wcell = np.ceil(c.o_w[poses] / q - 1e-9).astype(np.int64)
        vals = values[parts]
        best = np.zeros(cells + 1)
        take = np.zeros((len(poses), cells + 1), dtype=bool)
        for k in range(len(poses)):
            w = int(wcell[k])
            if w > cells:
                continue
            cand = best[: cells + 1 - w] + vals[k]
            improved = cand > best[w:] + 1e-12
            take[k, w:] = improved
            best[w:] = np.where(improved, cand, best[w:])
        self.work.add(COST_DP_ITEM * len(poses) * (1 + cells / 1200))
        cell = int(np.argmax(best))
        total = float(best[cell])
        chosen: list[int] = []
        for k in range(len(poses) - 1, -1, -1):
            if take[k, cell]:
                chosen.append(int(poses[k]))
                cell -= int(wcell[k])
        return total, chosen[::-1]

    # -- sheet plans -------------------------------------------------------------------------------
    def part_values(self, cfg: PlanConfig, rng: np.random.Generator | None) -> np.ndarray:
        """Knapsack value of every part: (area / mean area)^α, optionally jittered."""
        c = self.cat
        v = (c.part_area / c.part_area.mean()) ** cfg.alpha
        if cfg.jitter > 0 and rng is not None:
            v = v * (1.0 + cfg.jitter * rng.random(len(v)))
        return v

    def plan(self, rem: np.ndarray, cfg: PlanConfig, values: np.ndarray,
             rng: np.random.Generator | None) -> list[list[int]]:
        """Rows of poses for one sheet (bottom to top) of largest total value."""
        c = self.cat
        live = rem[c.o_part]
        heights = np.unique(c.o_h[live])[::-1]
        if len(heights) == 0:
            return []
        if len(heights) > cfg.n_heights:
            pick = np.linspace(0, len(heights) - 1, cfg.n_heights)
            if rng is not None and cfg.jitter > 0:
                pick = np.clip(pick + rng.uniform(-0.5, 0.5, len(pick)) * (len(heights) / cfg.n_heights), 0,
                               len(heights) - 1)
            firsts = heights[np.unique(np.round(pick).astype(int))]
        else:
            firsts = heights
        best_value, best_rows = -1.0, []
        for h1 in firsts:
            r = rem.copy()
            rows: list[list[int]] = []
            total, left, hc = 0.0, c.H, float(h1)
            while True:
                v, row = self.best_row(r, hc, c.L, cfg, values)
                if not row:
                    break
                rows.append(row)
                total += v
                r[c.o_part[row]] = False
                left -= float(c.o_h[row].max())
                fit = r[c.o_part] & (c.o_h <= left + 1e-9)
                if not fit.any():
                    break
                hc = float(c.o_h[fit].max())
            if total > best_value + 1e-9:
                best_value, best_rows = total, rows
        return best_rows

    # -- search interface --------------------------------------------------------------------------
    def fill_sheet(self, rem: np.ndarray, cfg: PlanConfig, values: np.ndarray,
                   rng: np.random.Generator | None) -> Sheet | None:
        """Plan and realise one sheet from the parts in ``rem`` (updated); ``None`` if no row fits."""
        rows = self.plan(rem, cfg, values, rng)
        return self.realise(rows, rem, cfg, values) if rows else None

    def initial_config(self) -> PlanConfig:
        return PlanConfig()

    def random_config(self, rng: np.random.Generator) -> PlanConfig:
        """Randomised knobs for one ruin-and-recreate step."""
        return PlanConfig(alpha=float(rng.uniform(0.8, 1.8)), n_heights=int(rng.choice([10, 16, 24])),
                          top_k=int(rng.choice([48, 64, 96])), jitter=float(rng.choice([0.0, 0.05, 0.15, 0.3])))

    # -- realisation -------------------------------------------------------------------------------
    def realise(self, rows: list[list[int]], rem: np.ndarray, cfg: PlanConfig, values: np.ndarray) -> Sheet:
        """Place planned rows (``rem`` is updated in place)."""
        c = self.cat
        sheet = Sheet()
        y = 0.0
        for row in rows:
            height = float(c.o_h[row].max())
            if self.irregular:
                self._nestle_row(sheet, y, height, rem, cfg, values)
            else:
                rem[c.o_part[row]] = False
                x = 0.0
                for o in row:
                    sheet.pieces.append(Piece(int(o), x, y))
                    x += float(c.o_w[o])
            y += height
        sheet.area = float(c.part_area[[c.o_part[p.orient] for p in sheet.pieces]].sum())
        return sheet

    def _twins(self, o: int) -> np.ndarray:
        c = self.cat
        p = c.o_part[o]
        r = np.arange(c.part_start[p], c.part_start[p + 1])
        return r[c.twins[r] == c.twins[o]]

    def _gain_matrix(self, poses: list[int]) -> np.ndarray:
        """Nestling gains ``G[a, b]`` of pose ``b`` following pose ``a`` (cached across calls)."""
        c = self.cat
        n = len(poses)
        if any((a, b) not in self._gains for a in poses for b in poses):
            G = pair_gains([c.orients[o].halo for o in poses], np.array([c.orients[o].w for o in poses]),
                           [c.orients[o].poly for o in poses], c.spacing)
            self.work.add(COST_GAINS + 4.65 * n * n)
            for i, a in enumerate(poses):
                for j, b in enumerate(poses):
                    self._gains[(a, b)] = float(G[i, j])
        return np.array([[self._gains[(a, b)] for b in poses] for a in poses]).reshape(n, n)

    def _order(self, row: list[int], last: int | None) -> list[int]:
        """Order and twin choice of a row's poses maximising the neighbours' nestling gains (greedy)."""
        var = [self._twins(o) for o in row]
        flat = [int(v) for vs in var for v in vs]
        item = np.array([k for k, vs in enumerate(var) for _ in vs])
        pool = flat + ([last] if last is not None else [])
        G = self._gain_matrix(pool)
        self.work.add(COST_ORDER)
        best_total, best_seq = -1.0, [0]
        for s0 in (range(len(flat)) if last is None else [len(flat)]):
            seq = [s0]
            used = np.zeros(len(row), dtype=bool)
            if last is None:
                used[item[s0]] = True
            total = 0.0
            while not used.all():
                g = np.where(used[item], -np.inf, G[seq[-1], : len(flat)])
                j = int(np.argmax(g))
                total += float(g[j])
                seq.append(j)
                used[item[j]] = True
            if total > best_total + 1e-9:
                best_total, best_seq = total, seq
        out = [pool[k] for k in best_seq]
        return out[1:] if last is not None else out

    def _slide_left(self, o: int, x_box: float, y: float, halos: list[np.ndarray]) -> float:
        """Where pose ``o`` on base ``y`` comes to rest sliding left towards ``halos``.

        It starts right of every halo in its band (a valid start), slides until contact or the
        left edge, and never ends right of its box position ``x_box`` (always allowed).
        """
        c = self.cat
        h = c.orients[o].h
        band = [g for g in halos if g[:, 1].min() < y + h and g[:, 1].max() > y]
        if not band:
            return 0.0
        start = max(x_box, max(float(g[:, 0].max()) for g in band) + 1e-3)
        t = slide_distance(c.orients[o].poly + np.array([start, y]), band, (-1.0, 0.0), self.tol)
        self.work.add(COST_SLIDE)
        return min(max(start - t, 0.0), x_box)

    def _nestle_row(self, sheet: Sheet, y: float, height: float, rem: np.ndarray, cfg: PlanConfig,
                    values: np.ndarray) -> None:
        """Fill one irregular row of height ``height`` at base ``y`` (see the module docstring)."""
        c = self.cat
        halos: list[np.ndarray] = []
        for p in sheet.pieces:            # earlier rows' outlines reaching into this band (boxes never do)
            if p.Y + c.o_h[p.orient] > y + 1e-9:
                halos.append(c.orients[p.orient].halo + np.array([p.X, p.Y]))
        last: int | None = None
        x_end = 0.0
        for attempt in range(4):
            cap = c.L - x_end
            placed = None
            for beta in (cfg.stretch if attempt == 0 else cfg.stretch[-2:]):
                _, poses = self.best_row(rem, height, cap * (1.0 + beta), cfg, values)
                if not poses:
                    break
                seq = self._order(poses, last)
                trial, trial_halos, xe = [], list(halos), x_end
                for o in seq:
                    x = self._slide_left(o, xe, y, trial_halos)
                    if x + c.o_w[o] > c.L + 1e-9:
                        trial = None
                        break
                    trial.append(Piece(int(o), float(x), y))
                    trial_halos.append(c.orients[o].halo + np.array([x, y]))
                    xe = max(xe, float(x + c.o_w[o]))      # a piece nestled deep into the one before ends left of it
                if trial is not None:
                    placed = (trial, trial_halos, xe)
                    break
            if placed is None:
                break
            trial, halos, x_end = placed
            sheet.pieces.extend(trial)
            rem[[c.o_part[p.orient] for p in trial]] = False
            last = trial[-1].orient
