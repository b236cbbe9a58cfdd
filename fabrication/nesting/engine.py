"""``nest(parts, params)``: parts on as few stock sheets as the search finds within its budget.

``NestingParams.mode`` names a strategy of :mod:`.registry` (``rectangles``, ``guillotine``,
``irregular``, ``auto``; one module each in :mod:`.strategies`).  A strategy lists sheet-filler
runs with their shares of the budget; each run makes a greedy first solution and then ruins and
recreates sheets (:mod:`.search`).  The result with the fewest sheets is kept (a tie goes to the
strategy easier to cut).

The budget is a work count (:mod:`.budget`): ``time_budget`` × :data:`UNITS_PER_SECOND` units
cover the whole stage — the catalog of poses, every run, the placements and the check by
:func:`~.result.verify_nesting` (reserved up front) — and each run gets its share of what is left
when it starts.  A result depends on the parts, the parameters, the seed and that count only.
"""

from __future__ import annotations

import time
from typing import Callable

import numpy as np

from ppfab.errors import NestingError

from ..flatpart import FlatPart, Placement
from .budget import COST_PART, COST_POSE, COST_VERIFY_PART, UNITS_PER_SECOND, Work
from .catalog import Catalog, build_catalog
from .params import NestingParams
from .registry import Run, get_strategy, rank_of
from .result import Nesting, lower_bound
from .rows import Sheet
from .search import first_solution, improve


def _solve(cat: Catalog, run: Run, units: float, seed: int, stream: int, lb: int,
           on_add: Callable[[float], None] | None = None) -> tuple[list[Sheet], Work, list]:
    """One run: the filler's greedy sheets, improved until ``units`` are spent (or the bound is met)."""
    work = Work(on_add=on_add)
    filler = run.make(cat, work)
    sheets, reached = first_solution(filler, np.ones(cat.n_parts, dtype=bool), filler.initial_config(), None, units)
    history = [(work.units, len(sheets))]
    rng = np.random.default_rng([seed, stream])
    sheets = improve(filler, sheets, units, rng, history=history, target=lb, cap=reached)
    return sheets, work, history


def _placements(cat: Catalog, sheets: list[Sheet], params: NestingParams) -> list[Placement]:
    x0, y0, _, _ = params.usable()
    order = sorted(range(len(sheets)), key=lambda i: (-sheets[i].area, min(cat.o_part[p.orient] for p in sheets[i].pieces)))
    wsheet = max(2, len(str(len(sheets))))
    out: dict[int, Placement] = {}
    for rank, i in enumerate(order):
        pieces = sorted(sheets[i].pieces, key=lambda p: (round(p.Y, 6), round(p.X, 6), p.orient))
        wpart = max(3, len(str(len(pieces))))
        for k, pc in enumerate(pieces):
            o = cat.orients[pc.orient]
            part = cat.parts[o.part]
            out[o.part] = Placement(part_id=part.part_id, sheet=rank, x=float(x0 + pc.X + o.shift[0]),
                                    y=float(y0 + pc.Y + o.shift[1]), rotation_deg=float(o.rotation),
                                    mirrored=bool(o.mirrored), nest_tag=f"{params.tag_prefix}{rank + 1:0{wsheet}d}-{k + 1:0{wpart}d}")
    return [out[i] for i in range(cat.n_parts)]


def work_budget(params: NestingParams) -> float:
    """The work count ``time_budget`` buys, units."""
    return float(params.time_budget) * UNITS_PER_SECOND


def nest(parts: list[FlatPart], params: NestingParams | None = None,
         on_progress: Callable[[float, float, int | None], None] | None = None) -> Nesting:
    """Place every part on stock sheets (see the module docstring).

    Parameters
    ----------
    parts : flat parts (outlines ``(k, 2)`` counter-clockwise, mm); ids must be unique
    params : :class:`NestingParams` (defaults when ``None``)
    on_progress : called as ``on_progress(units spent, units of the budget, fewest sheets so far or None)``
        about every 1/200 of the budget (it only watches: the layout does not depend on it)

    Returns
    -------
    Nesting : one placement per part (in the order given), the number of sheets, the
        utilisation (part area / area of the sheets used), a lower bound of the sheets
        (:func:`~.result.lower_bound`), and the work count spent (``work_units``) out of the budget
        (``work_budget``)

    Raises
    ------
    NestingError : a part fits the usable area in none of its allowed poses (named, with its
        size), a duplicate part id, or a malformed outline
    """
    p = params or NestingParams()
    t0 = time.perf_counter()
    sheet_area = float(p.sheet[0]) * float(p.sheet[1])
    budget = work_budget(p)
    strategy = get_strategy(p.mode)
    if not parts:
        return Nesting([], 0, 0.0, 0, strategy.name if strategy.name != "auto" else "rectangles",
                       (float(p.sheet[0]), float(p.sheet[1])), p.usable(), work_budget=budget, seed=p.seed)
    fixed = Work()
    cat = build_catalog(parts, p)
    fixed.add(COST_PART * cat.n_parts + COST_POSE * len(cat.orients) + COST_VERIFY_PART * cat.n_parts)
    total = float(cat.part_area.sum())
    lb = lower_bound(parts, p)
    runs = strategy.runs(cat, p)
    spent = fixed.units
    best = None
    step = budget / 200.0
    shown = [spent]

    def meter(units: float) -> None:
        if on_progress is not None and spent + units >= shown[0] + step:
            shown[0] = spent + units
            on_progress(min(shown[0], budget), budget, None if best is None else len(best[2]))

    for k, run in enumerate(runs):
        share = run.share / sum(r.share for r in runs[k:])
        units = share * max(budget - spent, 0.0)
        if best is not None and run.floor is not None and run.floor(cat) > units:
            continue                    # cannot pay even its cheapest first solution: left out
        sheets, work, history = _solve(cat, run, units, p.seed, k, lb, meter if on_progress else None)
        spent += work.units
        key = (len(sheets), rank_of(run.mode))
        if best is None or key < best[0]:
            best = (key, run.mode, sheets, history)
    if best is None:                     # every strategy has at least one run, and the first always runs
        raise NestingError(f"nesting strategy {strategy.name!r} made no run (internal error)")
    _, mode, sheets, history = best
    if on_progress is not None:
        on_progress(budget, budget, len(sheets))
    placements = _placements(cat, sheets, p)
    fills = sorted((s.area / sheet_area for s in sheets), reverse=True)
    return Nesting(
        placements=placements,
        sheets=len(sheets),
        utilisation=total / (len(sheets) * sheet_area),
        lower_bound=lb,
        mode=mode,
        sheet_size=(float(p.sheet[0]), float(p.sheet[1])),
        usable=p.usable(),
        sheet_fill=tuple(fills),
        work_units=spent,
        work_budget=budget,
        seed=p.seed,
        seconds=time.perf_counter() - t0,
        history=tuple(history),
    )
