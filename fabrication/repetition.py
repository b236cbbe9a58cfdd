"""Repetition: how many panel types and node types a structure has, at several tolerances.

Panels: the congruence classes of their cut outlines (:func:`fabrication.panels.congruence.group_congruent`:
largest corner distance after the best rigid motion, reflections only with ``mirror_allowed``) at each
tolerance of :data:`PANEL_TOLERANCES` (mm; ``0`` means equal to rounding, :data:`EXACT_MM`).

Nodes: a node's *signature* is its joint kind and plate count with the vector of its angles — the sorted
dihedral angles of every pair of plates there, then the sorted smallest plate-to-pane angles of its plates
(``nodes.json``: ``pairs[].dihedral_deg``, ``beams[].panel_angle_min_deg``).  Nodes of one kind and count
whose vectors differ by at most ``tol`` degrees in every entry (Chebyshev distance) share a type; the
grouping is leader clustering in node order (a node joins the first type whose leader is within ``tol``),
deterministic, with candidates from a k-d tree.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
from scipy.spatial import cKDTree

PANEL_TOLERANCES: tuple[float, ...] = (0.0, 1.0, 2.0, 5.0)
"""The tolerances (mm) at which the report and the manifest count panel types."""

NODE_TOLERANCES: tuple[float, ...] = (0.0, 0.1, 0.5, 1.0)
"""The tolerances (degrees) at which the report and the manifest count node types."""

EXACT_MM = 1e-6
""""Equal" outlines at tolerance 0: equal to 1e-6 mm (rounding of coordinates some 10⁴ mm from the origin)."""


def panel_type_counts(outlines: Sequence[np.ndarray], mirror: bool,
                      tolerances: Sequence[float] = PANEL_TOLERANCES) -> dict[str, int]:
    """``{"0": n0, "1": n1, …}``: the number of panel types at each tolerance (mm)."""
    from .panels.congruence import group_congruent

    out = {}
    for tol in tolerances:
        types = group_congruent(list(outlines), max(float(tol), EXACT_MM), mirror)
        out[f"{tol:g}"] = int(types.max()) + 1 if len(types) else 0
    return out


def node_signature(rec: dict[str, Any]) -> tuple[tuple[str, int], np.ndarray]:
    """``((joint kind, plates), angles (k,))`` of a node record (see the module docstring)."""
    pairs = sorted(float(p["dihedral_deg"]) for p in rec.get("pairs", ()) if p.get("dihedral_deg") is not None)
    panes = sorted(float(b["panel_angle_min_deg"]) for b in rec.get("beams", ())
                   if b.get("panel_angle_min_deg") is not None)
    vec = np.array([x for x in pairs + panes if math.isfinite(x)], dtype=float)
    return (str(rec.get("joint", "")), len(rec.get("beams", ()))), vec


def node_types(records: Sequence[dict[str, Any]], tol: float) -> np.ndarray:
    """``(V,)`` node type index per record (0, 1, … in order of first appearance) at ``tol`` degrees."""
    sigs = [node_signature(r) for r in records]
    types = np.full(len(records), -1, dtype=np.int64)
    groups: dict[tuple[tuple[str, int], int], list[int]] = {}
    for i, (key, vec) in enumerate(sigs):
        groups.setdefault((key, len(vec)), []).append(i)
    count = 0
    first: dict[int, int] = {}
    for (_, k), idx in sorted(groups.items(), key=lambda kv: kv[1][0]):
        if k == 0:
            for i in idx:
                types[i] = -2
            continue
        x = np.stack([sigs[i][1] for i in idx])
        tree = cKDTree(x)
        near = tree.query_ball_point(x, r=tol + 1e-9, p=np.inf)
        leader = np.full(len(idx), -1)
        for a in range(len(idx)):
            for b in sorted(near[a]):
                if b < a and leader[b] == b:
                    leader[a] = b
                    break
            else:
                leader[a] = a
        for a, i in enumerate(idx):
            types[i] = -10 - idx[leader[a]]          # provisional: minus the leader's record index
    # renumber in order of first appearance
    for i in range(len(records)):
        t = int(types[i])
        if t not in first:
            first[t] = count
            count += 1
        types[i] = first[t]
    return types


def node_type_counts(records: Sequence[dict[str, Any]],
                     tolerances: Sequence[float] = NODE_TOLERANCES) -> dict[str, int]:
    """``{"0": n0, "0.1": …}``: the number of node types at each tolerance (degrees)."""
    out = {}
    for tol in tolerances:
        t = node_types(records, max(float(tol), 1e-6))
        out[f"{tol:g}"] = int(t.max()) + 1 if len(t) else 0
    return out


def repetition(build) -> dict[str, Any]:
    """The manifest's ``repetition`` entry: panel types at :data:`PANEL_TOLERANCES` mm (``panel_types``) and
    node types at :data:`NODE_TOLERANCES` degrees (``node_types``), with the tolerance the build grouped its
    panels at."""
    panels = build.panels.panels
    mirror = bool(panels[0].mirror_allowed) if panels else False
    return {"panel_types": panel_type_counts([p.outline for p in panels], mirror),
            "panel_type_tolerance_mm": build.design.panels.type_tol,
            "panel_types_used": len(build.panels.types),
            "node_types": node_type_counts(list(build.nodes.records)),
            "node_tolerances_deg": list(NODE_TOLERANCES), "panel_tolerances_mm": list(PANEL_TOLERANCES)}
