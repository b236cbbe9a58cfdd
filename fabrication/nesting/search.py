"""Sheet-level search: a greedy first solution, then ruin and recreate within a work budget.

The first solution fills sheet after sheet, each as full as the sheet filler can make it
(rows of :mod:`.rows` or the strip stacks of :mod:`.stack`: both offer ``fill_sheet``,
``part_values`` and ``random_config``).
Then, repeatedly, the emptiest sheet and one to three others (drawn with a preference for
sheets with room) are emptied and their parts
re-planned with randomised filler knobs (for rows: value exponent, perturbed values, row
heights tried; for stacks: score bonus and jitter, first part); the new sheets replace the old ones when
they are fewer, or as many with a larger sum of squared fills (which drains the emptiest
sheet until it disappears).  Randomness comes from one seeded generator and the loop stops
on a count of work units, so a run depends only on the seed and the budget, never on the
machine's speed.
"""

from __future__ import annotations

import numpy as np

from ppfab.errors import NestingError

from typing import Any

from .catalog import Catalog
from .registry import Filler
from .rows import Sheet


GREEDY_SHARE = 0.6     # a first solution projected to cost more than this share of its budget goes cheaper


def fill_all(filler: Filler, rem: np.ndarray, cfg: Any,
             rng: np.random.Generator | None, budget_units: float | None = None) -> list[Sheet]:
    """:func:`first_solution` without the configuration reached."""
    return first_solution(filler, rem, cfg, rng, budget_units)[0]


def first_solution(filler: Filler, rem: np.ndarray, cfg: Any,
                   rng: np.random.Generator | None, budget_units: float | None = None) -> tuple[list[Sheet], Any]:
    """Fill sheets one after another until every part in ``rem`` is placed (``rem`` is consumed).

    With ``budget_units`` (a first solution): after each sheet the work per part placed so far
    projects the cost of the rest; while it would pass :data:`GREEDY_SHARE` of the budget the filler's
    next cheaper configuration (``filler.cheaper``) fills the following sheets — counted in work
    units, so the switch happens at the same sheet on any machine.
    """
    cat = filler.cat
    values = filler.part_values(cfg, rng)
    sheets: list[Sheet] = []
    n0, u0 = int(rem.sum()), filler.work.units
    while rem.any():
        if budget_units is not None and sheets:
            done = n0 - int(rem.sum())
            projected = filler.work.units + (filler.work.units - u0) / max(done, 1) * int(rem.sum())
            if projected > GREEDY_SHARE * budget_units:
                nxt = filler.cheaper(cfg)
                if nxt is not None:
                    cfg = nxt
                    values = filler.part_values(cfg, rng)
                    n0, u0 = int(rem.sum()), filler.work.units
        before = int(rem.sum())
        sheet = filler.fill_sheet(rem, cfg, values, rng)
        if sheet is None:
            left = [cat.parts[p].part_id for p in np.flatnonzero(rem)[:5]]
            raise NestingError(f"parts {', '.join(left)} could not be placed on an empty sheet")
        if int(rem.sum()) >= before or not sheet.pieces:
            raise NestingError("nesting made no progress on an empty sheet (internal error)")
        sheets.append(sheet)
    return sheets, cfg


def _score(sheets: list[Sheet], norm: float) -> float:
    return float(sum((s.area / norm) ** 2 for s in sheets))


def improve(filler: Filler, sheets: list[Sheet], budget_units: float, rng: np.random.Generator,
            history: list[tuple[float, int]] | None = None, target: int = 1, cap: Any = None) -> list[Sheet]:
    """Ruin and recreate until ``filler.work.units`` reaches ``budget_units`` or the sheets reach ``target``.

    A step is not begun when the mean cost of the steps so far would take the count past the
    budget; with ``cap`` (the configuration the first solution ended on) the random knobs of a step
    are stepped down the filler's cost ladder to no more than it.
    """
    cat: Catalog = filler.cat
    norm = cat.L * cat.H
    sheets = list(sheets)
    steps, start = 0, filler.work.units
    while filler.work.units < budget_units and len(sheets) > max(target, 1):
        if steps and filler.work.units + (filler.work.units - start) / steps > budget_units:
            break
        k = int(min(len(sheets), rng.choice([2, 2, 3, 3, 4])))
        fills = np.array([s.area for s in sheets])
        worst = int(np.argmin(fills))
        others = np.array([i for i in range(len(sheets)) if i != worst])
        room = (1.02 - fills[others] / norm) ** 2
        sel = [worst] + [int(i) for i in rng.choice(others, size=k - 1, replace=False, p=room / room.sum())]
        rem = np.zeros(cat.n_parts, dtype=bool)
        for i in sel:
            for p in sheets[i].pieces:
                rem[cat.o_part[p.orient]] = True
        cfg = filler.random_config(rng)
        if cap is not None:
            while filler.cost_key(cfg) > filler.cost_key(cap):
                lower = filler.cheaper(cfg)
                if lower is None:
                    break
                cfg = lower
        new = fill_all(filler, rem, cfg, rng)
        steps += 1
        old = [sheets[i] for i in sel]
        if len(new) < len(old) or (len(new) == len(old) and _score(new, norm) > _score(old, norm) + 1e-12):
            sheets = [s for i, s in enumerate(sheets) if i not in sel] + new
        if history is not None:
            history.append((filler.work.units, len(sheets)))
    return sheets
