"""Trimming a net to the plan outline of the surface: outer loops and holes, by the even–odd rule.

A face is kept when its four corners lie inside the region and no boundary point lies inside it (so a hole
smaller than a panel still removes the panel over it).  Everything is in the plan frame (2D, mm).

Examples
--------
>>> import numpy as np
>>> square = np.array([[0, 0], [4, 0], [4, 4], [0, 4.0]])
>>> hole = np.array([[1, 1], [2, 1], [2, 2], [1, 2.0]])
>>> inside(np.array([[0.5, 0.5], [1.5, 1.5], [5, 5.0]]), [square, hole]).tolist()
[True, False, False]
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

CHUNK = 1 << 22
"""Largest number of point–edge pairs tested in one vectorised pass."""


def _edges(loops: Sequence[np.ndarray]) -> np.ndarray:
    """``(E, 2, 2)`` segments of closed loops (each ``(k, 2)``)."""
    segs = [np.stack([lp, np.roll(lp, -1, axis=0)], axis=1) for lp in loops if len(lp) >= 3]
    return np.concatenate(segs) if segs else np.zeros((0, 2, 2))


def _crossings(p: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """Parity of the crossings of a ray in +x from each point ``(M, 2)`` with ``segs (E, 2, 2)``: ``(M,)`` bool."""
    out: np.ndarray = np.zeros(len(p), dtype=bool)
    if not len(segs) or not len(p):
        return out
    step = max(1, CHUNK // len(segs))
    a, b = segs[:, 0], segs[:, 1]
    for s in range(0, len(p), step):
        q = p[s:s + step, None, :]
        straddle = (a[None, :, 1] > q[..., 1]) != (b[None, :, 1] > q[..., 1])
        with np.errstate(divide="ignore", invalid="ignore"):       # a level segment never straddles
            t = (q[..., 1] - a[None, :, 1]) / (b[None, :, 1] - a[None, :, 1])
            xc = a[None, :, 0] + t * (b[None, :, 0] - a[None, :, 0])
        out[s:s + step] = (np.count_nonzero(straddle & (xc > q[..., 0]), axis=1) % 2).astype(bool)
    return out


def inside(points: np.ndarray, loops: Sequence[np.ndarray]) -> np.ndarray:
    """Whether plan points ``(M, 2)`` lie inside the region bounded by ``loops`` (even–odd: holes are out)."""
    return _crossings(np.asarray(points, dtype=float), _edges([np.asarray(lp, dtype=float) for lp in loops]))


def faces_inside(corners: np.ndarray, loops: Sequence[np.ndarray]) -> np.ndarray:
    """Which faces lie wholly inside the region.

    Parameters
    ----------
    corners : (F, 4, 2) float — plan corners of the faces
    loops : the region's boundary loops, each ``(k, 2)``

    Returns
    -------
    (F,) bool — all four corners inside and no boundary point inside the face
    """
    c = np.asarray(corners, dtype=float)
    keep: np.ndarray = np.asarray(inside(c.reshape(-1, 2), loops).reshape(len(c), 4).all(axis=1))
    pts = np.concatenate([np.asarray(lp, dtype=float) for lp in loops]) if len(loops) else np.zeros((0, 2))
    if not len(pts) or not keep.any():
        return keep
    idx = np.flatnonzero(keep)
    lo, hi = c[idx].min(axis=1), c[idx].max(axis=1)
    step = max(1, CHUNK // (4 * len(pts)))
    for s in range(0, len(idx), step):
        k = idx[s:s + step]
        box = ((pts[None, :, 0] >= lo[s:s + step, None, 0]) & (pts[None, :, 0] <= hi[s:s + step, None, 0]) &
               (pts[None, :, 1] >= lo[s:s + step, None, 1]) & (pts[None, :, 1] <= hi[s:s + step, None, 1]))
        for r in np.flatnonzero(box.any(axis=1)):
            cand = pts[box[r]]
            quad = _edges([c[k[r]]])
            if _crossings(cand, quad).any():
                keep[k[r]] = False
    return keep
