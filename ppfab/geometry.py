"""What to build, and building it: a construction or a quad mesh file, optionally optimised, placed in mm.

:class:`GeometrySpec` is the ``[geometry]`` table of a design file (validated by
:func:`ppfab.schema.parse_params`); :func:`build_geometry` turns it into a
:class:`Geometry`: the placed mesh, the polyline families that are planar by
construction (or by optimisation), where it came from and the optimiser's
record.  This is geometry-core work: numpy and scipy only, no file formats
beyond the mesh readers of :mod:`ppfab.io`.

Examples
--------
>>> from ppfab.geometry import GeometrySpec, build_geometry
>>> spec = GeometrySpec(method="translational", scale=1000.0,
...                     params={"a_points": [[-4, 0], [0, 1], [4, 0]], "b_points": [[-3, 0], [0, 0.5], [3, 0]],
...                             "faces_u": 4, "faces_v": 3})
>>> g = build_geometry(spec)
>>> g.mesh.shape, g.planar_families
((5, 4), ('rows', 'cols'))
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from .errors import DesignError, PpfabError
from .mesh import QuadGrid, QuadMesh
from .schema import param
from .topology import FAMILY_NAMES, families_of

log = logging.getLogger("ppfab")

# measured on the 2-core reference machine (benchmarks/pipeline.py): seconds per panel for the whole
# fabrication pipeline, and bytes of memory per vertex; used to warn before very large builds
SECONDS_PER_PANEL = 0.02
BYTES_PER_VERTEX = 20_000
MESH_FILE_BYTES_PER_VERTEX = 1024
"""A generous bound on the bytes of a text mesh file per vertex (a ``v`` line, its share of ``f`` lines, normals
and texture coordinates): a larger file is refused from its size, before it is read."""

class TooLargeError(PpfabError):
    """The design makes more vertices than ``geometry.max_vertices`` (checked before the expensive work)."""

    exit_code = 2


@dataclass(frozen=True)
class GeometrySpec:
    """What to build: a construction (``method`` + ``params``) or a quad mesh file (``mesh``), placed in mm."""

    method: str | None = param(None, doc="a registered construction (see `ppfab methods`)")
    mesh: str | None = param(None, doc="a quad mesh file (.obj/.off) instead of a construction; "
                                       "relative to the design file")
    params: dict = param({}, doc="parameters of the construction ([geometry.params])")
    scale: float = param(1.0, doc="factor from construction/mesh units to millimetres", exclusive_min=0)
    translate: list[float] = param([0.0, 0.0, 0.0], doc="translation in mm after scaling", length=3)
    rotate_z_deg: float = param(0.0, doc="rotation about the vertical axis after scaling, degrees", min=-360, max=360)
    flip_orientation: bool = param(False, doc="reverse the face orientation (which side is outside)")
    planar_families: list[str] | None = param(None, doc="families the beams follow: 'rows', 'cols' "
                                                        "(default: what the construction keeps planar)")
    max_vertices: int = param(250_000, doc="refuse larger meshes unless --allow-large is given", min=4)

    def __post_init__(self) -> None:
        if (self.method is None) == (self.mesh is None):
            raise DesignError("method" if self.method is None else "mesh",
                              "give exactly one of 'method' (a construction) or 'mesh' (a file)")
        if self.planar_families is not None:
            for k, fam in enumerate(self.planar_families):
                if fam not in FAMILY_NAMES:
                    raise DesignError(f"planar_families[{k}]", f"must be 'rows' or 'cols', got {fam!r}")

    def mesh_path(self, base_dir: Path | None = None) -> Path | None:
        """The mesh file, relative paths taken from ``base_dir`` (the design file's folder)."""
        if self.mesh is None:
            return None
        p = Path(self.mesh)
        return p if p.is_absolute() or base_dir is None else (base_dir / p)


@dataclass(frozen=True)
class Geometry:
    """The placed mesh (mm) with what the geometry stage learned about it.

    ``planar_families`` names the families (``"rows"``, ``"cols"``) that are planar by construction or were
    made planar by the optimiser; ``source`` is ``"method:<name>"`` or ``"mesh:<file>"``;
    ``optimize_result`` the :class:`~ppfab.optimize.OptimizeResult` when ``[optimize]`` ran;
    ``surface_deviation_mm`` the largest distance of a vertex to the designer's surface (``[surface]``).
    """

    mesh: QuadGrid | QuadMesh
    planar_families: tuple[str, ...]
    source: str
    optimize_result: Any = None
    surface_deviation_mm: float | None = None


def build_geometry(spec: GeometrySpec, optimize: Any = None, base_dir: Path | None = None,
                   allow_large: bool = True, note: Callable[[str], None] | None = None,
                   on_iteration: Callable[[Any], None] | None = None,
                   before_optimize: Callable[[QuadGrid | QuadMesh, tuple[str, ...]], None] | None = None) -> Geometry:
    """Construct the mesh (or read it and optionally optimise it) and place it in millimetres.

    Parameters
    ----------
    spec : the ``[geometry]`` record
    optimize : an :class:`~ppfab.optimize.params.OptimizeParams` record, or ``None``: the mesh as read or as
        constructed is optimised by it (§3.3)
    base_dir : folder that relative mesh paths are taken from
    allow_large : go on above ``spec.max_vertices``
    note : called with a short progress text before long steps
    on_iteration : called with every optimiser :class:`~ppfab.optimize.solver.IterationRecord`
    before_optimize : called with the mesh as read (file units) and the planar families asked for, before the
        optimiser runs; it may raise to refuse a design whose outcome is known from the input
    """
    from .constructions import get_construction
    from .io import load_mesh
    from .schema import parse_params
    from ppfab.transforms.similarity import transform

    result = None
    mesh: QuadGrid | QuadMesh
    optimised = families_of(getattr(optimize, "families", "")) if optimize is not None else ()
    if spec.method is not None:
        construction = get_construction(spec.method)
        record = parse_params(construction.params, spec.params, "geometry.params")
        expected = getattr(record, "expected_vertices", None)
        if expected is not None:
            check_size(int(expected()), spec.max_vertices, allow_large)
        mesh = construction.build(record)
        families = tuple(spec.planar_families or optimised or construction.planar_families)
        source = f"method:{spec.method}"
    else:
        path = spec.mesh_path(base_dir)
        assert path is not None
        check_file_size(path, spec.max_vertices, allow_large)
        mesh = load_mesh(path, None if allow_large else lambda n: check_size(n, spec.max_vertices, False))
        families = tuple(spec.planar_families or optimised)
        source = f"mesh:{spec.mesh}"
    if optimize is not None:            # a mesh as read, or a construction's mesh (e.g. a PP mesh made conical)
        from .optimize import optimize as run_optimize

        if before_optimize is not None:
            before_optimize(mesh, families)

        if note:
            note("optimising…")
        result = run_optimize(mesh, optimize, callback=on_iteration)
        if not result.targets_met:
            from .optimize.outcome import UNMET_NEXT

            log.warning("optimisation did not meet its targets: %s; %s", result.message, UNMET_NEXT)
        mesh = result.mesh
    check_size(vertex_count(mesh), spec.max_vertices, allow_large)
    mesh = transform(mesh, spec.scale, spec.rotate_z_deg, spec.translate, spec.flip_orientation)
    return Geometry(mesh, families, source, result)


def vertex_count(mesh: QuadGrid | QuadMesh) -> int:
    """Number of vertices of a grid ``(m+1)(n+1)`` or of a quad mesh ``N``."""
    v = mesh.vertices
    return int(v.shape[0] * (v.shape[1] if v.ndim == 3 else 1))


def check_file_size(path: Path, limit: int, allow_large: bool) -> None:
    """Refuse, from its size alone and before reading it, a mesh file too large to hold ``limit`` vertices
    (and anything that is not a regular file: a FIFO, a device)."""
    from .io.meshfile import regular_file

    size = regular_file(path, "mesh file")
    most = MESH_FILE_BYTES_PER_VERTEX * limit + (1 << 20)
    if size > most and not allow_large:
        raise TooLargeError(f"{path}: the file has {size / 2**20:.0f} MiB, more than a mesh of geometry.max_vertices "
                            f"= {limit} vertices needs (at most {most / 2**20:.0f} MiB) — pass --allow-large to proceed")


def check_size(nverts: int, limit: int, allow_large: bool) -> None:
    """Refuse (before the expensive stages) a mesh above ``geometry.max_vertices`` unless allowed."""
    if nverts > limit and not allow_large:
        raise TooLargeError(
            f"the design makes about {nverts} vertices (> geometry.max_vertices = {limit}); "
            f"fabrication would need about {nverts * SECONDS_PER_PANEL / 60:.0f} min and "
            f"{nverts * BYTES_PER_VERTEX / 2**30:.1f} GiB — pass --allow-large to proceed")
