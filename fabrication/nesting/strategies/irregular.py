"""``irregular``: true shapes nestled freely.

Panels go in true-shape rows (:mod:`..bands`): pushed together along each row, each finished row
dropped onto the one below.  Long thin parts (strips: beam plates) are stacked instead, each
dropped onto the skyline of the ones below and nestling into them (:mod:`..stack`).  When strips
hold at least :data:`STRIP_SHARE` of the part area only the stacks run, when there are none only
the rows, and in between both on half the budget each.
"""

from __future__ import annotations

from ..bands import BandFiller
from ..registry import Run, strategy
from ..stack import COST_PROFILE as STACK_PROFILE
from ..stack import StackFiller, strip_parts
from .guillotine import bands_floor

STRIP_SHARE = 0.9               # stacks alone when strips hold this share of the part area


def bands(cat, work) -> BandFiller:
    """The true-shape row filler (rows dropped onto each other)."""
    return BandFiller(cat, work, guillotine=False)


def stacks(cat, work) -> StackFiller:
    """The strip stacker."""
    return StackFiller(cat, work)


def stacks_floor(cat) -> float:
    """Work units of a first solution of strip stacks, estimated."""
    return STACK_PROFILE * len(cat.orients) + 4000.0 * cat.n_parts


@strategy("irregular", "true shapes nestled: rows pushed together and dropped onto each other; "
                       "long thin plates stacked bend into bend", rank=2)
def irregular(cat, params) -> list[Run]:
    frac = float(cat.part_area[strip_parts(cat)].sum() / cat.part_area.sum())
    if frac <= 0.0:
        return [Run(bands, "irregular", 1.0, bands_floor)]
    if frac >= STRIP_SHARE:
        return [Run(stacks, "irregular", 1.0, stacks_floor)]
    return [Run(bands, "irregular", 0.5, bands_floor), Run(stacks, "irregular", 0.5, stacks_floor)]
