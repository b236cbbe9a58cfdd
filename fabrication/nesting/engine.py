"""``nest(parts, params)``: parts on as few stock sheets as the search finds within its budget.

Modes (``NestingParams.mode``):

* ``guillotine`` — bounding boxes in rows across the sheet (:mod:`.rows`): every cut runs
  edge to edge (rows, then parts within a row, then the trims of each part), as glass is
  scored and broken.
* ``irregular`` — the same rows, but the outlines nestle: neighbours are turned (e.g. 180°)
  and slid together along the row, and the length saved is filled again.  When the parts are
  mostly strips (long and thin, like beam plates), they are stacked instead, each dropped onto
  the ones below and nestling into them (:mod:`.stack`); see :func:`strategies`.
* ``auto`` — both, each with its share of the budget; fewer sheets wins, a tie goes to
  guillotine (cheaper to cut).

Both run a greedy first solution and then ruin and recreate (:mod:`.search`).  The budget
is counted in deterministic work units (``time_budget`` × :data:`UNITS_PER_SECOND`), so a
result depends on the parts, the parameters and the seed only.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..flatpart import FlatPart, Placement
from .catalog import Catalog, build_catalog
from .params import NestingParams
from .result import Nesting
from .rows import Sheet, SheetFiller, Work
from .search import fill_all, improve
from .stack import StackFiller, strip_parts

UNITS_PER_SECOND = 215_000.0    # work units per second of budget (measured on a 2-core reference machine)
STRIP_SHARE = 0.9               # irregular mode stacks strips alone when they hold this share of the part area


def _filler(cat: Catalog, kind: str, work: Work):
    if kind in ("bands", "bands_guillotine"):
        from .bands import BandFiller

        return BandFiller(cat, work, guillotine=kind == "bands_guillotine")
    return StackFiller(cat, work) if kind == "stack" else SheetFiller(cat, kind == "rows", work)


def _solve(cat: Catalog, kind: str, units: float, seed: int, stream: int, lb: int) -> tuple[list[Sheet], Work, list]:
    work = Work()
    filler = _filler(cat, kind, work)
    sheets = fill_all(filler, np.ones(cat.n_parts, dtype=bool), filler.initial_config(), None)
    history = [(work.units, len(sheets))]
    rng = np.random.default_rng([seed, stream])
    sheets = improve(filler, sheets, units, rng, history=history, target=lb)
    return sheets, work, history


def strategies(cat: Catalog, mode: str) -> list[tuple[str, str, float]]:
    """The sheet fillers a mode runs: ``(filler, reported mode, share of the budget)``.

    ``guillotine`` runs the box rows; ``irregular`` runs the nestled rows when no part is a strip,
    the strip stacks (:mod:`.stack`) when strips hold at least :data:`STRIP_SHARE` of the part
    area, and both (half the budget each) in between; ``auto`` runs guillotine on a quarter of
    the budget and irregular on the rest.
    """
    frac = float(cat.part_area[strip_parts(cat)].sum() / cat.part_area.sum())
    if frac <= 0.0:
        irregular = [("rows", "irregular", 1.0)]
    elif frac >= STRIP_SHARE:
        irregular = [("stack", "irregular", 1.0)]
    else:
        irregular = [("rows", "irregular", 0.5), ("stack", "irregular", 0.5)]
    if mode == "guillotine":
        return [("guillotine", "guillotine", 1.0)]
    if mode == "irregular":
        return irregular
    return [("guillotine", "guillotine", 0.25)] + [(k, m, 0.75 * f) for k, m, f in irregular]


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


def nest(parts: list[FlatPart], params: NestingParams | None = None) -> Nesting:
    """Place every part on stock sheets (see the module docstring).

    Parameters
    ----------
    parts : flat parts (outlines ``(k, 2)`` counter-clockwise, mm); ids must be unique
    params : :class:`NestingParams` (defaults when ``None``)

    Returns
    -------
    Nesting : one placement per part (in the order given), the number of sheets, the
        utilisation (part area / area of the sheets used) and the area lower bound

    Raises
    ------
    NestingError : a part fits the usable area in none of its allowed poses (named, with its
        size), a duplicate part id, or a malformed outline
    """
    p = params or NestingParams()
    t0 = time.perf_counter()
    sheet_area = float(p.sheet[0]) * float(p.sheet[1])
    if not parts:
        return Nesting([], 0, 0.0, 0, p.mode if p.mode != "auto" else "guillotine",
                       (float(p.sheet[0]), float(p.sheet[1])), p.usable())
    cat = build_catalog(parts, p)
    total = float(cat.part_area.sum())
    x0, y0, x1, y1 = p.usable()
    lb_usable = int(math.ceil(total / ((x1 - x0) * (y1 - y0)) - 1e-12))
    budget = float(p.time_budget) * UNITS_PER_SECOND
    best = None
    for stream, (kind, mode, share) in enumerate(strategies(cat, p.mode)):
        sheets, work, history = _solve(cat, kind, share * budget, p.seed, stream, lb_usable)
        if best is None or len(sheets) < len(best[1]):
            best = (mode, sheets, work, history)
    mode, sheets, work, history = best
    placements = _placements(cat, sheets, p)
    fills = sorted((s.area / sheet_area for s in sheets), reverse=True)
    return Nesting(
        placements=placements,
        sheets=len(sheets),
        utilisation=total / (len(sheets) * sheet_area),
        lower_bound=int(math.ceil(total / sheet_area - 1e-12)),
        mode=mode,
        sheet_size=(float(p.sheet[0]), float(p.sheet[1])),
        usable=p.usable(),
        sheet_fill=tuple(fills),
        work_units=work.units,
        seconds=time.perf_counter() - t0,
        history=tuple(history),
    )
