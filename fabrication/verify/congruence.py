"""Independent references for the congruence checks: a face inset in its own plane, polygon signatures."""

from __future__ import annotations

import numpy as np

from ppfab.metrics import polygon_area


def inset_face_2d(corners: np.ndarray, delta: float) -> np.ndarray:
    """Independent reference for a panel: the face ``(4, 3)`` in its own plane, counter-clockwise,
    every edge line moved inward by ``delta``, consecutive lines intersected → ``(4, 2)``."""
    c = corners - corners.mean(axis=0)
    _, _, vt = np.linalg.svd(c)
    p = c @ vt[:2].T
    if polygon_area(p) < 0:
        p = p[::-1]
    e = np.roll(p, -1, axis=0) - p
    n = np.stack([-e[:, 1], e[:, 0]], axis=1) / np.linalg.norm(e, axis=1)[:, None]
    b = np.einsum("ki,ki->k", n, p) + delta
    out = []
    for k in range(len(p)):
        a = np.array([n[k - 1], n[k]])
        out.append(np.linalg.solve(a, [b[k - 1], b[k]]))
    return np.array(out)


def shape_signature(poly: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Edge lengths and interior angles of a polygon, in order (orientation-independent angles)."""
    p = np.asarray(poly, dtype=float)
    e = np.roll(p, -1, axis=0) - p
    lengths = np.linalg.norm(e, axis=1)
    e_in = p - np.roll(p, 1, axis=0)
    cross = e_in[:, 0] * e[:, 1] - e_in[:, 1] * e[:, 0]
    ang = np.abs(np.arctan2(cross, np.einsum("ki,ki->k", e_in, e)))
    return lengths, ang


def congruence_error(a: np.ndarray, b: np.ndarray, limits: tuple[float, float] = (1.0, 1.0)
                     ) -> tuple[float, float]:
    """(max edge-length difference, max angle difference) of ``b`` against ``a`` for the corner
    correspondence (cyclic shift, with or without reversal) that fits best against ``limits`` (mm, rad): the
    one with the smallest ``max(dl / limits[0], da / limits[1])``, so a near-symmetric outline is not matched
    by a shift whose edge lengths happen to agree while its angles do not."""
    la, aa = shape_signature(a)
    best, score = (np.inf, np.inf), np.inf
    for poly in (np.asarray(b, dtype=float), np.asarray(b, dtype=float)[::-1]):
        lb, ab = shape_signature(poly)
        if len(lb) != len(la):
            continue
        for k in range(len(lb)):
            dl = float(np.abs(np.roll(lb, k) - la).max())
            da = float(np.abs(np.roll(ab, k) - aa).max())
            here = max(dl / limits[0], da / limits[1])
            if here < score:
                best, score = (dl, da), here
    return best


def congruence_limits(reference: np.ndarray, tol: float) -> tuple[float, float]:
    """The largest edge-length and angle differences (mm, rad) of :func:`congruence_error` for an outline whose
    corners lie within ``tol`` of those of ``reference`` (a corner moved by ``tol`` changes an edge by up to
    ``2 tol`` and an angle by up to about ``2 tol`` over each of its two edges), plus 1e-6 for rounding."""
    lengths, _ = shape_signature(reference)
    return 2.0 * tol + 1e-6, 4.0 * tol / max(float(lengths.min()), 1e-9) + 1e-6
