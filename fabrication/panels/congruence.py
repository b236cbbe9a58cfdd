"""Congruence classes of flat outlines: identical panels are cheaper, so they share a type id.

Two outlines with the same number of corners are congruent within ``tol`` when some
cyclic relabelling of corners and a rigid motion of the plane (and, when mirroring is
allowed, a reflection) brings every corner within ``tol`` of its partner.  For a fixed
correspondence the best rigid motion is the 2D Kabsch/Procrustes solution; the test is
the largest residual corner distance.  Candidates are found with a k-d tree on the
sorted edge lengths (congruent within ``tol`` ⇒ every sorted edge length within ``2 tol``).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


def kabsch_2d(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The best proper rigid motions of candidates ``b`` onto ``a`` (2D Kabsch/Procrustes, least squares over the
    corresponding corners): ``x ↦ R x + t`` minimising ``Σ_i |R b_i + t − a_i|²``.

    a : (k, 2); b : (C, k, 2) candidates (already in corresponding corner order).  Returns the rotations
    ``(C, 2, 2)``, the shifts ``(C, 2)`` and the largest corner distance after the motion ``(C,)``.
    """
    mean_a = a.mean(axis=0)
    mean_b = b.mean(axis=1)
    ca = a - mean_a
    cb = b - mean_b[:, None, :]
    h = np.einsum("cki,kj->cij", cb, ca)            # cross-covariance
    # optimal rotation angle for 2D: atan2(h01 - h10, h00 + h11)
    theta = np.arctan2(h[:, 0, 1] - h[:, 1, 0], h[:, 0, 0] + h[:, 1, 1])
    c, s = np.cos(theta), np.sin(theta)
    rot = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)   # (C, 2, 2)
    moved = np.einsum("cij,ckj->cki", rot, cb)
    residual = np.linalg.norm(moved - ca[None], axis=-1).max(axis=-1)
    shift = mean_a[None, :] - np.einsum("cij,cj->ci", rot, mean_b)
    return rot, shift, residual


def correspondences(b: np.ndarray, mirror: bool) -> np.ndarray:
    """All corner relabellings of ``b (k, 2)`` that keep it counter-clockwise: ``(S, k, 2)``.

    Cyclic shifts; with ``mirror`` also the reflection ``x ↦ −x`` with reversed order.
    """
    k = len(b)
    out = [np.roll(b, -s, axis=0) for s in range(k)]
    if mirror:
        m = b[::-1] * np.array([-1.0, 1.0])
        out += [np.roll(m, -s, axis=0) for s in range(k)]
    return np.stack(out)


def congruence_distance(a: np.ndarray, b: np.ndarray, mirror: bool = False) -> float:
    """Smallest largest-corner distance between outlines ``a`` and ``b`` over relabellings and rigid motions."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.shape != b.shape:
        return float("inf")
    return float(kabsch_2d(a, correspondences(b, mirror))[2].min())


def group_congruent(outlines: list[np.ndarray], tol: float, mirror: bool = False) -> np.ndarray:
    """Type index per outline: the first outline of each class is its representative.

    Parameters
    ----------
    outlines : list of (k_i, 2) counter-clockwise polygons
    tol : largest corner distance (mm) after alignment for two outlines to share a type
    mirror : reflections count as congruent

    Returns
    -------
    types : (P,) int, numbered 0, 1, … in order of first appearance (deterministic)
    """
    n = len(outlines)
    types = np.full(n, -1, dtype=np.int64)
    reps: list[int] = []
    by_k: dict[int, list[int]] = {}
    for i, o in enumerate(outlines):
        by_k.setdefault(len(o), []).append(i)
    candidates: dict[int, list[int]] = {}
    for k, idx in by_k.items():
        keys = np.stack([np.sort(np.linalg.norm(np.roll(outlines[i], -1, 0) - outlines[i], axis=1)) for i in idx])
        tree = cKDTree(keys)
        near = tree.query_ball_point(keys, r=2.0 * tol + 1e-9, p=np.inf)
        for local, i in enumerate(idx):
            candidates[i] = sorted(idx[j] for j in near[local] if idx[j] < i)
    rep_of: dict[int, int] = {}
    for i in range(n):
        found = -1
        reps_here = [j for j in candidates[i] if j in rep_of]
        a = np.asarray(outlines[i], dtype=float)
        for j in reps_here:
            if congruence_distance(np.asarray(outlines[j], dtype=float), a, mirror) <= tol + 1e-9:
                found = rep_of[j]
                break
        if found < 0:
            found = len(reps)
            reps.append(i)
            rep_of[i] = found
        types[i] = found
    return types
