"""The ``principal`` net: curvature lines of the height field, two families intersected into a quad net.

The principal directions solve ``II v = κ I v`` (:mod:`.curvature`); family 1 follows the larger
curvature ``κ1``, family 2 the smaller.  The curves are traced and intersected by
:mod:`.traced` (classical Runge–Kutta in plan, seeds ``spacing`` apart along the middle curves, re-seeded strip
by strip where they fan).  A principal
net is conjugate and orthogonal: its quads are nearly planar and nearly rectangular before optimisation.

At an umbilic (``κ1 = κ2``: the top of a dome of revolution, a flat part) the directions are undefined and
the curves turn around it: :func:`umbilics` finds them on the fit's grid, and :func:`principal_net`
refuses when one lies inside the outline, with its place in mm.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..errors import GeometryError
from .curvature import forms, principal
from .heightfield import HeightField
from .plan import PlanFrame
from .sections import EDGE_MARGIN, FLAT, SectionsNet, grid_inside
from .traced import DirectionField, traced_net

BALANCED = 0.25
"""Edges within ``±BALANCED`` of the spacing need no re-seeding (:func:`~.traced.traced_net`)."""

UMBILIC = 0.1
"""``|κ1 − κ2|`` below this fraction of the surface's typical ``max |κ|`` counts as umbilic."""


MAX_UMBILICS = 8
"""At most this many umbilics are located and reported."""


def umbilics(hf: HeightField, frame: PlanFrame, loops: Sequence[np.ndarray], margin: float) -> np.ndarray:
    """Umbilics: local minima of ``|κ1 − κ2|`` on the fit's plan grid below :data:`UMBILIC` of the 90th
    percentile of ``max(|κ1|, |κ2|)``, inside the outline and ``margin`` mm or more from it.

    Returns
    -------
    (U, 3) float — world points (mm), the most pronounced first; the whole region when the surface is flat
    """
    gx, gy = hf.x, hf.y
    X, Y = np.meshgrid(gx, gy, indexing="ij")
    k1, k2, _, _ = principal(*forms(hf, X, Y))
    gap = k1 - k2
    kmax = np.maximum(np.abs(k1), np.abs(k2))
    _, inside_flat = grid_inside(hf, loops, margin)
    ins = inside_flat.reshape(X.shape)
    if not ins.any():
        return np.zeros((0, 3))
    scale = float(np.percentile(kmax[ins], 90))
    if scale < FLAT:
        k = np.argwhere(ins)[len(np.argwhere(ins)) // 2]
        loc = np.array([X[k[0], k[1]], Y[k[0], k[1]], float(hf.f(X[k[0], k[1]], Y[k[0], k[1]]))])
        return frame.to_world(loc)[None]
    # local minima over the 3 × 3 neighbourhood
    pad = np.pad(gap, 1, constant_values=np.inf)
    nb = np.stack([pad[1 + di:1 + di + gap.shape[0], 1 + dj:1 + dj + gap.shape[1]]
                   for di in (-1, 0, 1) for dj in (-1, 0, 1) if di or dj])
    low = ins & (gap <= nb.min(axis=0)) & (gap < UMBILIC * scale)
    idx = np.argwhere(low)
    idx = idx[np.argsort(gap[low])]
    cell = float(max(gx[1] - gx[0], gy[1] - gy[0]))
    found: list[np.ndarray] = []
    for i, j in idx:
        start = np.array([X[i, j], Y[i, j]])
        if any(np.hypot(*(start - q)) <= 4 * cell for q in found):     # half a spacing apart
            continue
        p = _refine(hf, start, cell)
        if all(np.hypot(*(p - q)) > 4 * cell for q in found):
            found.append(p)
        if len(found) >= MAX_UMBILICS:
            break
    if not found:
        return np.zeros((0, 3))
    xy = np.array(found)
    return frame.to_world(np.column_stack([xy, hf.f(xy[:, 0], xy[:, 1])]))


def _refine(hf: HeightField, p: np.ndarray, cell: float) -> np.ndarray:
    """The minimum of ``(κ1 − κ2)²`` near a grid point (Nelder–Mead within two cells of it)."""
    from scipy.optimize import minimize

    def gap2(q: np.ndarray) -> float:
        k1, k2, _, _ = principal(*forms(hf, np.array([q[0]]), np.array([q[1]])))
        return float((k1[0] - k2[0]) ** 2)

    res = minimize(gap2, p, method="Nelder-Mead",
                   options={"initial_simplex": [p, p + [cell, 0.0], p + [0.0, cell]], "xatol": 1.0,
                            "fatol": 0.0, "maxiter": 200})
    q = np.asarray(res.x, dtype=float)
    return q if np.hypot(*(q - p)) <= 2 * cell else p


def principal_field(hf: HeightField) -> DirectionField:
    """The curvature directions of ``hf`` as a :data:`~.traced.DirectionField` (family 1: the larger
    curvature ``κ1``)."""
    def field(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        _, _, d1, d2 = principal(*forms(hf, p[:, 0], p[:, 1]))
        return d1, d2
    return field


def principal_net(hf: HeightField, frame: PlanFrame, loops: Sequence[np.ndarray], spacing: float,
                  min_face: float = 0.25) -> tuple[SectionsNet, np.ndarray, np.ndarray, str]:
    """Build the principal net, trimmed to the plan region.

    Returns
    -------
    net : rows along curvature lines of family 1, columns of family 2 (``planar_family = "none"``)
    twist : (F,) float — per kept face (row-major), ``|II(a, b)| / (|a||b| max|κ|)``, about 0
    found : (U, 3) float — umbilics inside the region nearer than ``EDGE_MARGIN × spacing`` to its edge
        (empty: none; farther inside the net is refused)
    seeding : ``"uniform"`` (``spacing`` along the middle curves) or ``"strips"`` (:mod:`.balance`)

    Raises
    ------
    GeometryError : an umbilic (or a flat surface) inside the outline, with its place in mm
    """
    loops = [np.asarray(lp, dtype=float)[:, :2] for lp in loops]
    inner = umbilics(hf, frame, loops, EDGE_MARGIN * spacing)
    if len(inner):
        w = inner[0]
        more = f" and {len(inner) - 1} more" if len(inner) > 1 else ""
        raise GeometryError(
            f"principal net: an umbilic (equal principal curvatures: the curvature lines turn around it) at "
            f"(x, y) = ({w[0]:.0f}, {w[1]:.0f}) mm inside the outline{more}; "
            "use net = 'conjugate', 'sections' or 'pp', or trim the surface away from it",
            element=f"({w[0]:.0f}, {w[1]:.0f})")
    found = umbilics(hf, frame, loops, 0.0)
    net, twist, seeding = traced_net(hf, frame, loops, spacing, min_face, principal_field(hf), "principal", BALANCED)
    return net, twist, found, seeding
