"""The design file (TOML): what to build and how to fabricate it.

Sections (every key is documented in the README, ``ppfab methods`` lists the
construction parameters)::

    [design]            name, description
    [geometry]          method | mesh, scale, translate, rotate_z_deg, flip_orientation, planar_families
    [surface]           instead of method | mesh: a surface (.3dm, triangle mesh) remeshed into a net
    [geometry.params]   the parameters of the chosen construction
    [optimize]          optional: optimise the mesh (read or constructed) for the P/PP property first
    [support]           how the node axes / support planes are found
    [beams]             beam plates and joints
    [panels]            glass panels
    [glazing]           the strips the glass rests on (bite, gasket)
    [splices]           bolted or welded splices of beams cut into pieces
    [nesting]           stock sheets for the glass
    [beam_nesting]      stock sheets for the beam plates
    [output]            which optional files to write

Every problem is a :class:`~ppfab.errors.DesignError` naming the key path,
printed as one line and exit code 2 by the command line.
"""

from __future__ import annotations

import hashlib
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

from ppfab.errors import DesignError
from ppfab.geometry import GeometrySpec
from ppfab.schema import param, parse_params, suggest

if TYPE_CHECKING:  # pragma: no cover
    from ppfab.optimize.params import OptimizeParams
    from ppfab.support.params import SupportParams
    from ppfab.surface.spec import SurfaceSpec

    from .beams.params import BeamParams
    from .glazing.params import GlazingParams
    from .glazing.splices import SpliceParams
    from .nesting import NestingParams
    from .panels import PanelParams


DEFAULT_DESIGN = Path(__file__).resolve().parent / "data" / "default.toml"
"""The bundled default example (a PP gridshell roof), built by ``ppfab build`` without a design file."""


@dataclass(frozen=True)
class DesignInfo:
    name: str = param("untitled", doc="name shown in the report and manifest")
    description: str = param("", doc="free text")
    date: str = param("", doc="issue date in the drawings' title blocks (e.g. 2026-12-01); empty: the date of "
                              "SOURCE_DATE_EPOCH when set, else none")


@dataclass(frozen=True)
class OutputSection:
    panels_step: bool = param(True, doc="also write panels.step (glass as thin solids, for clash checks)")
    report: bool = param(True, doc="write report.html")
    per_type_dxf: bool = param(True, doc="write one flat DXF per panel type")
    type_dimensions: bool = param(True, doc="dimension the edges and both diagonals in the per-type DXFs "
                                            "(layer DIM)")
    dxf_r12: bool = param(False, doc="also write every cutting sheet and per-type DXF as DXF R12, in dxf_r12/ "
                                     "(for legacy cutting tables)")
    dxf_r2000: bool = param(False, doc="also write every cutting sheet and per-type DXF as DXF R2000, in dxf_r2000/")
    ifc: bool = param(True, doc="write model.ifc (IFC4: an IfcPlate per pane, an IfcMember per beam plate, with "
                                "property sets)")
    rhino: bool = param(True, doc="write model.3dm (Rhino: layers per family, objects named by part id, user text, "
                                  "node axes, the mesh)")
    glb: bool = param(True, doc="write model.glb (glTF binary for viewing; node names are the part ids)")
    paper: str = param("A1", doc="paper size of the drawings in drawings/ (frame, title block, standard scale): "
                                 "A1, A0 (a large roof's key plan) or A3",
                       choices=("A0", "A1", "A3"))
    classification: dict = param({}, doc="classification of the parts in model.ifc ([output.classification]): "
                                         "system (e.g. \"Uniclass 2015\"), optional edition and source, and a code "
                                         "per part kind (panel, beam, strip, splice, setting_block, …), e.g. "
                                         "panel = \"Pr_xx_xx_xx Glass panes\": the code, then an optional title")

    def __post_init__(self):
        from .contract import PART_KINDS

        c = self.classification
        for key, value in c.items():
            where = f"output.classification.{key}"
            if key not in ("system", "edition", "source") and key not in PART_KINDS:
                raise DesignError(where, f"is neither system, edition, source nor a part kind "
                                         f"({', '.join(PART_KINDS)}): remove it or name a part kind")
            if not isinstance(value, str) or not value.strip():
                raise DesignError(where, "must be a non-empty string (a code, then an optional title)")
        if any(k in PART_KINDS for k in c) and "system" not in c:
            raise DesignError("output.classification.system", "missing: name the classification system the codes "
                                                              "belong to, e.g. system = \"Uniclass 2015\"")


def _section_types() -> dict[str, Callable[[], type]]:
    """Section name → its parameter dataclass (imported lazily: fabrication is heavy)."""
    def beams():
        from fabrication.beams.params import BeamParams
        return BeamParams

    def panels():
        from fabrication.panels import PanelParams
        return PanelParams

    def nesting():
        from fabrication.nesting import NestingParams
        return NestingParams

    def glazing():
        from fabrication.glazing.params import GlazingParams
        return GlazingParams

    def splices():
        from fabrication.glazing.splices import SpliceParams
        return SpliceParams

    def optimize():
        from ppfab.optimize.params import OptimizeParams
        return OptimizeParams

    def support():
        from ppfab.support.params import SupportParams
        return SupportParams

    def surface():
        from ppfab.surface.spec import SurfaceSpec
        return SurfaceSpec

    return {
        "design": lambda: DesignInfo,
        "geometry": lambda: GeometrySpec,
        "surface": surface,
        "optimize": optimize,
        "support": support,
        "beams": beams,
        "panels": panels,
        "glazing": glazing,
        "splices": splices,
        "nesting": nesting,
        "beam_nesting": nesting,
        "output": lambda: OutputSection,
    }


SECTION_DEFAULTS: dict[str, dict[str, Any]] = {
    # plate stock for the beams differs from glass stock: 6 m x 2 m steel plate
    "nesting": {"tag_prefix": "G"},
    "beam_nesting": {"sheet": [6000.0, 2000.0], "time_budget": 5.0, "tag_prefix": "B"},
}
"""Defaults that differ between sections sharing one parameter record."""

SECTION_TEXT: dict[str, str] = {
    "design": "Name and description shown in the report and the manifest.",
    "geometry": "What to build: a construction (`method` + `[geometry.params]`) or a quad mesh file (`mesh`), "
                "and its placement in millimetres.",
    "surface": "Instead of `[geometry] method` or `mesh`: a designer's surface (Rhino .3dm, triangle mesh) remeshed "
               "into a quad net (`net`: planar sections and their conjugate curves, curvature lines, or two families "
               "of planar sections; docs/remeshing.md); `[optimize]` then makes the "
               "panels planar, staying close to that surface.",
    "optimize": "Optional: optimise the mesh (read from `mesh = …` or constructed by `method = …`) for planar faces and "
                "planar polylines first (§3.3), e.g. a PP construction made conical with `keep_conical`.",
    "support": "How the node axes and support planes are found.",
    "beams": "Planar beam plates along the support planes and their joints.",
    "panels": "Glass panels.",
    "glazing": "The glazing strips the panes rest on, their gaskets and the bite check (docs/glazing.md).",
    "splices": "Splices where a long beam is cut into pieces: bolted cover plates, or full-penetration butt welds "
               "where the edges are too short for a cover plate (docs/glazing.md).",
    "nesting": "Glass stock sheets and the nesting of the panels.",
    "beam_nesting": "Plate stock for the beam plates (same keys as `[nesting]`; defaults: sheet 6000 × 2000, "
                    "budget 5 s, tag prefix `B`).",
    "output": "Optional files.",
}
"""What each section is for (the README's key tables and the comments of ``ppfab new``)."""


@dataclass(frozen=True)
class Design:
    """A parsed, validated design file."""

    source: str
    sha256: str
    base_dir: Path
    info: DesignInfo
    geometry: GeometrySpec
    sections: dict[str, Any] = field(default_factory=dict)
    raw: dict = field(default_factory=dict)

    def section(self, name: str) -> Any:
        """The record of a section by name (defaults when absent); the typed properties below name each one."""
        return self.sections[name]

    @property
    def optimize(self) -> "OptimizeParams | None":
        """``[optimize]``, or ``None`` when the design file has no such section."""
        return self.sections.get("optimize") if "optimize" in self.raw else None

    @property
    def surface(self) -> "SurfaceSpec | None":
        """``[surface]``, or ``None`` when the design names a construction or a quad mesh."""
        return self.sections.get("surface")

    @property
    def support(self) -> "SupportParams":
        return self.sections["support"]

    @property
    def beams(self) -> "BeamParams":
        return self.sections["beams"]

    @property
    def panels(self) -> "PanelParams":
        return self.sections["panels"]

    @property
    def glazing(self) -> "GlazingParams":
        return self.sections["glazing"]

    @property
    def splices(self) -> "SpliceParams":
        return self.sections["splices"]

    @property
    def nesting(self) -> "NestingParams":
        """Glass stock sheets (``[nesting]``)."""
        return self.sections["nesting"]

    @property
    def beam_nesting(self) -> "NestingParams":
        """Plate stock for the beams (``[beam_nesting]``)."""
        return self.sections["beam_nesting"]

    @property
    def output(self) -> OutputSection:
        return self.sections["output"]

    def mesh_path(self) -> Path | None:
        """The mesh file of ``[geometry] mesh``, relative to the design file's folder."""
        return self.geometry.mesh_path(self.base_dir)

    def input_files(self) -> list[Path]:
        """The files this design reads (the design file, the mesh file): an output folder must not hold them."""
        out = [Path(self.source)] if self.sha256 else []
        mesh = self.mesh_path()
        return out + ([mesh] if mesh is not None else [])


def _check_tag_prefixes(records: dict[str, Any]) -> None:
    """Nest tags are ``<prefix><sheet>-<part>``: unique only when the glass and plate prefixes differ (also in
    letter case, as a CAM program may ignore it) and neither ends in a digit (``G1`` + sheet 03 would read as
    ``G`` + sheet 103)."""
    prefixes = {name: records[name].tag_prefix for name in ("nesting", "beam_nesting") if name in records}
    for name, prefix in prefixes.items():
        if not prefix.isascii() or not prefix[-1:].isalpha():
            raise DesignError(f"{name}.tag_prefix", f"must be ASCII letters and digits ending in a letter, got "
                                                    f"{prefix!r} (the sheet number follows it)")
    if len(prefixes) == 2 and prefixes["nesting"].lower() == prefixes["beam_nesting"].lower():
        raise DesignError("beam_nesting.tag_prefix", f"{prefixes['beam_nesting']!r} is also the glass prefix "
                                                     f"([nesting] tag_prefix {prefixes['nesting']!r}): nest tags "
                                                     "would repeat; give the beam plates another prefix")


def parse_design(doc: dict, source: str = "<dict>", sha256: str = "", base_dir: Path | None = None,
                 sections: tuple[str, ...] | None = None) -> Design:
    """Validate a design document (already parsed TOML) into a :class:`Design`."""
    types = _section_types()
    for key, value in doc.items():
        if key not in types:
            raise DesignError(key, "unknown section" + suggest(key, list(types)) +
                              f"; valid sections: {', '.join(types)}")
        if not isinstance(value, dict):
            raise DesignError(key, f"must be a table ([{key}]), got {type(value).__name__}")
    if "geometry" not in doc and "surface" not in doc:
        raise DesignError("geometry", "missing required section [geometry] (with 'method' or 'mesh')")
    wanted = sections or tuple(types)
    records: dict[str, Any] = {}      # section name -> its parameter record (types differ by section)
    for name in wanted:
        if name == "surface" and "surface" not in doc:
            continue
        table = dict(doc.get(name, {}))
        if name == "geometry" and "surface" in doc:
            table = _surface_geometry(table, doc["surface"])
        for key, value in SECTION_DEFAULTS.get(name, {}).items():
            table.setdefault(key, value)
        records[name] = parse_params(types[name](), table, name)
    _check_tag_prefixes(records)
    geometry: GeometrySpec = records["geometry"]
    _check_mesh_path(geometry)
    if geometry.method is not None:
        from ppfab.constructions import get_construction

        c = get_construction(geometry.method)
        parse_params(c.params, geometry.params, "geometry.params")   # validate early
    elif geometry.params:
        raise DesignError("geometry.params", "only a construction ('method') takes parameters")
    return Design(source=source, sha256=sha256, base_dir=base_dir or Path.cwd(),
                  info=records["design"], geometry=geometry, sections=records, raw=doc)


def _surface_geometry(table: dict, surface: dict) -> dict:
    """``[geometry]`` of a design with ``[surface]``: no method or mesh of its own (the surface file stands as
    its input file), and no scale (the surface's units say how long a millimetre is)."""
    for key in ("method", "mesh", "params"):
        if key in table:
            raise DesignError(f"geometry.{key}", "a design with [surface] builds on its surface: leave out "
                                                 "[geometry] method, mesh and params")
    if table.get("scale", 1.0) != 1.0:
        raise DesignError("geometry.scale", "a [surface] is read in its own units (a .3dm states them, a mesh "
                                            "declares [surface] units): leave scale out")
    path = surface.get("path") if isinstance(surface, dict) else None
    return {**table, "mesh": path if isinstance(path, str) and path else "surface"}


MAX_DESIGN_BYTES = 1 << 20
"""A design file is a few kB of TOML; anything above 1 MiB is refused from its size, before it is read."""

MAX_DESIGN_DEPTH = 16
"""Deepest nesting of tables and arrays in a design file (the deepest a design needs is 5: ``geometry.params``
holding a list of points); deeper nesting is refused, as is nesting too deep for the TOML reader itself."""


def _check_depth(doc: dict) -> None:
    """Refuse tables and arrays nested deeper than :data:`MAX_DESIGN_DEPTH`, naming the first key path that
    does (walked without recursion)."""
    stack: list[tuple[Any, str, int]] = [(doc, "", 0)]
    while stack:
        value, key, depth = stack.pop()
        if depth > MAX_DESIGN_DEPTH:
            raise DesignError(key, f"tables and arrays nested more than {MAX_DESIGN_DEPTH} levels deep; "
                                   "a design file needs at most 5")
        if isinstance(value, dict):
            stack.extend((v, f"{key}.{k}" if key else str(k), depth + 1) for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((v, f"{key}[{i}]", depth + 1) for i, v in enumerate(value))


def _check_mesh_path(geometry: GeometrySpec) -> None:
    """``[geometry] mesh`` must be a usable path string: not empty, no NUL or other control character."""
    from ppfab.io.pathtext import path_problem, printable

    if geometry.mesh is None:
        return
    problem = path_problem(geometry.mesh)
    if problem == "is empty":
        raise DesignError("geometry.mesh", "the mesh path is empty; give the path of the mesh file (.obj or .off, "
                                           "relative to the design file), or a construction with 'method'")
    if problem is not None:
        raise DesignError("geometry.mesh", f"the path '{printable(geometry.mesh)}' {problem}; give the path of "
                                           "the mesh file (.obj or .off)")


def _regular_design_file(p: Path) -> None:
    """A design path must be a regular file: a FIFO or a device is refused before it is opened."""
    from ppfab.errors import MeshFileError
    from ppfab.io.meshfile import regular_file

    try:
        size = regular_file(p, "design file")
    except MeshFileError as exc:
        raise DesignError("", str(exc).replace("cannot read (", "cannot read design file (")) from None
    if size > MAX_DESIGN_BYTES:
        raise DesignError("", f"{p}: {size / 2**20:.1f} MiB is not a design file (at most "
                              f"{MAX_DESIGN_BYTES // 2**20} MiB of TOML)")


def load_design(path: str | Path | None = None, sections: tuple[str, ...] | None = None) -> Design:
    """Read and validate a design file; ``None`` loads the bundled default example."""
    if path is not None and os.fspath(path) == "":
        raise DesignError("", "the design file path is empty; give the path of a design file (.toml)")
    p = DEFAULT_DESIGN if path is None else Path(path)
    _regular_design_file(p)
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise DesignError("", f"{p}: cannot read design file ({exc.strerror or exc})") from None
    if len(data) > MAX_DESIGN_BYTES:
        raise DesignError("", f"{p}: {len(data) / 2**20:.1f} MiB is not a design file (at most "
                              f"{MAX_DESIGN_BYTES // 2**20} MiB of TOML)")
    try:
        doc = tomllib.loads(data.decode("utf-8-sig"))
    except UnicodeDecodeError:
        raise DesignError("", f"{p}: design file is not UTF-8 text") from None
    except tomllib.TOMLDecodeError as exc:
        raise DesignError("", f"{p}: malformed TOML: {exc}") from None
    except RecursionError:
        raise DesignError("", f"{p}: tables and arrays nested too deep to read (more than {MAX_DESIGN_DEPTH} "
                              "levels; a design file needs at most 5)") from None
    try:
        _check_depth(doc)
        return parse_design(doc, str(p), hashlib.sha256(data).hexdigest(), p.resolve().parent, sections)
    except DesignError as exc:
        raise DesignError(exc.key, f"{str(exc)[len(exc.key) + 2:] if exc.key else str(exc)} (in {p})") from None
