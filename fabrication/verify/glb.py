"""model.glb: one node per part, named by part id, each a closed mesh of the part's volume on its mesh face or
support plane (glTF metres, +Y up, read back into the mm frame of the other files)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..contract import GLB_HOLE_SEGMENTS
from . import Verification, check
from ._solids import check_names, check_part_solid, check_screw_points


@check("glb")
def check_glb(v: Verification) -> None:
    rel = v.manifest.get("files", {}).get("glb")
    if rel is None:
        return
    import trimesh

    from ..writers.glb import MM_TO_GLTF

    scene: Any
    try:
        scene = trimesh.load(str(v.folder / rel), force="scene", process=False)
    except Exception as exc:  # noqa: BLE001 - reported as a finding
        v.error(rel, "", f"cannot be read by trimesh ({exc})")
        return
    rows = {r["part_id"]: r for r in (v.parts or [])}
    names = list(scene.graph.nodes_geometry)
    check_names(v, rel, names, {k: r["kind"] for k, r in rows.items()}, "glTF node")
    back = np.linalg.inv(MM_TO_GLTF)
    for name in names:
        row = rows.get(name)
        if row is None:
            continue
        transform, geometry = scene.graph[name]
        mesh = scene.geometry[geometry]
        if not mesh.is_watertight:
            v.error(rel, name, "mesh is not closed")
            continue
        pts = trimesh.transform_points(mesh.vertices, transform) @ back.T
        if row["kind"] == "screw":                 # a prism per screw of the plate, at its stations
            check_screw_points(v, rel, row, pts, eps=2e-7 * float(np.abs(pts).max()) + 1e-3)
            continue
        # float32 vertices: about 1e-7 of the structure's size
        eps = 2e-7 * float(np.abs(pts).max()) + 1e-6
        volume = abs(float(mesh.volume)) * abs(np.linalg.det(transform[:3, :3])) * 1e9
        # the writer's vertex order: the base rings (the outline's, then each bolt hole's), then the top rings;
        # a hole is a polygon of its circle's area, so the volume is the area less the holes times the thickness
        holes = int(float(row.get("holes") or 0)) if row["kind"] in ("beam", "splice") else 0
        half = len(pts) // 2
        k = half - holes * GLB_HOLE_SEGMENTS
        # the top outline ring: a plate bevelled under its strips has two different faces (as in beams.step)
        check_part_solid(v, rel, row, pts, volume, eps=eps, volume_tol=1e-4, ring=pts[:max(k, 0)], holes=True,
                         top_ring=pts[half:half + max(k, 0)])
    v.checked.append("glb")
