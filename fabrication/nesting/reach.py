"""Look-ahead for filling a length: which totals a few parts can reach (a subset sum on a grid).

A row that ends 300 mm short of the sheet's edge wastes that strip when no remaining part is
narrower; a sheet whose last row leaves 400 mm wastes it when no part is that low.  The fillers
therefore ask, for a length ``R`` still free, how much of it ``k`` or fewer parts can fill:
``fill(R) = max {Σ_{i∈S} v_i ≤ R : |S| ≤ k}`` over the parts' lengths ``v`` (rounded up to a grid
of ``q`` mm, so the answer is never optimistic by more than the rounding of ``R``).  Parts are
treated as available in any number (a look-ahead, not a plan).
"""

from __future__ import annotations

import numpy as np


def fillable(values: np.ndarray, cap: float, q: float, most: int) -> np.ndarray:
    """``best[c]`` = the largest total of at most ``most`` of ``values`` that is ``<= c q``, for ``c = 0..cap/q``.

    Parameters
    ----------
    values : (n,) lengths > 0, mm (repeats allowed; each may be used any number of times)
    cap : largest length asked about, mm; q : grid, mm; most : number of parts at most

    Returns
    -------
    best : (C + 1,) float, mm (``C = floor(cap / q)``); ``best[c] <= c q``
    """
    n = int(np.floor(cap / q + 1e-9))
    v = np.unique(np.ceil(np.asarray(values, dtype=float) / q - 1e-9).astype(np.int64))
    v = v[(v > 0) & (v <= n)]
    mask = (1 << (n + 1)) - 1
    reach = 1                                   # bit c set: total c q reachable
    layer = 1
    for _ in range(most):
        nxt = 0
        for s in v.tolist():
            nxt |= layer << s
        nxt &= mask
        layer = nxt & ~reach
        reach |= nxt
        if not layer:
            break
    bits = np.frombuffer(reach.to_bytes((n + 8) // 8, "little"), dtype=np.uint8)
    on = np.unpackbits(bits, bitorder="little")[: n + 1].astype(bool)
    idx = np.where(on, np.arange(n + 1), -1)
    return np.maximum.accumulate(idx).astype(float) * q
