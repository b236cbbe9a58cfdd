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
    placed = {name: scene.graph[name] for name in names if name in rows}
    closed, volumes = mesh_facts({g: scene.geometry[g] for _, g in placed.values()})
    for name, (transform, geometry) in placed.items():
        row = rows[name]
        mesh = scene.geometry[geometry]
        if not closed[geometry]:
            v.error(rel, name, "mesh is not closed")
            continue
        pts = trimesh.transform_points(mesh.vertices, transform) @ back.T
        if row["kind"] == "screw":                 # a prism per screw of the plate, at its stations
            check_screw_points(v, rel, row, pts, eps=2e-7 * float(np.abs(pts).max()) + 1e-3)
            continue
        # float32 vertices: about 1e-7 of the structure's size
        eps = 2e-7 * float(np.abs(pts).max()) + 1e-6
        volume = abs(volumes[geometry]) * abs(np.linalg.det(transform[:3, :3])) * 1e9
        # the writer's vertex order: the base rings (the outline's, then each bolt hole's), then the top rings;
        # a hole is a polygon of its circle's area, so the volume is the area less the holes times the thickness
        holes = int(float(row.get("holes") or 0)) if row["kind"] in ("beam", "splice") else 0
        half = len(pts) // 2
        k = half - holes * GLB_HOLE_SEGMENTS
        # the top outline ring: a plate bevelled under its strips has two different faces (as in beams.step)
        check_part_solid(v, rel, row, pts, volume, eps=eps, volume_tol=1e-4, ring=pts[:max(k, 0)], holes=True,
                         top_ring=pts[half:half + max(k, 0)])
    v.checked.append("glb")


BATCH_TRIANGLES = 200_000
"""Triangles :func:`mesh_facts` measures at once: the arrays of a batch take about 0.3 kB a triangle (60 MB),
where the whole of model.glb at 44 × 30 faces at once took 370 MB more than the scene."""


def mesh_facts(meshes: dict[str, Any], batch: int = BATCH_TRIANGLES) -> tuple[dict[str, bool], dict[str, float]]:
    """Of every mesh (name → a trimesh with ``vertices (n, 3)`` and ``faces (m, 3)``), in batches of meshes of
    about ``batch`` triangles: whether it is closed — every edge shared by exactly two of its triangles, as
    trimesh's ``is_watertight`` has it — and its signed volume (the divergence theorem over its triangles, about
    its vertices' centre), in its own units.  An instanced shape (one mesh placed by many nodes) is measured
    once."""
    import itertools

    closed: dict[str, bool] = {}
    volumes: dict[str, float] = {}
    # a mesh's batch: the triangles before it, in whole batches
    before = np.cumsum([0] + [len(m.faces) for m in meshes.values()])[:-1] // max(batch, 1)
    for _, group in itertools.groupby(zip(before.tolist(), meshes), key=lambda kn: kn[0]):
        c, w = _batch_facts({n: meshes[n] for _, n in group})
        closed.update(c)
        volumes.update(w)
    return closed, volumes


def _batch_facts(meshes: dict[str, Any]) -> tuple[dict[str, bool], dict[str, float]]:
    """:func:`mesh_facts` of a batch of meshes, all at once."""
    names = list(meshes)
    if not names:
        return {}, {}
    verts = [np.asarray(meshes[n].vertices, dtype=float).reshape(-1, 3) for n in names]
    faces = [np.asarray(meshes[n].faces, dtype=np.int64).reshape(-1, 3) for n in names]
    # a triangle naming a vertex the mesh does not have: the mesh is not closed (and is left out of the sums)
    broken = [len(f) > 0 and (int(f.min()) < 0 or int(f.max()) >= len(v)) for v, f in zip(verts, faces)]
    faces = [f[:0] if bad else f for f, bad in zip(faces, broken)]
    n_verts = np.array([len(x) for x in verts])
    n_faces = np.array([len(f) for f in faces])
    offset = np.concatenate([[0], np.cumsum(n_verts)[:-1]])
    mesh_of_face = np.repeat(np.arange(len(names)), n_faces)
    tri = np.concatenate(faces) + np.repeat(offset, n_faces)[:, None]                      # (F, 3) global ids
    centre = np.stack([np.bincount(np.repeat(np.arange(len(names)), n_verts), weights=c, minlength=len(names))
                       for c in np.concatenate(verts).T], axis=1) / np.maximum(n_verts, 1)[:, None]
    p = np.concatenate(verts) - np.repeat(centre, n_verts, axis=0)                         # about each centre
    a, b, c = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
    six = np.einsum("ij,ij->i", a, np.cross(b, c))
    volume = np.bincount(mesh_of_face, weights=six, minlength=len(names)) / 6.0
    # every edge (its two vertex ids, smaller first) once per triangle using it: closed iff each appears twice
    e = np.sort(tri[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    key = e[:, 0] * (int(n_verts.sum()) + 1) + e[:, 1]
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    bad = np.bincount(np.repeat(mesh_of_face, 3), weights=counts[inverse.reshape(-1)] != 2, minlength=len(names))
    return ({n: bool(bad[k] == 0 and n_faces[k] > 0 and not broken[k]) for k, n in enumerate(names)},
            {n: float(volume[k]) for k, n in enumerate(names)})
