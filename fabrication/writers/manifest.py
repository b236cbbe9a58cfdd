"""``manifest.json``: generator, units, design, mesh, fabrication parameters, files, quality, summary and the
sha256 of every file listed — written last.  It holds no absolute path: the design file by its name (with
its sha256, and the mesh file's), so a build does not depend on where it ran."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ppfab import __version__
from ppfab.mesh import QuadGrid, as_quadmesh
from ppfab.schema import as_plain

from . import Files, writer
from .base import listed_files
from ._json import json_text

if TYPE_CHECKING:  # pragma: no cover
    from ..design import Design
    from ..records import BuildRecord


def sha256_of(path: Path) -> str:
    """Hex sha256 of a file, read in 1 MiB chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def fabrication_params(design: "Design") -> dict[str, Any]:
    """Every fabrication parameter used, for ``manifest.json['fabrication']``."""
    out: dict[str, Any] = {}
    out.update(design.beams.manifest())
    panels = design.panels
    nesting = design.nesting
    out.update({"panel_gap": panels.gap, "planarity_tolerance": panels.planarity_tolerance,
                "max_crease_deg": panels.max_crease_deg,
                "glass_thickness": panels.thickness, "glass_makeup": panels.makeup,
                "sheet": list(nesting.sheet), "sheet_margin": nesting.margin, "part_spacing": nesting.spacing})
    for name in ("support", "beams", "panels", "glazing", "splices", "nesting", "beam_nesting", "output"):
        out[name] = as_plain(design.section(name))
    return out


def manifest(build: "BuildRecord", out: Path, files: Files) -> dict[str, Any]:
    """The manifest document for a build written into ``out`` with the ``files`` table."""
    from ..design import DEFAULT_DESIGN

    mesh = build.mesh
    grid = mesh if isinstance(mesh, QuadGrid) else mesh.grid
    mesh_entry: dict[str, Any] = {"path": files.get("mesh_obj", "mesh.obj"),
                                  "planar_families": list(build.geometry.planar_families)}
    if grid is not None:
        mesh_entry.update(rows=int(grid.shape[0]), cols=int(grid.shape[1]), closed=bool(grid.closed))
    qm = as_quadmesh(mesh)
    mesh_entry.update(vertices=int(len(qm.vertices)), faces=int(len(qm.faces)))
    design = build.design
    geometry = as_plain(design.geometry)
    entry: dict[str, Any] = {"name": design.info.name, "method": design.geometry.method or "mesh",
                             "source": "bundled default" if design.source == str(DEFAULT_DESIGN)
                             else Path(design.source).name, "sha256": design.sha256}
    mesh_file = design.mesh_path()
    if mesh_file is not None:
        # only relative paths: the folder must not depend on where it was built (byte-identical builds)
        if Path(str(geometry["mesh"])).is_absolute():
            geometry["mesh"] = mesh_file.name
        entry["mesh_sha256"] = sha256_of(mesh_file)
    entry["geometry"] = geometry
    doc: dict[str, Any] = {
        "generator": f"ppfab {__version__}",
        "units": "mm",
        "design": entry,
        "mesh": mesh_entry,
        "fabrication": fabrication_params(design),
        "files": files,
        "quality": dict(build.quality.as_dict().items()),
        "summary": build.summary.as_dict(),
    }
    from ..repetition import repetition

    doc["repetition"] = repetition(build)
    g = build.glazing
    if g is not None:
        doc["glazing"] = {"support": g.params.support, "strips": len(g.strips), "offset_mm": g.offset,
                          "bite_min_mm": None if not g.bites else round(g.bite_min, 4),
                          "min_bite_mm": design.panels.min_bite, "splices": len(g.splices),
                          "cover_plates": 2 * len(g.splices), "welds": len(g.welds),
                          "welded_splices": sum(w.joint == "splice" for w in g.welds)}
    doc["sha256"] = {name: sha256_of(out / name) for name in listed_files(files)}
    return doc


@writer("manifest", order=90, declare=lambda build: {})
def write_manifest(build: "BuildRecord", out: Path, files: Files) -> str:
    doc = manifest(build, out, files)
    (out / "manifest.json").write_text(json_text(doc), encoding="utf-8")
    return f"{len(doc['sha256'])} files"
