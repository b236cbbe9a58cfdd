"""Which polylines become planar, which carry fairness, which vertices are fixed.

Polylines come from :attr:`ppfab.mesh.QuadMesh.polylines` (traced through
valence-4 vertices, stopping at singular vertices and jagged-boundary corners;
on a regular patch: rows ``v[i, :]`` = family 0, columns ``v[:, j]`` = family 1).
A polyline with fewer than three vertices lies in a plane anyway: it gets no
support plane and is counted as skipped.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import DesignError
from ..mesh import QuadMesh
from ..topology import Polyline

FAMILY_CODES = {"rows": (0,), "cols": (1,), "both": (0, 1), "none": ()}


@dataclass(frozen=True)
class Selection:
    """Polylines of an optimisation problem.

    planar : polylines that get a support plane (``>= 3`` vertices), in ``mesh.polylines`` order
    planar_index : (S,) int, their indices in ``mesh.polylines``
    fair : polylines carrying E_fair (``>= 3`` vertices)
    skipped : number of requested polylines with fewer than 3 vertices
    crossing : indices of polylines of the requested families left out because they pass twice through
        one vertex (possible only around odd singular vertices, where the families mix): such a polyline's
        plane would have to contain both of its directions there, i.e. be the tangent plane
    """

    planar: list[Polyline]
    planar_index: np.ndarray
    fair: list[Polyline]
    skipped: int
    crossing: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))


def select_polylines(mesh: QuadMesh, families: str, indices: list[int] | tuple[int, ...] = (),
                     fair_families: str = "both") -> Selection:
    """Polylines of the requested families plus the explicitly listed ones.

    A polyline of a requested family that passes twice through one vertex (see :class:`Selection`) is
    left out unless its index is listed explicitly.
    Raises :class:`DesignError` (key ``polylines[k]``) for an index that is not a polyline of the mesh.
    """
    lines = mesh.polylines
    codes = FAMILY_CODES[families]
    fam = np.array([p.family for p in lines], dtype=np.int64)
    lengths = np.array([len(p) for p in lines], dtype=np.int64)
    wanted = np.isin(fam, codes)
    crossing = wanted & np.array([self_crossing(p) for p in lines], dtype=bool)
    wanted &= ~crossing
    for k, idx in enumerate(indices):
        if not 0 <= idx < len(lines):
            raise DesignError(f"polylines[{k}]", f"polyline {idx} does not exist (the mesh has {len(lines)}, "
                                                 f"numbered 0..{len(lines) - 1})")
        wanted[idx] = True
    long_enough = lengths >= 3
    chosen = np.flatnonzero(wanted & long_enough)
    fair_codes = FAMILY_CODES[fair_families]
    fair = [p for p, ok in zip(lines, np.isin(fam, fair_codes) & long_enough) if ok]
    crossing[list(indices)] = False
    return Selection([lines[i] for i in chosen], chosen, fair, int((wanted & ~long_enough).sum()),
                     np.flatnonzero(crossing))


def self_crossing(p: Polyline) -> bool:
    """The polyline passes twice through a vertex (an open polyline may still end where it started)."""
    v = p.vertices if (p.closed or len(p) < 2 or p.vertices[0] != p.vertices[-1]) else p.vertices[:-1]
    return len(np.unique(v)) < len(v)


def free_vertices(mesh: QuadMesh, fix_boundary: bool, fixed: list[int] | tuple[int, ...] = ()) -> np.ndarray:
    """Boolean ``(N,)``: which vertices may move.

    Raises :class:`DesignError` (key ``fixed_vertices[k]``) for an index out of range.
    """
    n = len(np.asarray(mesh.vertices))
    free = np.ones(n, dtype=bool)
    if fix_boundary:
        free &= ~mesh.topology.boundary_vertices
    for k, idx in enumerate(fixed):
        if not 0 <= idx < n:
            raise DesignError(f"fixed_vertices[{k}]", f"vertex {idx} does not exist (the mesh has {n} vertices)")
        free[idx] = False
    return free


def edge_pairs(lines: list[Polyline]) -> tuple[np.ndarray, np.ndarray]:
    """Consecutive vertex pairs of polylines (closing edge included for closed ones).

    Returns ``pairs (E, 2)`` and ``owner (E,)`` = position of the polyline in ``lines``.
    """
    pairs, owner = [], []
    for s, p in enumerate(lines):
        v = p.vertices
        b = np.roll(v, -1) if p.closed else v[1:]
        a = v if p.closed else v[:-1]
        pairs.append(np.stack([a, b], axis=1))
        owner.append(np.full(len(a), s, dtype=np.int64))
    if not pairs:
        return np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=np.int64)
    return np.concatenate(pairs).astype(np.int64), np.concatenate(owner)


def triples(lines: list[Polyline]) -> np.ndarray:
    """Successive vertex triples ``(T, 3)`` ``(u, v, w)`` along polylines (wrapping for closed ones)."""
    out = []
    for p in lines:
        v = p.vertices
        if p.closed:
            out.append(np.stack([np.roll(v, 1), v, np.roll(v, -1)], axis=1))
        else:
            out.append(np.stack([v[:-2], v[1:-1], v[2:]], axis=1))
    if not out:
        return np.zeros((0, 3), dtype=np.int64)
    return np.concatenate(out).astype(np.int64)
