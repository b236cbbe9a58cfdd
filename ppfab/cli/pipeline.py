"""``ppfab build``: design → mesh → support → beams → panels → nesting → files → report → manifest.

Each stage is a function ``stage(ctx)`` reading and adding entries of
``ctx.data``; :data:`STAGES` lists them in order, so the benchmark can time
them and the tests can inject a failure at any of them.  Nothing is written
outside the temporary output folder, and every fabrication check runs before
the files that depend on it are written.
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .. import __version__
from ..errors import FabricationError, GeometryError, PpfabError
from ..mesh import QuadGrid, QuadMesh
from .design import Design
from .output import Progress

log = logging.getLogger("ppfab")

# measured on the 2-core reference machine (benchmarks/pipeline.py): seconds per panel for the whole
# fabrication pipeline, and bytes of memory per vertex; used to warn before very large builds
SECONDS_PER_PANEL = 0.02
BYTES_PER_VERTEX = 20_000


class TooLargeError(PpfabError):
    exit_code = 2


@dataclass
class BuildContext:
    design: Design
    out: Path
    progress: Progress
    allow_large: bool = False
    data: dict[str, Any] = field(default_factory=dict)
    files: dict[str, Any] = field(default_factory=dict)


def _json_dump(obj: Any) -> str:
    return json.dumps(obj, indent=2, sort_keys=False, default=_plain) + "\n"


def _plain(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


# -- stages -------------------------------------------------------------------------------------

@dataclass
class Geometry:
    """The placed mesh (mm) with what the geometry stage learned about it."""

    mesh: QuadGrid | QuadMesh
    planar_families: tuple[str, ...]
    source: str
    optimize_result: Any = None


def build_geometry(design: Design, allow_large: bool = True, progress: Progress | None = None) -> Geometry:
    """Construct the mesh (or read it, optionally optimise it) and place it in millimetres."""
    from ..constructions import get_construction
    from ..schema import parse_params
    from ..io import load_mesh
    from ..similarity import transform

    geo = design.geometry
    result = None
    if geo.method is not None:
        construction = get_construction(geo.method)
        record = parse_params(construction.params, geo.params, "geometry.params")
        expected = getattr(record, "expected_vertices", None)
        if expected is not None:
            _check_size(int(expected()), geo.max_vertices, allow_large)
        mesh = construction.build(record)
        families = tuple(geo.planar_families or get_construction(geo.method).planar_families)
        source = f"method:{geo.method}"
    else:
        mesh = load_mesh(design.mesh_path())
        opt = design.optimize
        optimised = {"rows": ("rows",), "cols": ("cols",), "both": ("rows", "cols")}.get(
            getattr(opt, "families", ""), ()) if opt is not None else ()
        families = tuple(geo.planar_families or optimised)
        source = f"mesh:{geo.mesh}"
        if opt is not None:
            from ..optimize import optimize

            if progress:
                progress.note("optimising…")
            result = optimize(mesh, opt)
            if not result.targets_met:
                log.warning("optimisation did not meet its targets: %s", result.message)
            mesh = result.mesh
    nverts = mesh.vertices.shape[0] * (mesh.vertices.shape[1] if mesh.vertices.ndim == 3 else 1)
    _check_size(nverts, geo.max_vertices, allow_large)
    mesh = transform(mesh, geo.scale, geo.rotate_z_deg, geo.translate, geo.flip_orientation)
    return Geometry(mesh, families, source, result)


def _check_size(nverts: int, limit: int, allow_large: bool) -> None:
    """Refuse (before the expensive stages) a mesh above ``geometry.max_vertices`` unless allowed."""
    if nverts > limit and not allow_large:
        raise TooLargeError(
            f"the design makes about {nverts} vertices (> geometry.max_vertices = {limit}); "
            f"fabrication would need about {nverts * SECONDS_PER_PANEL / 60:.0f} min and "
            f"{nverts * BYTES_PER_VERTEX / 2**30:.1f} GiB — pass --allow-large to proceed")


def stage_geometry(ctx: BuildContext) -> None:
    """Stage 1: :func:`build_geometry`."""
    geo = ctx.design.geometry
    ctx.progress.start("geometry", f"construction '{geo.method}'" if geo.method else f"mesh {geo.mesh}")
    g = build_geometry(ctx.design, ctx.allow_large, ctx.progress)
    ctx.data.update(mesh=g.mesh, planar_families=g.planar_families, source=g.source)
    if g.optimize_result is not None:
        ctx.data["optimize"] = g.optimize_result
    mesh = g.mesh
    shape = mesh.shape if isinstance(mesh, QuadGrid) else (mesh.grid.shape if mesh.grid is not None else None)
    ctx.progress.done(f"{'grid ' + 'x'.join(map(str, shape)) if shape else 'quad mesh'}")


def stage_quality(ctx: BuildContext) -> None:
    """Measure δ_f, δ_P, deviation (mm), conical residual and folds; a folded mesh stops the build."""
    from ..metrics import quality

    ctx.progress.start("quality")
    q = quality(ctx.data["mesh"])
    ctx.data["quality"] = q
    if q.flipped_edges:
        raise GeometryError(f"the mesh is folded: {q.flipped_edges} edge(s) join faces with opposite normals "
                            "(the surface passes through a cuspidal edge)", element="mesh", value=q.flipped_edges)
    if q.degenerate_edges:
        raise GeometryError(f"the mesh has {q.degenerate_edges} zero-length edge(s)", element="mesh")
    ctx.progress.done(f"δ_f max {q.delta_f_max:.1e}, δ_P rows {q.delta_p_rows_max:.1e} "
                      f"cols {q.delta_p_cols_max:.1e}, panel deviation {q.deviation_abs_max:.2g} mm")


def stage_mesh_files(ctx: BuildContext) -> None:
    """Write the mesh (OBJ, row-major on a patch) and its support structure (JSON)."""
    from ..io import grid_to_json, write_obj

    ctx.progress.start("mesh files")
    mesh = ctx.data["mesh"]
    write_obj(mesh, ctx.out / "mesh.obj", header=f"ppfab {__version__} — {ctx.design.info.name}")
    ctx.files["mesh_obj"] = "mesh.obj"
    grid = mesh if isinstance(mesh, QuadGrid) else mesh.grid
    if grid is not None:
        (ctx.out / "mesh.json").write_text(_json_dump(grid_to_json(grid)), encoding="utf-8")
        ctx.files["mesh_json"] = "mesh.json"
    ctx.progress.done("mesh.obj")


from . import stages as _fab  # noqa: E402

STAGES: list[tuple[str, Callable[[BuildContext], None]]] = [
    ("geometry", stage_geometry),
    ("quality", stage_quality),
    ("support", _fab.stage_support),
    ("panels", _fab.stage_panels),      # panel planarity (mm) is the root cause of most beam defects: check it first
    ("beams", _fab.stage_beams),
    ("nesting", _fab.stage_nesting),
    ("mesh_files", stage_mesh_files),
    ("files", _fab.stage_files),
    ("report", _fab.stage_report),
]


def run_stages(ctx: BuildContext, stages: list[tuple[str, Callable[[BuildContext], None]]] | None = None) -> None:
    for _, fn in (stages or STAGES):
        try:
            fn(ctx)
        except BaseException:
            ctx.progress.fail()
            raise


def _sha256(path: Path) -> str:
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _listed_files(files: dict[str, Any]) -> list[str]:
    out: list[str] = []
    for value in files.values():
        if isinstance(value, str):
            out.append(value)
        elif isinstance(value, (list, tuple)):
            out.extend(v for v in value if isinstance(v, str))
    return sorted(set(out))


def stage_manifest(ctx: BuildContext) -> None:
    """Write manifest.json: generator, units, design, mesh, fabrication parameters, files, quality, sha256."""
    from ..schema import as_plain

    ctx.progress.start("manifest")
    mesh = ctx.data["mesh"]
    grid = mesh if isinstance(mesh, QuadGrid) else mesh.grid
    mesh_entry: dict[str, Any] = {"path": ctx.files.get("mesh_obj", "mesh.obj"),
                                  "planar_families": list(ctx.data.get("planar_families", ()))}
    if grid is not None:
        mesh_entry.update(rows=int(grid.shape[0]), cols=int(grid.shape[1]), closed=bool(grid.closed))
    qm = mesh.to_quadmesh() if isinstance(mesh, QuadGrid) else mesh
    mesh_entry.update(vertices=int(len(qm.vertices)), faces=int(len(qm.faces)))
    fabrication = _fab.fabrication_params(ctx)
    design = ctx.design
    manifest = {
        "generator": f"ppfab {__version__}",
        "units": "mm",
        "design": {"name": design.info.name, "method": design.geometry.method or "mesh",
                   "source": design.source if design.source != str(_default_design()) else "bundled default",
                   "sha256": design.sha256,
                   "geometry": as_plain(design.geometry)},
        "mesh": mesh_entry,
        "fabrication": fabrication,
        "files": ctx.files,
        "quality": {k: v for k, v in ctx.data["quality"].as_dict().items()},
        "summary": ctx.data.get("summary", {}),
    }
    manifest["sha256"] = {name: _sha256(ctx.out / name) for name in _listed_files(ctx.files)}
    (ctx.out / "manifest.json").write_text(_json_dump(manifest), encoding="utf-8")
    ctx.data["manifest"] = manifest
    ctx.progress.done(f"{len(manifest['sha256'])} files")


def _default_design() -> Path:
    from .design import DEFAULT_DESIGN

    return DEFAULT_DESIGN


STAGES.append(("manifest", stage_manifest))
