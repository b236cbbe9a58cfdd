"""``auto``: the other strategies, each on a share of the budget; fewer sheets wins, a tie goes to the
one easier to cut (rectangles, then guillotine, then irregular).

The runs go irregular, guillotine, rectangles; a later run whose share cannot pay its cheapest first
solution (large part counts on a small budget) is left out, so the budget holds at every size.
"""

from __future__ import annotations

from ..registry import Run, strategy
from .guillotine import all_convex, guillotine
from .irregular import irregular
from .rectangles import rectangles

SHARES = {"rectangles": 0.2, "guillotine": 0.3, "irregular": 0.5}


@strategy("auto", "rectangles, guillotine and irregular on shares of the budget; fewest sheets wins, "
                  "ties go to the easier cut", rank=3)
def auto(cat, params) -> list[Run]:
    parts = {"irregular": irregular(cat, params)}
    if all_convex(cat):
        parts["guillotine"] = guillotine(cat, params)
    parts["rectangles"] = rectangles(cat, params)
    total = sum(SHARES[k] for k in parts)
    return [Run(r.make, r.mode, r.share * SHARES[k] / total, r.floor) for k, runs in parts.items() for r in runs]
