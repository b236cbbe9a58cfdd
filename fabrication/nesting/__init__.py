"""Nesting flat parts (glass panels, beam plates) on stock sheets.

>>> from fabrication.nesting import NestingParams, nest, verify_nesting   # doctest: +SKIP

:func:`nest` returns a :class:`Nesting` (placements with unique nest tags ``S03-017``, sheets used,
utilisation, a lower bound of the sheets from the parts grown by half the spacing); :func:`verify_nesting`
re-checks any nesting with shapely and raises :class:`~ppfab.errors.NestingError` naming the part at fault.
"""

from .budget import UNITS_PER_SECOND
from .engine import nest, work_budget
from .params import NestingParams
from .registry import STRATEGIES, get_strategy, strategy
from .result import Nesting, lower_bound, placed_outline, verify_nesting

__all__ = ["NestingParams", "Nesting", "nest", "verify_nesting", "placed_outline", "lower_bound", "UNITS_PER_SECOND",
           "work_budget", "STRATEGIES", "get_strategy", "strategy"]
