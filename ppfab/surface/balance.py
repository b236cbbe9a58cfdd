"""Panel sizes held to the spacing by re-seeding: where the seeds and planes of a sections net go.

A quad net has no T-junctions (:class:`ppfab.mesh.QuadMesh` faces share whole edges, and the support
structure follows whole polylines), so a conjugate curve cannot end where its neighbours converge nor a
new one start where they fan apart.  What can be chosen is where each curve and each plane starts.  On a
dense net (several curves and planes per panel) each strip between two neighbouring seeds is made as wide
as its panels need: its narrowest and widest panel inside the outline straddle ``spacing`` (their
geometric mean is ``spacing``), strip after strip from the middle outwards; the planes likewise along the
curves.  A strip whose curves fan apart by a factor ``r`` inside the outline still spans ``r`` — re-seeding
centres that range on the spacing, it cannot narrow it; :func:`ppfab.surface.remesh.remesh` reports the
range reached.

Examples
--------
>>> import numpy as np
>>> L = np.ones((12, 3)) * np.array([0.5, 1.0, 2.0])        # three lanes: edges of 0.5, 1 and 2 per step
>>> t = strip_positions(L, np.ones((12, 3), dtype=bool), 6.0, 1.0)
>>> np.diff(t).tolist()                                       # widths 0.5 … 2 per strip → mean 1 per step
[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0]
"""

from __future__ import annotations

import numpy as np


def strip_positions(lengths: np.ndarray, inside: np.ndarray, start: float, spacing: float) -> np.ndarray:
    """Fractional positions along a dense index at which to place the curves.

    Parameters
    ----------
    lengths : (K, L) float — length of the dense edge ``k → k + 1`` on each of ``L`` lanes (the other
        family's dense lines), mm
    inside : (K, L) bool — the edge lies inside the outline
    start : fractional position of the middle curve (kept)
    spacing : target panel size, mm

    Returns
    -------
    (P,) float — sorted positions in ``[0, K]``, ``start`` among them; each strip's narrowest and widest
    panel over the lanes inside it have the geometric mean ``spacing`` (the last strips at either end stop
    where the dense net ends)
    """
    L = np.asarray(lengths, dtype=float)
    ins = np.asarray(inside, dtype=bool)
    K = L.shape[0]
    right = _march(L, ins, start, spacing)
    left = K - _march(L[::-1], ins[::-1], K - start, spacing)
    return np.concatenate([left[::-1], [start], right])


def _march(L: np.ndarray, ins: np.ndarray, start: float, spacing: float) -> np.ndarray:
    """Positions after ``start`` (exclusive), strip after strip."""
    K = L.shape[0]
    C = np.vstack([np.zeros(L.shape[1]), np.cumsum(L, axis=0)])

    def at(t: float) -> np.ndarray:
        k = min(int(np.floor(t)), K - 1)
        return C[k] + (t - k) * L[k]

    out: list[float] = []
    a = start
    while a < K - 1e-9:
        ca = at(a)
        k0 = min(int(np.floor(a)), K - 1)
        b = int(np.floor(a)) + 1
        while b <= K and _mean_width(C[b] - ca, ins[k0:b]) < spacing:
            b += 1
        if b > K:
            break
        lo, hi = max(a, float(b - 1)), float(b)
        for _ in range(60):                  # bisection: the width is piecewise linear per lane, min·max not
            mid = 0.5 * (lo + hi)
            if _mean_width(at(mid) - ca, ins[k0:b]) >= spacing:
                hi = mid
            else:
                lo = mid
        t = hi
        out.append(t)
        a = t
    return np.array(out)


def _mean_width(w: np.ndarray, ins: np.ndarray) -> float:
    """``sqrt(min · max)`` of the strip widths ``w (L,)`` over the lanes wholly inside (``ins (k, L)``), else
    over the lanes partly inside, else over all."""
    for lanes in (ins.all(axis=0), ins.any(axis=0), np.ones(len(w), dtype=bool)):
        if lanes.any():
            x = w[lanes]
            return float(np.sqrt(max(float(x.min()), 0.0) * float(x.max())))
    return 0.0


def balanced_positions(dense: np.ndarray, inside: np.ndarray, seeds: np.ndarray, planes: np.ndarray,
                       y_mid: float, x_mid: float, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """The seeds (``y`` on the middle section) and planes (``x``) of a balanced sections net.

    Parameters
    ----------
    dense : (P, S, 3) float — the dense net in the plan frame: row ``i`` in plane ``planes[i]``, column
        ``j`` the conjugate curve through ``seeds[j]``
    inside : (P, S) bool — dense vertices inside the outline
    seeds, planes : (S,), (P,) float — increasing
    y_mid, x_mid : the middle section's seed and the middle plane (kept)
    spacing : target panel size, mm
    """
    d = np.asarray(dense, dtype=float)
    ins = np.asarray(inside, dtype=bool)
    along_rows = np.linalg.norm(np.diff(d, axis=1), axis=-1).T           # (S-1, P): section edges
    rows_in = (ins[:, 1:] & ins[:, :-1]).T
    along_cols = np.linalg.norm(np.diff(d, axis=0), axis=-1)             # (P-1, S): conjugate-curve edges
    cols_in = ins[1:] & ins[:-1]
    s0 = float(np.interp(y_mid, seeds, np.arange(len(seeds))))
    p0 = float(np.interp(x_mid, planes, np.arange(len(planes))))
    ts = strip_positions(along_rows, rows_in, s0, spacing)
    tp = strip_positions(along_cols, cols_in, p0, spacing)
    return (np.interp(ts, np.arange(len(seeds)), seeds), np.interp(tp, np.arange(len(planes)), planes))
