"""The Pareto front of two figures and the best variant by one figure."""

from __future__ import annotations

from typing import Any

from ppfab.errors import DesignError

from .figures import FIGURES


def pareto_mask(points: list[tuple[float, float]], better: tuple[str, str]) -> list[bool]:
    """Which points are on the Pareto front: no other point is at least as good in both figures and better
    in one (``better[i]`` is ``"min"`` or ``"max"``).

    >>> pareto_mask([(1, 5), (2, 2), (3, 3), (5, 1)], ("min", "min"))
    [True, True, False, True]
    """
    sign = [1.0 if b == "min" else -1.0 for b in better]
    p = [(sign[0] * x, sign[1] * y) for x, y in points]
    out = []
    for i, (x, y) in enumerate(p):
        dominated = any(a <= x and b <= y and (a < x or b < y) for j, (a, b) in enumerate(p) if j != i)
        out.append(not dominated)
    return out


def best_row(rows: list[dict[str, Any]], figure: str) -> dict[str, Any]:
    """The successful row with the best value of ``figure`` (the first in sweep order among equals)."""
    if figure not in FIGURES:
        raise DesignError("--best", f"unknown figure {figure!r}; give one of {', '.join(FIGURES)}")
    ok = [r for r in rows if r.get("status") == "ok" and r.get(figure) is not None]
    if not ok and figure == "cost":
        raise DesignError("--best", "no successful variant has a cost: the sweep file has no [cost] prices, or a "
                                    "priced quantity is not measured at this sweep's stage (sheets, steel, welds "
                                    "and node types need stage 'nesting')")
    if not ok:
        raise DesignError("--best", f"no successful variant has a value of {figure} (was it measured at this "
                                    f"sweep's stage? {figure} needs stage {FIGURES[figure].stage!r})")
    sign = 1.0 if FIGURES[figure].better == "min" else -1.0
    return min(ok, key=lambda r: (sign * float(r[figure]), r.get("index", 0)))
