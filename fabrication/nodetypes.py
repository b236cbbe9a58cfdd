"""Node types: nodes grouped by their joint and angles, for the installers' node sheets.

Two nodes are of one type when they have the same joint kind, the same roles of their plates (through / end)
and their pairwise plate dihedral angles (``nodes.json`` ``pairs``), sorted, agree after rounding to
``tolerance_deg``.  Rounding to a grid is a partition (unlike a chain of "within tolerance" comparisons), so
every node has exactly one type; two nodes closer than the tolerance can still fall on either side of a grid
line.  Types are numbered ``NT01, NT02, …`` in order of their first node.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DEFAULT_TOLERANCE_DEG = 1.0
"""Grid of the rounded angles, degrees."""


@dataclass(frozen=True)
class NodeType:
    """One node type: its id, key (joint, roles, rounded angles) and the records of its nodes (``nodes.json``)."""

    type_id: str
    joint: str
    roles: tuple[str, ...]
    angles_deg: tuple[float, ...]
    nodes: tuple[dict, ...]

    @property
    def slot_width_range(self) -> tuple[float, float] | None:
        """Smallest and largest half-lap slot width of the type's nodes, mm (``None`` without slots)."""
        w = [r["slot_width_mm"] for r in self.nodes if r.get("slot_width_mm") is not None]
        return (float(min(w)), float(max(w))) if w else None


def _key(rec: dict, tol: float) -> tuple:
    angles = sorted(float(p["dihedral_deg"]) for p in rec.get("pairs", []) if p.get("dihedral_deg") is not None)
    rounded = tuple(float(np.round(a / tol) * tol) for a in angles)
    roles = tuple(sorted(b["role"] for b in rec.get("beams", [])))
    return rec.get("joint", "none"), roles, rounded


def node_types(records: list[dict] | tuple[dict, ...], tolerance_deg: float = DEFAULT_TOLERANCE_DEG
               ) -> list[NodeType]:
    """The node types of ``records`` (one per vertex, :func:`fabrication.nodes.node_records`); nodes without a
    plate are left out.

    >>> recs = [{"joint": "halflap", "beams": [{"role": "through"}] * 2, "pairs": [{"dihedral_deg": a}]}
    ...         for a in (80.2, 80.4, 84.0)]
    >>> [len(t.nodes) for t in node_types(recs)]
    [2, 1]
    """
    groups: dict[tuple, list[dict]] = {}
    for r in records:
        if not r.get("beams"):
            continue
        groups.setdefault(_key(r, tolerance_deg), []).append(r)
    width = max(2, len(str(len(groups))))
    return [NodeType(f"NT{k + 1:0{width}d}", key[0], key[1], key[2], tuple(recs))
            for k, (key, recs) in enumerate(groups.items())]
