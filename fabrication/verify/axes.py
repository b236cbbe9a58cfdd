"""Node axes and beam lists against the support structure: nodes.csv, nodes.json, mesh.json and parts.csv agree.

* every node's axis in ``nodes.csv`` is the one in ``nodes.json`` and, on a regular patch, in ``mesh.json``
  (within 1e-9; grid vertex ``k`` is OBJ vertex ``obj_vertex[k]`` when the mesh came from a file);
* the support planes of ``mesh.json`` (``support_u`` rows, ``support_w`` columns) hold their polylines'
  vertices (within ``beams.plane_tolerance``) and their axes (within the torsion tolerance at beam depth);
* a node's beams in ``nodes.csv`` are exactly the beam plates whose ``nodes`` in ``parts.csv`` contain it,
  and ``nodes.json`` lists the same.
"""

from __future__ import annotations


import numpy as np

from . import Verification, check
from ._cells import is_vector
from ._shapes import literal, number, torsion_tolerance


@check("axes")
def check_axes(v: Verification) -> None:
    rows = v.nodes
    mesh = v.mesh
    if rows is None or mesh is None:
        return
    m = v.manifest
    files = m.get("files", {})
    rel = files.get("nodes_csv", "nodes.csv")
    fab = m.get("fabrication", {})
    depth = float(fab.get("beam_depth", 0.0))
    plane_tol = float(fab.get("beams", {}).get("plane_tolerance", fab.get("beam_plane_tolerance", 0.5)))
    tors_tol, tors_key = torsion_tolerance(m)
    axes = np.full((len(mesh.vertices), 3), np.nan)
    listed: dict[int, set[str]] = {}
    for r in rows:
        k = int(r["vertex"])
        if 0 <= k < len(axes):
            axes[k] = [number(r[c]) for c in ("axis_x", "axis_y", "axis_z")]
            listed[k] = set(filter(None, r["beams"].split(";")))
    # nodes.json
    jrel = files.get("nodes_json")
    if jrel is not None:
        doc = v.read_json(jrel) or {}
        nodes = doc.get("nodes", []) if isinstance(doc, dict) else None
        if not isinstance(nodes, list):
            v.error(jrel, "nodes", "must be a list of nodes")
            nodes = []
        for n, node in enumerate(nodes):
            vk = node.get("vertex") if isinstance(node, dict) else None
            axis = node.get("axis") if isinstance(node, dict) else None
            beam_list = node.get("beams", []) if isinstance(node, dict) else None
            if not (isinstance(vk, int) and is_vector(axis, 3) and isinstance(beam_list, list)
                    and all(isinstance(b, dict) and isinstance(b.get("part_id"), str) for b in beam_list)):
                v.error(jrel, f"nodes[{n}]", "is not a node: an integer vertex, a 3-vector axis and a list of beams "
                                             "with part ids")
                continue
            if not 0 <= vk < len(axes):
                continue
            k = vk
            d = float(np.abs(np.asarray(axis, dtype=float) - axes[k]).max())
            if not d <= 1e-8:
                v.error(rel, node.get("node_id", f"N{k:04d}"), f"axis differs from nodes.json by {d:.3g}")
            beams = {b["part_id"] for b in beam_list}
            if beams != listed.get(k, set()):
                v.error(rel, node.get("node_id", f"N{k:04d}"),
                        f"beams {sorted(listed.get(k, set()))} differ from nodes.json {sorted(beams)}")
    # parts.csv: the nodes of every beam plate
    carried: dict[int, set[str]] = {}
    for row in (v.parts or []):
        if row["kind"] == "beam":
            for k in literal(row.get("nodes", "")) or []:
                carried.setdefault(int(k), set()).add(row["part_id"])
    if carried:
        for k in range(len(axes)):
            a, b = listed.get(k, set()), carried.get(k, set())
            if a != b:
                extra, missing = sorted(a - b), sorted(b - a)
                what = "; ".join(filter(None, [f"{', '.join(extra)} do(es) not pass through it" if extra else "",
                                               f"{', '.join(missing)} pass(es) through it but is not listed"
                                               if missing else ""]))
                v.error(rel, f"N{k:04d}", f"beam list does not match the plates of parts.csv: {what}")
    # mesh.json
    mrel = files.get("mesh_json")
    if mrel is not None:
        grid = v.read_json(mrel) or {}
        try:
            shape = (int(grid.get("rows", 0)), int(grid.get("cols", 0)))
            gv = np.asarray(grid.get("vertices", []), dtype=float).reshape(-1, 3)
            order = np.asarray(grid.get("obj_vertex", np.arange(len(gv))), dtype=np.int64).reshape(-1)
        except (TypeError, ValueError) as exc:
            v.error(mrel, "vertices", f"cannot be read as rows × cols points ({exc})")
            grid, gv, order = {}, np.zeros((0, 3)), np.zeros(0, dtype=np.int64)
        if (len(gv) == len(mesh.vertices) and len(order) == len(gv)
                and np.array_equal(np.sort(order), np.arange(len(gv)))
                and np.abs(gv - mesh.vertices[order]).max(initial=0.0) <= 1e-6):
            try:
                ga = np.asarray(grid.get("axes", np.full_like(gv, np.nan)), dtype=float).reshape(-1, 3)
            except (TypeError, ValueError):
                v.error(mrel, "axes", "is not a list of 3-vectors")
                ga = np.full_like(gv, np.nan)
            if len(ga) != len(gv):
                v.error(mrel, "axes", f"{len(ga)} axes for {len(gv)} vertices")
                ga = np.full_like(gv, np.nan)
            diff = np.abs(ga - axes[order]).max(axis=1)
            for k in np.flatnonzero(~(diff <= 1e-8))[:20]:
                v.error(mrel, f"N{int(order[k]):04d}", f"axis {np.round(ga[k], 9).tolist()} differs from "
                                                       f"nodes.csv {np.round(axes[order[k]], 9).tolist()}")
            if shape[0] * shape[1] != len(gv):
                v.error(mrel, "rows", f"rows {shape[0]} x cols {shape[1]} do not hold its {len(gv)} vertices")
                shape = (0, 0)
            pts, ax = gv.reshape(shape + (3,)) if shape[0] else gv, axes[order]
            if shape[0]:
                ax = ax.reshape(shape + (3,))
            for key, family in (("support_u", 0), ("support_w", 1)):
                if key not in grid or not shape[0]:
                    continue
                try:
                    planes = np.asarray(grid[key], dtype=float).reshape(-1, 4)
                except (TypeError, ValueError):
                    v.error(mrel, key, "is not a list of planes [a, b, c, d]")
                    continue
                lines = (pts, ax) if family == 0 else (pts.transpose(1, 0, 2), ax.transpose(1, 0, 2))
                for i, (plane, p, a) in enumerate(zip(planes, *lines)):
                    n = plane[:3] / np.linalg.norm(plane[:3])
                    off = float(np.abs(p @ n + plane[3] / np.linalg.norm(plane[:3])).max())
                    lean = depth * float(np.abs(a @ n).max())
                    name = f"{key}[{i}]"
                    if off > plane_tol + 1e-6:
                        v.error(mrel, name, f"its polyline's vertices are up to {off:.3g} mm off the plane")
                    if not lean <= tors_tol + 1e-6:
                        v.error(mrel, name, f"the node axes leave the plane by up to {lean:.3g} mm at beam depth "
                                            f"({tors_key} {tors_tol:g} mm)")
        elif len(gv):
            v.error(mrel, "vertices", "differ from mesh.obj")
    v.checked.append("axes")
