"""The result of nesting and its independent check (shapely, exact outlines)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ppfab.errors import NestingError
from ppfab.metrics import polygon_area

from ..flatpart import FlatPart, Placement, place_points
from .params import NestingParams


@dataclass(frozen=True)
class Nesting:
    """Placements of all parts on stock sheets.

    Attributes
    ----------
    placements : one per part, in the order of the parts given
    sheets : number of sheets used
    utilisation : part area / area of the sheets used (whole sheets)
    lower_bound : no layout uses fewer sheets (:func:`lower_bound`: the parts grown by half the spacing)
    mode : the strategy that produced this result (``"rectangles"``, ``"guillotine"`` or ``"irregular"``)
    sheet_fill : (sheets,) part area / sheet area per sheet
    work_units : the work count spent (:mod:`.budget`): with the same parts, parameters and seed, a
        run given this count (``work_budget``) makes the same layout on any machine
    work_budget : the work count the budget allowed (``time_budget`` × units per second)
    seed : the search seed
    seconds : wall time of :func:`~.engine.nest` (informative; the layout never depends on it)
    history : ``(work units, sheets)`` along the search of the winning run
    """

    placements: list[Placement]
    sheets: int
    utilisation: float
    lower_bound: int
    mode: str
    sheet_size: tuple[float, float]
    usable: tuple[float, float, float, float]
    sheet_fill: tuple[float, ...] = ()
    work_units: float = 0.0
    work_budget: float = 0.0
    seed: int = 0
    seconds: float = 0.0
    history: tuple = field(default=(), repr=False)

    def by_sheet(self) -> list[list[Placement]]:
        """Placements grouped per sheet (sheet order), each sorted by nest tag."""
        out: list[list[Placement]] = [[] for _ in range(self.sheets)]
        for p in self.placements:
            out[p.sheet].append(p)
        return [sorted(s, key=lambda p: p.nest_tag) for s in out]

    def summary(self) -> dict:
        return {"sheets": self.sheets, "utilisation": round(self.utilisation, 4), "lower_bound": self.lower_bound,
                "mode": self.mode, "sheet": list(self.sheet_size), "seconds": round(self.seconds, 2),
                "work_units": int(round(self.work_units)), "work_budget": int(round(self.work_budget)),
                "seed": self.seed}


def placed_outline(part: FlatPart, placement: Placement) -> np.ndarray:
    """The part's outline in sheet coordinates, ``(k, 2)`` mm."""
    return place_points(np.asarray(part.outline, dtype=float), placement)


def _allowed_rotation(part: FlatPart, rot: float, params: NestingParams) -> bool:
    from .catalog import rotation_policy

    free, allowed = rotation_policy(part, params)
    return free or any(abs(((rot - a) + 180.0) % 360.0 - 180.0) < 1e-6 for a in allowed)


def verify_nesting(parts: list[FlatPart], nesting: Nesting, params: NestingParams, tol: float = 1e-6) -> None:
    """Check a nesting independently of how it was made; raise :class:`NestingError` naming the part.

    Checks: every part placed exactly once and nothing else placed; sheet indices in range;
    nest tags unique; rotation allowed and mirroring only where the part allows it; every
    outline inside the usable area (after trim) within ``tol``; every two outlines on a sheet at
    least ``spacing − tol`` apart (shapely distances, exact for polygons).
    """
    from shapely import STRtree
    from shapely.geometry import Polygon

    by_id = {p.part_id: p for p in parts}
    seen: dict[str, int] = {}
    tags: dict[str, str] = {}
    for pl in nesting.placements:
        if pl.part_id not in by_id:
            raise NestingError(f"placement of unknown part {pl.part_id}")
        seen[pl.part_id] = seen.get(pl.part_id, 0) + 1
        if pl.nest_tag in tags:
            raise NestingError(f"nest tag {pl.nest_tag} used by {tags[pl.nest_tag]} and {pl.part_id}")
        tags[pl.nest_tag] = pl.part_id
        if not 0 <= pl.sheet < nesting.sheets:
            raise NestingError(f"part {pl.part_id} is on sheet {pl.sheet}, outside 0..{nesting.sheets - 1}")
        part = by_id[pl.part_id]
        if not _allowed_rotation(part, pl.rotation_deg, params):
            raise NestingError(f"part {pl.part_id} is rotated by {pl.rotation_deg:g}°, not an allowed rotation")
        if pl.mirrored and not part.mirror_allowed:
            raise NestingError(f"part {pl.part_id} is placed mirrored but its make-up does not allow it")
    twice = [k for k, n in seen.items() if n > 1]
    if twice:
        raise NestingError(f"part {twice[0]} is placed {seen[twice[0]]} times" +
                           (f" (and {len(twice) - 1} more parts)" if len(twice) > 1 else ""))
    missing = [p.part_id for p in parts if p.part_id not in seen]
    if missing:
        raise NestingError(f"part {missing[0]} is not placed" + (f" (and {len(missing) - 1} more)" if len(missing) > 1 else ""))
    x0, y0, x1, y1 = params.usable()
    s = float(params.spacing)
    for sheet, group in enumerate(nesting.by_sheet()):
        polys = []
        for pl in group:
            pts = placed_outline(by_id[pl.part_id], pl)
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            out = max(x0 - lo[0], y0 - lo[1], hi[0] - x1, hi[1] - y1)
            if out > tol:
                raise NestingError(f"part {pl.part_id} ({pl.nest_tag}) leaves the usable area of sheet {sheet + 1} "
                                   f"by {out:.4g} mm")
            polys.append(Polygon(pts))
        if s <= 0 and len(polys) < 2:
            continue
        tree = STRtree(polys)
        left, right = tree.query(polys, predicate="dwithin", distance=max(s - tol, 0.0))
        for a, b in zip(left.tolist(), right.tolist()):
            if a >= b:
                continue
            d = polys[a].distance(polys[b])
            if d < s - tol or (s <= 0 and polys[a].intersection(polys[b]).area > tol):
                raise NestingError(f"parts {group[a].part_id} and {group[b].part_id} on sheet {sheet + 1} are "
                                   f"{d:.4g} mm apart, spacing is {s:g} mm")


def grown_areas(outlines: list[np.ndarray], r: float) -> np.ndarray:
    """``(n,)`` areas of the polygons ``outlines`` (each ``(k, 2)``) grown by ``r ≥ 0`` (the Minkowski sum with a
    disk of radius ``r``): Steiner's formula ``A + r·P + π r²`` for the convex ones, batched by vertex count;
    shapely's buffer for the others, whose round corners are chords of their arcs, so a value never exceeds the
    true grown area."""
    out = np.zeros(len(outlines))
    by_k: dict[int, list[int]] = {}
    for i, q in enumerate(outlines):
        by_k.setdefault(len(q), []).append(i)
    for idx in by_k.values():
        q = np.asarray([outlines[i] for i in idx], dtype=float)                 # (m, k, 2)
        area = np.abs(polygon_area(q))
        if r <= 0:
            out[idx] = area
            continue
        e_in, e_out = q - np.roll(q, 1, axis=1), np.roll(q, -1, axis=1) - q
        turn = e_in[..., 0] * e_out[..., 1] - e_in[..., 1] * e_out[..., 0]
        convex = np.all(turn >= 0, axis=1) | np.all(turn <= 0, axis=1)
        out[idx] = area + r * np.linalg.norm(e_out, axis=-1).sum(axis=1) + math.pi * r * r
        if not convex.all():
            from shapely.geometry import Polygon

            for j in np.flatnonzero(~convex):
                out[idx[j]] = Polygon(q[j]).buffer(r, quad_segs=16).area
    return out


def grown_area(outline: np.ndarray, r: float) -> float:
    """Area of one polygon ``(k, 2)`` grown by ``r`` (:func:`grown_areas`)."""
    return float(grown_areas([outline], r)[0])


def lower_bound(parts: list[FlatPart], params: NestingParams) -> int:
    """No layout of ``parts`` uses fewer sheets: ``ceil(Σ grown area / ((W + s)(H + s)))``.

    Parts at least the spacing ``s`` apart stay disjoint when each grows by ``s/2`` (:func:`grown_areas`), and a
    part inside the usable ``W × H`` of a sheet (after the trim) grows into that rectangle grown by ``s/2`` on
    every side; so the grown parts of one sheet fit disjointly in ``(W + s)(H + s)``.  With ``s = 0`` and no
    trim this is the plain area bound ``ceil(Σ area / sheet area)``; spacing and trim only raise it.
    """
    if not parts:
        return 0
    s = float(params.spacing)
    x0, y0, x1, y1 = params.usable()
    total = float(grown_areas([p.outline for p in parts], 0.5 * s).sum())
    return int(math.ceil(total / ((x1 - x0 + s) * (y1 - y0 + s)) - 1e-9))


__all__ = ["Nesting", "verify_nesting", "placed_outline", "lower_bound", "grown_area", "grown_areas"]
