"""nodes.csv: contract columns, one node per vertex at its position, unit axes, known beams."""

from __future__ import annotations

import numpy as np

from ..contract import NODES_CONTRACT_COLUMNS as NODES_COLUMNS
from . import Verification, check, read_csv


@check("nodes", 40)
def check_nodes(v: Verification) -> None:
    files = v.data.get("manifest", {}).get("files", {})
    rel = files.get("nodes_csv")
    mesh = v.data.get("mesh")
    if rel is None or mesh is None:
        return
    rows = read_csv(v.folder / rel)
    v.data["nodes"] = rows
    if rows:
        missing = [c for c in NODES_COLUMNS if c not in rows[0]]
        if missing:
            v.error(rel, "columns", f"missing contract columns {missing}")
            return
    if len(rows) != len(mesh.vertices):
        v.error(rel, "rows", f"{len(rows)} nodes for {len(mesh.vertices)} mesh vertices")
    part_ids = {row["part_id"] for row in v.data.get("parts", [])}
    for row in rows:
        k = int(row["vertex"])
        if not 0 <= k < len(mesh.vertices):
            v.error(rel, row["node_id"], f"vertex {k} does not exist")
            continue
        p = np.array([float(row[c]) for c in ("x", "y", "z")])
        if np.abs(p - mesh.vertices[k]).max() > 1e-3:
            v.error(rel, row["node_id"], f"position differs from OBJ vertex {k} by "
                                          f"{np.abs(p - mesh.vertices[k]).max():.3g} mm")
        a = np.array([float(row[c]) for c in ("axis_x", "axis_y", "axis_z")])
        if abs(np.linalg.norm(a) - 1) > 1e-6:
            v.error(rel, row["node_id"], f"axis is not a unit vector (|a| = {np.linalg.norm(a):.6f})")
        for b in filter(None, row["beams"].split(";")):
            if part_ids and b not in part_ids:
                v.error(rel, row["node_id"], f"beam {b} is not in the parts list")
    v.checked.append("nodes")
