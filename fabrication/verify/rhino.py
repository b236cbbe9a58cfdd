"""model.3dm: the contract layers; one closed extrusion per part, named by part id, on its layer, with the
parts.csv values as user text, on its mesh face or support plane; one axis line per node; the mesh.

A part of a repeated shape is an instance of a block (:func:`placed_objects`): the block's one member placed by
the instance's transform, which must be a rigid motion, is checked like any part's own body."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..contract import EXCHANGE_PROPERTIES, RETENTION_KINDS, RHINO_LAYERS, csv_value
from . import Verification, check, read_csv
from ._shapes import open_ring
from ._solids import check_names, check_screw_points, check_part_solid, polygon_area_3d


def _points(curve) -> np.ndarray:
    """``(n, 3)`` a polyline curve's points, the closing point left out (one call into rhino3dm per point)."""
    pts = np.array([(p.X, p.Y, p.Z) for p in map(curve.Point, range(curve.PointCount))], dtype=float).reshape(-1, 3)
    return open_ring(pts)


def _mesh_points(mesh) -> np.ndarray:
    """``(n, 3)`` a rhino3dm mesh's vertices (one call into rhino3dm for all of them, not three per vertex)."""
    return np.array([(p.X, p.Y, p.Z) for p in mesh.Vertices.ToPoint3dArray()], dtype=float).reshape(-1, 3)


def _check_two_face_mesh(v: Verification, rel: str, row: dict[str, str], g) -> None:
    """A beam plate written as a closed mesh (its two faces differ: bevelled under its strips): the writer's vertex
    order — the base rings (the outline's, then each bolt hole's), then the top rings — gives its two outline
    rings; its volume by the divergence theorem over the mesh's triangles (numpy, not the writer's mesh)."""
    from ..contract import GLB_HOLE_SEGMENTS

    if not g.IsClosed:
        v.error(rel, row["part_id"], "is not a closed mesh")
        return
    pts = _mesh_points(g)
    faces = g.Faces
    tri = np.array([faces[i][:3] for i in range(faces.Count)], dtype=int).reshape(-1, 3)
    c0 = pts.mean(axis=0)                         # about the centre: no cancellation of large coordinates
    a, b, c = pts[tri[:, 0]] - c0, pts[tri[:, 1]] - c0, pts[tri[:, 2]] - c0
    volume = abs(float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6.0)
    half = len(pts) // 2
    k = half - int(float(row.get("holes") or 0)) * GLB_HOLE_SEGMENTS
    # rhino3dm reads a mesh's vertices back in single precision: about 1e-7 of the coordinates
    eps = 2e-7 * float(np.abs(pts).max(initial=0.0)) + 1e-4
    check_part_solid(v, rel, row, pts, volume, eps=eps, volume_tol=1e-4, ring=pts[:max(k, 0)], holes=True,
                     top_ring=pts[half:half + max(k, 0)])


def _curve_area(curve, samples: int = 720) -> float:
    """The area inside a closed planar curve (an inner profile): ``π r²`` of a complete circle (a bolt hole),
    else from ``samples`` points along it."""
    if getattr(curve, "IsCompleteCircle", False):
        return float(np.pi * curve.Radius ** 2)
    d = curve.Domain
    ts = np.linspace(d.T0, d.T1, samples, endpoint=False)
    pts = np.array([(p.X, p.Y, p.Z) for p in map(curve.PointAt, ts)], dtype=float)
    return polygon_area_3d(pts)


RIGID_TOLERANCE = 1e-9
"""Largest entry of ``Rᵀ R − I`` (and ``|det R − 1|``) of an instance's transform read as a rigid motion."""


@dataclass(frozen=True)
class PlacedObject:
    """An object of the model as it is seen: ``attributes`` its own (name, layer, user text), ``geometry`` its body
    where it stands — a block instance's member duplicated and moved by the instance's transform; ``block`` the
    name of that block, ``""`` for an object that is its own body."""

    attributes: Any
    geometry: Any
    block: str = ""


def placed_objects(f: Any) -> tuple[list[PlacedObject], list[tuple[str, str]]]:
    """The model objects of the 3dm archive ``f`` (rhino3dm ``File3dm``) with block instances resolved, and the
    problems found on the way as ``(subject, message)``: an instance of a missing block, a block of other than
    one member, a transform that is not a rigid motion (that part is left out, so it is also named as missing), a
    block member that belongs to no block.  Block members themselves (instance-definition objects) are not model
    objects."""
    import rhino3dm as _rhino3dm

    r: Any = _rhino3dm
    members = {}
    placed: list[PlacedObject] = []
    problems: list[tuple[str, str]] = []
    for obj in f.Objects:
        if obj.Attributes.Mode == r.ObjectMode.InstanceDefinitionObject:
            members[obj.Attributes.Id] = obj
    used = set()
    for obj in f.Objects:
        a = obj.Attributes
        if a.Mode == r.ObjectMode.InstanceDefinitionObject:
            continue
        g = obj.Geometry
        if not isinstance(g, r.InstanceReference):
            placed.append(PlacedObject(a, g))
            continue
        name = a.Name or "(unnamed)"
        block = f.InstanceDefinitions.FindId(g.ParentIdefId)
        if block is None:
            problems.append((name, f"instance of block {g.ParentIdefId}, which is not in the file"))
            continue
        ids = list(block.GetObjectIds())
        if len(ids) != 1 or ids[0] not in members:
            problems.append((name, f"block {block.Name!r} holds {len(ids)} member(s), expected one body"))
            continue
        used.add(ids[0])
        x = g.Xform
        m = np.array([[getattr(x, f"M{i}{j}") for j in range(4)] for i in range(4)])
        rot = m[:3, :3]
        if np.abs(m[3] - [0.0, 0.0, 0.0, 1.0]).max() > RIGID_TOLERANCE or \
                np.abs(rot.T @ rot - np.eye(3)).max() > RIGID_TOLERANCE or \
                abs(np.linalg.det(rot) - 1.0) > RIGID_TOLERANCE:
            problems.append((name, f"the transform of its block {block.Name!r} is not a rigid motion"))
            continue
        body = members[ids[0]].Geometry.Duplicate()
        if not body.Transform(x):
            problems.append((name, f"the body of block {block.Name!r} cannot be moved by its transform"))
            continue
        placed.append(PlacedObject(a, body, block.Name))
    for key in sorted(members.keys() - used, key=str):
        problems.append((f"block member {key}", "is the body of no placed block"))
    return placed, problems


@check("rhino")
def check_rhino(v: Verification) -> None:
    m = v.manifest
    rel = m.get("files", {}).get("rhino")
    if rel is None:
        return
    import rhino3dm as _rhino3dm

    rhino3dm: Any = _rhino3dm                   # its stubs miss the iteration protocols
    f = rhino3dm.File3dm.Read(str(v.folder / rel))
    if f is None:
        v.error(rel, "", "cannot be read by rhino3dm")
        return
    if f.Settings.ModelUnitSystem != rhino3dm.UnitSystem.Millimeters:
        v.error(rel, "units", f"model units are {f.Settings.ModelUnitSystem}, expected millimetres")
    layers = [la.FullPath for la in f.Layers]
    for name in RHINO_LAYERS:
        if name not in layers:
            v.error(rel, name, "layer is missing")
    rows = {r["part_id"]: r for r in (v.parts or [])}
    parts, axes, meshes = [], [], []
    objects, problems = placed_objects(f)
    for subject, problem in problems:
        v.error(rel, subject, problem)
    for obj in objects:
        a = obj.attributes
        layer = layers[a.LayerIndex] if 0 <= a.LayerIndex < len(layers) else "?"
        if layer == "nodes":
            axes.append(obj)
        elif layer == "mesh":
            meshes.append(obj)
        else:
            parts.append((a.Name, layer, obj))
    check_names(v, rel, [n for n, _, _ in parts], {k: r["kind"] for k, r in rows.items()}, "Rhino object")
    for name, layer, obj in parts:
        row = rows.get(name)
        if row is None:
            continue
        if row["kind"] == "panel":
            want = "glass"
        elif row["kind"] in RETENTION_KINDS:
            want = f"retention::{row['kind']}"
        else:
            want = f"beams::{row.get('family', '')}"
        if layer != want:
            v.error(rel, name, f"is on layer {layer}, expected {want}")
        text = dict(obj.attributes.GetUserStrings())
        for key in EXCHANGE_PROPERTIES:
            cell = csv_value(row.get(key, "") or (row.get("mass_kg", "") if key == "weight_kg" else ""))
            if cell and text.get(key) != cell:
                v.error(rel, name, f"user text {key} is {text.get(key)!r}, parts.csv has {cell!r}")
        g = obj.geometry
        if row["kind"] == "screw":                 # the screws of a plate: one closed mesh of a prism per screw
            if not isinstance(g, rhino3dm.Mesh) or not g.IsClosed:
                v.error(rel, name, "is not a closed mesh")
                continue
            pts = _mesh_points(g)
            # rhino3dm reads a mesh's vertices back in single precision: about 1e-7 of the coordinates
            check_screw_points(v, rel, row, pts, eps=2e-7 * float(np.abs(pts).max(initial=0.0)) + 1e-3)
            continue
        if row["kind"] == "beam" and isinstance(g, rhino3dm.Mesh):     # a plate bevelled under its strips
            _check_two_face_mesh(v, rel, row, g)
            continue
        if not isinstance(g, rhino3dm.Extrusion) or not g.IsSolid:
            v.error(rel, name, "is not a closed extrusion")
            continue
        bottom, top = _points(g.Profile3d(0, 0.0)), _points(g.Profile3d(0, 1.0))
        height = float(np.linalg.norm(top.mean(axis=0) - bottom.mean(axis=0)))
        area = polygon_area_3d(bottom) - sum(_curve_area(g.Profile3d(k, 0.0)) for k in range(1, g.ProfileCount))
        check_part_solid(v, rel, row, np.concatenate([bottom, top]), area * height, ring=bottom, holes=True)
    mesh = v.mesh
    nodes_rel = m.get("files", {}).get("nodes_csv")
    if nodes_rel and mesh is not None:
        nodes = {r["node_id"]: r for r in read_csv(v.folder / nodes_rel)}
        readable = {r["node_id"] for r in (v.nodes or [])}     # rows whose cells the nodes check read
        check_names(v, rel, [a.attributes.Name for a in axes], {k: "node" for k in nodes}, "node axis")
        for obj in axes:
            row = nodes.get(obj.attributes.Name)
            if row is None or row["node_id"] not in readable:
                continue
            g = obj.geometry
            start = np.array([g.PointAtStart.X, g.PointAtStart.Y, g.PointAtStart.Z])
            end = np.array([g.PointAtEnd.X, g.PointAtEnd.Y, g.PointAtEnd.Z])
            k = int(row["vertex"])
            axis = np.array([float(row[c]) for c in ("axis_x", "axis_y", "axis_z")])
            d = end - start
            if np.abs(start - mesh.vertices[k]).max() > 1e-6 or np.linalg.norm(np.cross(d, axis)) > 1e-6 * max(
                    1.0, float(np.linalg.norm(d))) or d @ axis <= 0:
                v.error(rel, row["node_id"], "axis line does not start at its vertex along its node axis")
    if len(meshes) != 1 or not isinstance(meshes[0].geometry, rhino3dm.Mesh):
        v.error(rel, "mesh", f"{len(meshes)} objects on layer mesh, expected the mesh")
    elif mesh is not None:
        g = meshes[0].geometry
        pts = _mesh_points(g)
        if len(pts) != len(mesh.vertices) or len(g.Faces) != len(mesh.faces) or \
                np.abs(pts - mesh.vertices).max() > 1e-2:           # read back in single precision
            v.error(rel, "mesh", f"{len(pts)} vertices, {len(g.Faces)} faces differ from mesh.obj")
    v.checked.append("rhino")
