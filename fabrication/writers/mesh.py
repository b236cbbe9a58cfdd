"""``mesh.obj`` (the mesh in mm; a constructed regular patch in row-major order, a mesh file in its own vertex
order) and ``mesh.json`` (grid in row-major order, face image, the support planes and node axes of the
support structure that was fabricated, and for a mesh file ``obj_vertex``: the OBJ vertex of each grid
vertex)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING


from ppfab import __version__
from ppfab.io import grid_to_json, write_obj
from ppfab.mesh import QuadGrid
from ppfab.support.structure import SupportStructure

from . import Files, writer
from ._json import json_text

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord


def grid_with_support(grid: QuadGrid, support: SupportStructure) -> QuadGrid:
    """``grid`` carrying the fabricated structure's node axes and, for each family whose polylines all lie in
    their planes with the axes, its support planes (``support_u`` rows, ``support_w`` columns)."""
    ids = support.mesh.grid_ids
    assert ids is not None and ids.shape == grid.shape
    m1 = grid.shape[0]
    planes, planar = support.polyline_planes, support.polyline_planar
    assert planar is not None, "SupportStructure.__post_init__ sets polyline_planar"
    rows, cols = slice(0, m1), slice(m1, None)
    return replace(grid, axes=support.axes[ids],
                   support_u=planes[rows] if planar[rows].all() else None,
                   support_w=planes[cols] if planar[cols].all() else None)


def mesh_files(build: "BuildRecord") -> Files:
    """mesh.obj, and mesh.json for a regular patch."""
    mesh = build.mesh
    grid = mesh if isinstance(mesh, QuadGrid) else mesh.grid
    return {"mesh_obj": "mesh.obj", **({"mesh_json": "mesh.json"} if grid is not None else {})}


@writer("mesh", order=10, declare=mesh_files)
def write_mesh_files(build: "BuildRecord", out: Path, files: Files) -> str:
    mesh = build.mesh
    write_obj(mesh, out / "mesh.obj", header=f"ppfab {__version__} — {build.design.info.name}")
    grid = mesh if isinstance(mesh, QuadGrid) else mesh.grid
    if grid is not None:
        doc = grid_to_json(grid_with_support(grid, build.support))
        if not isinstance(mesh, QuadGrid) and mesh.grid_ids is not None:
            # a regular patch recovered from a mesh file: mesh.obj keeps the file's vertex order, mesh.json
            # the grid's row-major order; obj_vertex[k] is the OBJ vertex of grid vertex k
            doc["obj_vertex"] = [int(x) for x in mesh.grid_ids.reshape(-1)]
        (out / "mesh.json").write_text(json_text(doc), encoding="utf-8")
    return "mesh.obj"
