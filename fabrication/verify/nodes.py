"""nodes.csv: contract columns, one node per vertex at its position, unit axes, known beams.

The vertex, position and axis cells are read with :class:`~fabrication.verify._cells.CellReader`: a bad cell
is a finding naming its row and column, and its row is left out of :attr:`FolderData.nodes` (the other checks read
only rows whose numbers they can use)."""

from __future__ import annotations

import numpy as np

from ..contract import NODES_CONTRACT_COLUMNS as NODES_COLUMNS
from . import Verification, check
from ._cells import CellReader

NUMBER_COLUMNS = ("x", "y", "z", "axis_x", "axis_y", "axis_z")


@check("nodes")
def check_nodes(v: Verification) -> None:
    files = v.manifest.get("files", {})
    rel = files.get("nodes_csv")
    mesh = v.mesh
    if rel is None or mesh is None:
        return
    raw = v.read_table(rel, NODES_COLUMNS)
    if raw is None:
        return
    cells = CellReader(v, rel)
    rows: list[dict[str, str]] = []
    points: list[tuple[int, np.ndarray, np.ndarray]] = []
    for n, row in enumerate(raw, start=1):
        k = cells.integer(n, row, "vertex", low=0, high=len(mesh.vertices))
        p = cells.vector(n, row, NUMBER_COLUMNS[:3])
        a = cells.vector(n, row, NUMBER_COLUMNS[3:])
        tors = cells.number(n, row, "torsion_mm", empty_ok=True) if "torsion_mm" in row else 0.0
        beams = cells.text(n, row, "beams")
        name = cells.text(n, row, "node_id")
        if k is None or p is None or a is None or beams is None or name is None or (tors is None and row["torsion_mm"]):
            continue
        rows.append({c: ("" if x is None else x) for c, x in row.items() if isinstance(c, str)})
        points.append((k, p, a))
    v.read.nodes = rows
    if len(raw) != len(mesh.vertices):
        v.error(rel, "rows", f"{len(raw)} nodes for {len(mesh.vertices)} mesh vertices")
    part_ids = {row["part_id"] for row in (v.parts or [])}
    for row, (k, p, a) in zip(rows, points):
        if np.abs(p - mesh.vertices[k]).max() > 1e-3:
            v.error(rel, row["node_id"], f"position differs from OBJ vertex {k} by "
                                          f"{np.abs(p - mesh.vertices[k]).max():.3g} mm")
        if abs(np.linalg.norm(a) - 1) > 1e-6:
            v.error(rel, row["node_id"], f"axis is not a unit vector (|a| = {np.linalg.norm(a):.6f})")
        for b in filter(None, row["beams"].split(";")):
            if part_ids and b not in part_ids:
                v.error(rel, row["node_id"], f"beam {b} is not in the parts list")
    v.checked.append("nodes")
