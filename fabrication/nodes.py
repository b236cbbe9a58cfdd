"""Node data for node and bracket designers: ``nodes.csv`` and ``nodes.json``.

One row per mesh vertex (``vertex`` = 0-based index of the OBJ vertex), see the
output contract in DESIGN.md.  Columns of ``nodes.csv``:

=================  =======================================================================
``node_id``        ``N`` + vertex index (``N0042``)
``vertex``         0-based OBJ vertex index
``i, j``           grid index on a regular patch (empty otherwise)
``x, y, z``        position, mm
``axis_x…z``       unit node axis of the support structure (pointing into the structure)
``beams``          ``;``-separated part ids of the plates meeting there
``roles``          ``;``-separated ``through``/``end`` per plate (same order)
``joint``          ``halflap``, ``butt``, ``plain`` or ``free``
``valence``        number of mesh edges at the vertex; ``boundary`` 0/1
``dihedral_deg``   smallest angle between the planes of two different beams meeting
                   there (the angle of the two planes at a regular node)
``beam_panel_deg`` ``;``-separated, per plate: smallest angle between the plate and the
                   panels along its polyline's edges at the node (its own edge for a segment)
``torsion_deg``    largest torsion of the edges at the node (angle between the planes of
                   the edge with either end axis; 0 for a torsion-free support structure)
``torsion_mm``     the same as the offset of an axis at beam depth (the figure checked against
                   ``beams.max_torsion_mm``)
``slot_width_mm``  half-lap slot width (empty elsewhere)
``trims_mm``       ``;``-separated end set-backs of ending plates from the axis
=================  =======================================================================

``nodes.json`` holds the same per node with lists instead of ``;``-strings, plus
the planes of the beams, every pairwise angle and ``axis_normal_deg``, the angle between
the node axis and the surface normal.
"""

from __future__ import annotations

import csv
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from ppfab import planes as pl

from . import contract



def _fmt(x: float, digits: int = 6) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return ""
    return f"{x:.{digits}f}".rstrip("0").rstrip(".") if abs(x) < 1e12 else repr(float(x))


def _num(x: float) -> float | None:
    return None if x is None or not math.isfinite(x) else float(x)


def node_records(beams: Any) -> list[dict]:
    """One dict per vertex from a :class:`~fabrication.beams.BeamSet` (lists, not strings)."""
    support = beams.support
    mesh = support.mesh
    topo = mesh.topology
    v = support.vertices
    edges = support.edges
    ef = topo.edge_faces
    fplanes = mesh.face_planes
    nv = len(v)
    edge_id = {(int(a), int(b)): k for k, (a, b) in enumerate(edges.tolist())}
    tors = np.degrees(support.torsion)
    toff = support.torsion_offset(beams.params.depth)
    node_tors = np.zeros(nv)
    node_off = np.zeros(nv)
    for col in (0, 1):
        np.maximum.at(node_tors, edges[:, col], tors)
        np.maximum.at(node_off, edges[:, col], toff)
    normal_angle = support.normal_angle_deg
    grid = support.grid_index
    joint_at = beams.joint_at
    by_id = beams.by_id
    out = []
    for k in range(nv):
        j = joint_at.get(k)
        parts = list(j.parts) if j else []
        plates = []
        for pid, role in zip(parts, j.roles if j else ()):
            p = by_id[pid]
            line = support.polylines[p.polyline]
            seq = line.vertices
            pos = int(np.flatnonzero(seq == k)[0])
            at = int(np.flatnonzero(p.nodes == k)[0])
            c = int(p.chain[at])
            # a plate ending at the node has its edges on its own side only (segments, parts cut at nodes)
            steps = (-1, 1) if bool(p.through[at]) else (1,) if c == 0 else (-1,) if c == len(p.top) - 1 else (-1, 1)
            nbrs = [int(seq[(pos + d) % len(seq)]) for d in steps if 0 <= pos + d < len(seq) or line.closed]
            faces: set[int] = set()
            for w in nbrs:
                e = edge_id.get((min(k, w), max(k, w)))
                if e is not None:
                    faces.update(int(f) for f in ef[e] if f >= 0)
            angles = [float(np.degrees(pl.angle_between(p.plane, fplanes[f]))) for f in sorted(faces)]
            trim = dict(j.trims).get(pid) if j else None
            plates.append({"part_id": pid, "role": role, "plane": p.plane.tolist(),
                           "panel_angles_deg": angles, "panel_angle_min_deg": min(angles) if angles else None,
                           "trim_mm": trim})
        rec = {
            "node_id": contract.node_id(k),
            "vertex": k,
            "grid": None if grid is None else [int(grid[k, 0]), int(grid[k, 1])],
            "position": v[k].tolist(),
            "axis": support.axes[k].tolist(),
            "beams": plates,
            "joint": j.kind if j else "none",
            "valence": int(topo.valence[k]),
            "boundary": bool(topo.boundary_vertices[k]),
            "dihedral_deg": _num(j.dihedral_min_deg) if j else None,
            "pairs": [{"a": a, "b": b, "dihedral_deg": dih, "opening_deg": _num(op), "same_beam": same}
                      for a, b, dih, op, same in (j.angles if j else ())],
            "torsion_deg": float(node_tors[k]),
            "torsion_mm": float(node_off[k]),
            "axis_normal_deg": float(normal_angle[k]),
            "slot_width_mm": _num(j.slot_width) if j else None,
        }
        out.append(rec)
    return out


def _csv_row(r: dict) -> list[str]:
    grid = r["grid"]
    b = r["beams"]
    return [r["node_id"], str(r["vertex"]), "" if grid is None else str(grid[0]), "" if grid is None else str(grid[1]),
            *(_fmt(x, 4) for x in r["position"]), *(_fmt(x, 9) for x in r["axis"]),
            ";".join(x["part_id"] for x in b), ";".join(x["role"] for x in b), r["joint"], str(r["valence"]),
            "1" if r["boundary"] else "0", _fmt(r["dihedral_deg"] if r["dihedral_deg"] is not None else math.nan, 4),
            ";".join(_fmt(x["panel_angle_min_deg"] if x["panel_angle_min_deg"] is not None else math.nan, 4)
                     for x in b),
            _fmt(r["torsion_deg"], 9), _fmt(r["torsion_mm"], 6),
            _fmt(r["slot_width_mm"] if r["slot_width_mm"] is not None else math.nan, 4),
            ";".join(_fmt(x["trim_mm"], 4) for x in b if x["trim_mm"] is not None)]


def write_nodes_csv(path: str | os.PathLike, records: list[dict]) -> Path:
    """Write ``nodes.csv`` (columns :data:`contract.NODES_COLUMNS`, one row per vertex, in vertex order)."""
    path = Path(path)
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(contract.NODES_COLUMNS)
        for r in records:
            w.writerow([contract.csv_cell(c) for c in _csv_row(r)])
    return path


def write_nodes_json(path: str | os.PathLike, records: list[dict], meta: dict | None = None) -> Path:
    """Write ``nodes.json``: ``{"units": "mm", "angles": "degrees", "columns": …, "nodes": [...]}``."""
    path = Path(path)
    doc = {"units": "mm", "angles": "degrees", "count": len(records), **(meta or {}), "nodes": records}
    path.write_text(json.dumps(contract.json_safe(doc), indent=1, allow_nan=False) + "\n", encoding="utf-8")
    return path


def write_nodes(out_dir: str | os.PathLike, beams: Any, stem: str = "nodes",
                records: list[dict] | None = None) -> tuple[Path, Path]:
    """``OUT/nodes.csv`` and ``OUT/nodes.json`` for a beam set (``records`` from :func:`node_records`
    when already computed); returns both paths."""
    out = Path(out_dir)
    records = node_records(beams) if records is None else records
    meta = {"support": beams.support.summary(), "beam_depth_mm": beams.params.depth,
            "beam_thickness_mm": beams.params.thickness, "joint": beams.params.joint}
    return write_nodes_csv(out / f"{stem}.csv", records), write_nodes_json(out / f"{stem}.json", records, meta)
