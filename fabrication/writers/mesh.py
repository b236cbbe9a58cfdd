"""``mesh.obj`` (the mesh in mm; a regular patch in row-major order) and ``mesh.json`` (grid, support planes,
face image, node axes)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ppfab import __version__
from ppfab.io import grid_to_json, write_obj
from ppfab.mesh import QuadGrid

from . import Files, writer
from ._json import json_text

if TYPE_CHECKING:  # pragma: no cover
    from ..build.records import Build


@writer("mesh", order=10)
def write_mesh_files(build: "Build", out: Path, files: Files) -> str:
    mesh = build.mesh
    write_obj(mesh, out / "mesh.obj", header=f"ppfab {__version__} — {build.design.info.name}")
    files["mesh_obj"] = "mesh.obj"
    grid = mesh if isinstance(mesh, QuadGrid) else mesh.grid
    if grid is not None:
        (out / "mesh.json").write_text(json_text(grid_to_json(grid)), encoding="utf-8")
        files["mesh_json"] = "mesh.json"
    return "mesh.obj"
