"""beams.step against the structure: every plate solid lies in its support plane, the plate frame of
parts.csv, with its nodes on it, its slots on their node axes and its end cuts where nodes.json says.

For each beam solid (read by the ``step`` check) and its ``parts.csv`` row:

* in the row's frame every vertex is at ``z = ±t/2`` (a plate of thickness ``t`` centred on the frame
  plane), and the frame plane is the row's support plane;
* every node of the plate (``parts.csv`` ``nodes``): its position (``mesh.obj``) lies in the plane within
  ``beams.plane_tolerance``, its axis (``nodes.csv``) lies in the plane within the torsion tolerance at beam
  depth, and its top point lies on the plate's outline — or, where a half-lap slot or an end cut takes
  material away (``nodes.json``), within the distance at which the plate's top edge leaves the strip cut
  away, deeper by the notch under a crossing glazing strip there (``parts.csv`` ``notches``): the strip is ``r = w/2 + set-back`` wide either side of the node axis (``w`` the slot width), so
  along a top edge at angle ``θ`` to the in-plane axis the corner lies ``r / sin θ`` from the node (the
  smallest ``θ`` over the mesh edges from the node that lie in the plate's plane);
* every half-lap slot: at a through node of a ``halflap`` joint, the outline has edges on both lines
  parallel to the in-plane node axis at half the slot width; every end cut: an edge on the line parallel to
  the axis at the set-back.

The outline of each plate in its frame — its section in the mid-plane, the mean of its two faces (which differ
where its top edge is bevelled, :mod:`fabrication.beams.bevel_cut`) — is kept in :attr:`FolderData.plate_outlines`,
and the union of its faces, the outline cut from the sheet, in :attr:`FolderData.plate_cut_outlines` for the placement
check.
"""

from __future__ import annotations


import numpy as np

from . import Verification, check
from .bevels import plate_faces
from ._shapes import boundary_distance, edges_on_line, face_outline, frame_of, literal, number, solid_points, \
    to_frame, torsion_tolerance


def _notch_depths(row: dict) -> dict[int, float]:
    """Node → the depth (mm) of the deepest notch the plate of ``row`` has there under a strip of another beam
    (``parts.csv`` ``notches``, rounded there to 0.01 mm: the half of it is added back); empty without notches."""
    cell = literal(row.get("notches", "")) if row.get("notches") else None
    out: dict[int, float] = {}
    for n in cell if isinstance(cell, list) else []:
        if isinstance(n, dict) and isinstance(n.get("node"), int) and isinstance(n.get("depth_mm"), (int, float)):
            out[n["node"]] = max(out.get(n["node"], 0.0), float(n["depth_mm"]) + 0.005)
    return out


def _node_plates(v: Verification) -> dict[int, dict[str, dict]]:
    """vertex → part id → the plate record of nodes.json (role, trim_mm)."""
    files = v.manifest.get("files", {})
    rel = files.get("nodes_json")
    if rel is None:
        return {}
    doc = v.read_json(rel)
    if doc is None:
        return {}
    out: dict[int, dict[str, dict]] = {}
    nodes = doc.get("nodes", []) if isinstance(doc, dict) else []
    for k, node in enumerate(nodes if isinstance(nodes, list) else []):
        try:
            out[int(node["vertex"])] = {b["part_id"]: {**b, "joint": node.get("joint"),
                                                       "slot_width_mm": node.get("slot_width_mm")}
                                        for b in node.get("beams", [])}
        except (AttributeError, KeyError, TypeError, ValueError):
            v.error(rel, f"nodes[{k}]", "is not a node record (vertex, joint, beams of part_id and role)")
    return out


def _common_line(a: np.ndarray, b: np.ndarray, near: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The line of two unit planes ``(4,)``: the point nearest to ``near`` and the unit direction; ``None``
    when they are (nearly) parallel."""
    d = np.cross(a[:3], b[:3])
    s = float(np.linalg.norm(d))
    if s < 1e-9:
        return None
    d = d / s
    # the point x with a·x + a_d = 0, b·x + b_d = 0 nearest to `near`: solve in the span of the normals
    n = np.stack([a[:3], b[:3]])
    rhs = -np.array([a[3], b[3]]) - n @ near
    x = near + n.T @ np.linalg.solve(n @ n.T, rhs)
    return x, d


def _smallest_sine(q: np.ndarray, s: np.ndarray, frame: dict, plane: np.ndarray, vertices: np.ndarray,
                   others: set[int], plane_tol: float) -> float:
    """``sin θ`` of the smallest angle between the in-plane node axis ``s`` (unit, 2D) at the top point ``q``
    and the mesh edges from the node to ``others`` that lie in the plate's ``plane`` (its top edges); 1 when
    none does (the strip's half-width is then the distance)."""
    near = [w for w in others if abs(float(vertices[w] @ plane[:3] + plane[3])) <= plane_tol + 1e-6]
    if not near:
        return 1.0
    d = to_frame(vertices[near], frame)[:, :2] - q
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    return max(float(np.abs(d[:, 0] * s[1] - d[:, 1] * s[0]).min()), 1e-3)


@check("step_geometry")
def check_step_geometry(v: Verification) -> None:
    solids = v.beam_solids
    mesh = v.mesh
    node_rows = v.nodes
    if not solids or mesh is None or node_rows is None:
        return
    m = v.manifest
    rel = m.get("files", {}).get("beams_step", "beams.step")
    fab = m.get("fabrication", {})
    t = float(fab.get("beam_thickness", 0.0))
    depth = float(fab.get("beam_depth", 0.0))
    plane_tol = float(fab.get("beams", {}).get("plane_tolerance", fab.get("beam_plane_tolerance", 0.5)))
    tors_tol, tors_key = torsion_tolerance(m)
    axes = {int(r["vertex"]): np.array([number(r[c]) for c in ("axis_x", "axis_y", "axis_z")]) for r in node_rows}
    plates_at = _node_plates(v)
    outlines = v.read.plate_outlines
    cut_outlines = v.read.plate_cut_outlines
    neighbours: dict[int, set[int]] = {}
    for i, j in np.asarray(mesh.edges, dtype=int).tolist():
        neighbours.setdefault(i, set()).add(j)
        neighbours.setdefault(j, set()).add(i)
    planes: dict[str, np.ndarray] = {}
    for row in (v.parts or []):
        pl_ = literal(row.get("plane", "")) if row["kind"] == "beam" else None
        if isinstance(pl_, list) and len(pl_) == 4:
            arr = np.asarray(pl_, dtype=float)
            planes[row["part_id"]] = arr / np.linalg.norm(arr[:3])
    for row in (v.parts or []):
        pid = row["part_id"]
        if row["kind"] != "beam" or pid not in solids:
            continue
        frame = frame_of(row)
        plane = literal(row.get("plane", ""))
        nodes = literal(row.get("nodes", ""))
        if frame is None or not isinstance(plane, list) or len(plane) != 4 or not isinstance(nodes, list):
            v.error("parts.csv", pid, "frame, plane or nodes of the beam plate cannot be read")
            continue
        plane = np.asarray(plane, dtype=float)
        plane = plane / np.linalg.norm(plane[:3])
        notched = _notch_depths(row)
        solid = solids[pid]
        local = to_frame(solid_points(solid), frame)
        off = float(np.abs(np.abs(local[:, 2]) - 0.5 * t).max()) if len(local) else float("inf")
        if off > 1e-6:
            v.error(rel, pid, f"solid is not the plate of its frame in parts.csv: a vertex is {off:.3g} mm off the "
                              f"faces at ±{0.5 * t:g} mm")
            continue
        tilt = float(np.linalg.norm(np.cross(frame["normal"], plane[:3])))
        shift = abs(float(frame["origin"] @ plane[:3] + plane[3]))
        if tilt > 1e-9 or shift > 1e-6:
            v.error("parts.csv", pid, f"the plate frame is not in the support plane (turned {np.degrees(tilt):.3g}°, "
                                      f"{shift:.3g} mm off)")
        faces = plate_faces(solid, frame)
        if faces is None:
            ring = face_outline(solid, frame["normal"])
            if ring is None:
                v.error(rel, pid, "solid has no face in its plate plane")
                continue
            poly = to_frame(ring, frame)[:, :2]
            cut_outlines[pid] = poly
        else:
            if faces.mid is None:
                v.error(rel, pid, "its two faces do not have the same corners in the same order (a plate, or one "
                                  "bevelled under its strips)")
                continue
            poly = faces.mid
            cut_outlines[pid] = faces.cut
        outlines[pid] = poly
        for k in nodes:
            k = int(k)
            if not 0 <= k < len(mesh.vertices) or k not in axes:
                v.error("parts.csv", pid, f"node {k} does not exist")
                continue
            name = f"{pid} at N{k:04d}"
            p = mesh.vertices[k]
            dist = abs(float(p @ plane[:3] + plane[3]))
            if dist > plane_tol + 1e-6:
                v.error(rel, name, f"the node is {dist:.3g} mm from the plate's plane (beams.plane_tolerance "
                                   f"{plane_tol:g} mm)")
                continue
            a = axes[k]
            lean = depth * abs(float(a @ plane[:3]))
            if lean > tors_tol + 1e-6:
                v.error(rel, name, f"the node axis leaves the plate's plane by {lean:.3g} mm at beam depth "
                                   f"{depth:g} mm ({tors_key} {tors_tol:g} mm)")
            info = plates_at.get(k, {}).get(pid, {})
            width = number(info.get("slot_width_mm"), 0.0) if info.get("role") == "through" else 0.0
            trim = number(info.get("trim_mm"), 0.0)
            q = to_frame(p[None], frame)[0, :2]
            s = to_frame((p + a)[None], frame)[0, :2] - q            # the node axis in the plate, 2D
            if np.linalg.norm(s) < 1e-9:
                continue
            s = s / np.linalg.norm(s)
            gap = float(boundary_distance(q[None], poly)[0])
            allowed = (0.5 * width + trim) / _smallest_sine(q, s, frame, plane, mesh.vertices,
                                                           neighbours.get(k, set()), plane_tol)
            allowed += notched.get(k, 0.0)
            if gap > allowed + 1e-6:
                v.error(rel, name, f"the node's top point is {gap:.3g} mm from the plate's outline "
                                   f"(at most {allowed:.3g} mm where slot, end cut and notch take material away)")
                continue
            side = np.array([-s[1], s[0]])
            if info.get("joint") == "halflap" and info.get("role") == "through" and width > 0:
                # the slot is centred on the common line of this plate's plane and its partner's: the node
                # axis through the node, unless the node lies a little off a plane (within plane_tolerance)
                partner = [b for b, i in plates_at.get(k, {}).items() if b != pid and i.get("role") == "through"]
                centre, along = q, s
                if len(partner) == 1 and partner[0] in planes:
                    line = _common_line(plane, planes[partner[0]], p)
                    if line is not None:
                        c3, d3 = line
                        centre = to_frame(c3[None], frame)[0, :2]
                        along = to_frame((c3 + d3)[None], frame)[0, :2] - centre
                        along = along / np.linalg.norm(along)
                side_c = np.array([-along[1], along[0]])
                for sign in (-1.0, 1.0):
                    if not edges_on_line(poly, centre + sign * 0.5 * width * side_c, along, 1e-6):
                        v.error(rel, name, f"no slot wall on the node axis {'+-'[sign < 0]}{0.5 * width:.4g} mm "
                                           f"to the side (slot width {width:.4g} mm, nodes.json)")
            if info.get("role") == "end" and trim > 0:
                if not any(edges_on_line(poly, q + sign * trim * side, s, 1e-6) for sign in (-1.0, 1.0)):
                    v.error(rel, name, f"no end cut parallel to the node axis at its set-back {trim:.4g} mm")
    v.checked.append("step_geometry")
