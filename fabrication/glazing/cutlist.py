"""The glazing strips cut from stock bars: first-fit decreasing, one saw kerf per cut.

A stock bar's ends are not square or clean as delivered: ``a`` mm (``[glazing] bar_end_allowance``, default
10 mm) are squared off each end, so the strips lie on ``[a, B − a]`` of a bar of length ``B``.  Lengths ``ℓ_i``
(mm) go onto the usable length ``B' = B − 2a``: sorted longest first, each onto the first bar whose used length
``u`` still holds it (``u + ℓ_i ≤ B'``, ``u`` counting a kerf after every piece), else onto a new bar; a strip
starts at ``a + u``.  First-fit decreasing uses at most ``11/9 · OPT + 6/9`` bars (Dósa 2007); the lower bound
reported is ``⌈Σ(ℓ_i + k) / (B' + k)⌉``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class BarCut:
    """Where one strip is cut: bar (0-based), start along the bar (mm), length (mm), nest tag ``F<bar>-<k>``."""

    part_id: str
    bar: int
    start: float
    length: float
    nest_tag: str


def cut_bars(lengths: dict[str, float], bar_length: float, kerf: float,
             end_allowance: float = 0.0) -> tuple[list[BarCut], int]:
    """``(cuts in part order, lower bound on the bars)``; the strips lie ``end_allowance`` clear of both bar ends
    (starts measured from the bar's end as delivered); a strip longer than the usable length raises
    ``ValueError``."""
    usable = bar_length - 2.0 * end_allowance
    too_long = [p for p, length in lengths.items() if length > usable + 1e-9]
    if too_long:
        raise ValueError(f"{len(too_long)} glazing strip(s) are longer than the {usable:g} mm a {bar_length:g} mm "
                         f"bar gives with {end_allowance:g} mm squared off each end: {', '.join(too_long[:5])}")
    bar_length = usable
    order = sorted(lengths, key=lambda p: (-lengths[p], p))
    used: list[float] = []
    place: dict[str, tuple[int, float]] = {}
    for p in order:
        length = lengths[p]
        for b, u in enumerate(used):
            if u + length <= bar_length + 1e-9:
                place[p] = (b, u)
                used[b] = u + length + kerf
                break
        else:
            place[p] = (len(used), 0.0)
            used.append(length + kerf)
    width = max(2, len(str(len(used))))
    count: dict[int, int] = {}
    cuts = []
    for p in lengths:
        b, start = place[p]
        k = count.get(b, 0) + 1
        count[b] = k
        cuts.append(BarCut(p, b, end_allowance + start, lengths[p], f"F{b + 1:0{width}d}-{k:02d}"))
    bound = math.ceil(sum(v + kerf for v in lengths.values()) / (bar_length + kerf)) if lengths else 0
    return cuts, bound
