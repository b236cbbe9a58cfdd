"""Filling one sheet with rows of bounding rectangles: a knapsack per row, a search over row heights.

A sheet is filled bottom to top with rows (the first-stage cuts of a guillotine plan run
along the sheet's length).  For a row of height at most ``Hc`` every remaining part takes
its narrowest pose of height ``<= Hc``; a 0/1 knapsack over the quantised box widths
(capacity = the sheet length) picks the parts of largest total value (Σ area^α); the row's
height is its tallest box.  A sheet tries several first-row heights and stacks further rows
greedily into the height left; the plan of largest total value wins.  Rows are cut across the
sheet, parts across each row, and every part is trimmed inside its box (edge to edge for
convex parts).

Positions are box corners in the planning frame of :mod:`.catalog`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .budget import Work
from .catalog import Catalog

# work units (≈ 1 µs each on the reference machine) charged per operation: see .budget
COST_DP_CALL, COST_DP_ITEM = 66.0, 2.2
COST_SCAN = 0.0094            # per pose scanned for a row's candidates


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


class SheetFiller:
    """Plans and realises sheets for a :class:`~.catalog.Catalog`."""

    def __init__(self, cat: Catalog, work: Work):
        self.cat = cat
        self.work = work
        self.order = np.lexsort((-cat.o_h, cat.o_w, cat.o_part))
        self.o_part_s, self.o_w_s, self.o_h_s = cat.o_part[self.order], cat.o_w[self.order], cat.o_h[self.order]
        work.add(COST_SCAN * 10 * len(self.order))

    # -- knapsack rows ------------------------------------------------------------------------
    def _row_poses(self, rem: np.ndarray, hc: float, cap: float) -> np.ndarray:
        """The narrowest pose of height <= hc of every remaining part (pose indices).

        Poses are kept sorted by (part, width, −height) once, so a call is one pass over them.
        """
        srt = self.order
        fit = rem[self.o_part_s] & (self.o_h_s <= hc + 1e-9) & (self.o_w_s <= cap + 1e-9)
        self.work.add(COST_SCAN * len(srt))
        idx = np.flatnonzero(fit)
        if len(idx) == 0:
            return idx
        parts = self.o_part_s[idx]
        first = np.r_[True, parts[1:] != parts[:-1]]
        return srt[idx[first]]

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

    @staticmethod
    def cost_key(cfg: PlanConfig) -> tuple:
        """Configurations compare by cost in this order (larger = dearer)."""
        return (cfg.n_heights, cfg.top_k)

    def cheaper(self, cfg: PlanConfig) -> PlanConfig | None:
        """The next configuration down the cost ladder (fewer first-row heights, smaller knapsacks), or ``None``."""
        for n, k in ((6, 48), (2, 32)):
            if n < cfg.n_heights:
                return PlanConfig(alpha=cfg.alpha, n_heights=n, top_k=min(k, cfg.top_k), quantum=cfg.quantum,
                                  jitter=cfg.jitter)
        return None

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
            rem[c.o_part[row]] = False
            x = 0.0
            for o in row:
                sheet.pieces.append(Piece(int(o), x, y))
                x += float(c.o_w[o])
            y += height
        sheet.area = float(c.part_area[[c.o_part[p.orient] for p in sheet.pieces]].sum())
        return sheet
