"""The table of nesting strategies a design file's ``mode`` selects from.

A strategy says which sheet fillers to run on a set of parts and with what share of the work
budget (:class:`Run`); :func:`~.engine.nest` runs them and keeps the result with the fewest
sheets (a tie goes to the strategy of lower ``rank``: easier to cut).  Modules in
:mod:`fabrication.nesting.strategies` register theirs with :func:`strategy`; the package imports
every module, so a new strategy is one new file.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Protocol

import numpy as np

from ppfab.registry import Registry


class Filler(Protocol):
    """What the search (:mod:`.search`) needs of a sheet filler."""

    cat: Any
    work: Any

    def fill_sheet(self, rem: np.ndarray, cfg: Any, values: np.ndarray, rng: np.random.Generator | None) -> Any: ...
    def part_values(self, cfg: Any, rng: np.random.Generator | None) -> np.ndarray: ...
    def initial_config(self) -> Any: ...
    def cheaper(self, cfg: Any) -> Any | None: ...
    def cost_key(self, cfg: Any) -> tuple: ...
    def random_config(self, rng: np.random.Generator) -> Any: ...


@dataclass(frozen=True)
class Run:
    """One filler run of a strategy: ``make(catalog, work) -> filler``, the mode it reports, its budget share.

    ``floor(catalog)`` estimates the work units of the filler's cheapest first solution: a run that is
    not the first is skipped when its share of the budget cannot pay that.
    """

    make: Callable[[Any, Any], Filler]
    mode: str
    share: float
    floor: Callable[[Any], float] | None = None


@dataclass(frozen=True)
class Strategy:
    """One entry of :data:`STRATEGIES`: ``runs(catalog, params) -> [Run]``; ``rank`` breaks ties (lower wins)."""

    name: str
    summary: str
    rank: int
    runs: Callable[[Any, Any], list[Run]]


_TABLE: Registry[Strategy] = Registry("nesting mode", "fabrication.nesting.strategies")
STRATEGIES: dict[str, Strategy] = _TABLE.entries
"""The strategies registered so far (:func:`load_all` imports them all)."""


def strategy(name: str, summary: str, rank: int) -> Callable:
    """Decorator registering ``runs(catalog, params) -> list[Run]`` as strategy ``name``."""
    def register(fn: Callable[[Any, Any], list[Run]]) -> Callable[[Any, Any], list[Run]]:
        _TABLE.add(name, Strategy(name, summary, rank, fn))
        return fn
    return register


def load_all() -> dict[str, Strategy]:
    """Import every strategy module (once) and return the registry."""
    return _TABLE.load()


def get_strategy(name: str, key: str = "nesting.mode") -> Strategy:
    """Look a strategy up by name; an unknown name lists the valid ones."""
    return _TABLE.get(name, key)


def rank_of(mode: str) -> int:
    """Tie-break rank of a reported mode (unknown modes last)."""
    s = STRATEGIES.get(mode)
    return s.rank if s is not None else 1_000
