"""The work count: the currency of the nesting budget.

Every step of the nesting (catalog of poses, profiles, knapsacks, candidate evaluations, exact
slides, the final check) charges a fixed number of *work units* for what it does, counted from
the sizes it works on, never from a clock.  A run stops on a count of units, so the same parts,
parameters, seed and work count give the same layout on any machine.  ``time_budget`` seconds
are :data:`UNITS_PER_SECOND` × ``time_budget`` units: the unit costs were measured so that on the
reference machine (2 cores, idle, one nesting at a time) a unit takes about 1 µs at every size,
and the whole nesting stage (catalog, search, placements and :func:`~.result.verify_nesting`)
takes about its budget.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

UNITS_PER_SECOND = 1_000_000.0
"""Work units per second of ``time_budget`` on the reference machine."""

# fixed costs of a nesting, units
COST_PART = 150.0          # catalog: checks, halo, angles of one part
COST_POSE = 18.0           # catalog: one pose (turned outline and halo, box)
COST_VERIFY_PART = 60.0    # verify_nesting and the placements: per part


@dataclass
class Work:
    """Deterministic work counter (see the module docstring)."""

    units: float = 0.0
    on_add: Callable[[float], None] | None = field(default=None, repr=False, compare=False)
    """Called with the units so far after each charge (the progress display); never changes the count."""

    def add(self, n: float) -> None:
        self.units += n
        if self.on_add is not None:
            self.on_add(self.units)
