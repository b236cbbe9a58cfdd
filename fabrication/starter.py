"""A commented starter design (``ppfab new``): every section and key of the design schema with its default, and
for a mesh file the sections its measurements call for.

Nothing here repeats a default: the keys, types, defaults and meanings come from the parameter records
(:func:`fabrication.design._section_types`, :data:`~fabrication.design.SECTION_DEFAULTS`, the construction's
``params``).  For a construction method the values that make a design of it are those of the smallest bundled
example of that method (:mod:`fabrication.examples`); a value that differs from the default says so.

For a mesh file, :func:`survey` measures it first — its size (the scale that makes the mean edge about
:data:`TARGET_EDGE_MM`), face planarity ``δ_f`` and polyline planarity ``δ_P`` per family (§3.3), the conical
residual, singular vertices and holes — and :func:`propose` turns that into ``[optimize]``, ``[support]`` and
``[beams]``: both families close to planar (``δ_P ≤`` :data:`CLOSE`) give a PP mesh with half-lap joints, else
the family closer to planar is made planar (a P mesh, segmented joints with that family running through).
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import textwrap
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ppfab.errors import DesignError

PLANAR = 1e-6
"""``δ_f`` / ``δ_P`` at or below this count as planar already (the optimiser's default targets)."""

CLOSE = 1e-2
"""A polyline family with max ``δ_P`` at or below this is close to planar: optimising it planar moves the mesh
little."""

TARGET_EDGE_MM = 1500.0
"""The proposed scale makes the mean edge this long (glass panels of about 1.5 m) …"""

MAX_EDGE_MM = 2800.0
"""… and no edge longer than this (a panel then fits the default 6000 × 3210 mm glass sheet)."""

CONJUGACY_LIMIT = 0.4
"""The default of ``[optimize] max_conjugacy_defect``: above it ``ppfab build`` refuses to optimise the net."""

MAX_NORMAL_ANGLE_DEG = 30.0
"""A polyline whose plane lies further than this from the surface normal cannot be a planar beam (the default of
``[support] max_normal_angle_deg``)."""

DEFAULT_METHOD = "bisector"
"""``ppfab new`` without an argument: a small PP roof."""


@dataclass(frozen=True)
class MeshSurvey:
    """What :func:`survey` measured on a mesh file (lengths in the file's units)."""

    path: Path
    vertices: int
    faces: int
    extent: tuple[float, float, float]
    edge_mean: float
    edge_max: float
    delta_f_max: float
    delta_p_rows_max: float
    delta_p_cols_max: float
    conical_max: float
    singular_vertices: int
    boundary_loops: int
    families_consistent: bool
    grid_shape: tuple[int, int] | None
    conjugacy: float = 0.0
    tilt_max: tuple[float, float] = (0.0, 0.0)
    across: tuple[int, int] = (0, 0)
    polylines: tuple[int, int] = (0, 0)
    kink_max_deg: float = 0.0            # the largest angle between the normals of two neighbouring faces

    @property
    def holes(self) -> int:
        """Boundary loops beyond the outer one (an annulus, closed all round, has two loops and no hole)."""
        return max(0, self.boundary_loops - (2 if self.grid_shape is not None and self.boundary_loops == 2 else 1))

    @property
    def scale(self) -> float:
        """Mesh units → mm: mean edge :data:`TARGET_EDGE_MM`, longest edge at most :data:`MAX_EDGE_MM`, to two
        significant digits (rounded down); 1 when the mesh is in millimetres already."""
        if 500.0 <= self.edge_mean <= 3000.0 and self.edge_max <= MAX_EDGE_MM:
            return 1.0
        s = min(TARGET_EDGE_MM / self.edge_mean, MAX_EDGE_MM / self.edge_max)
        digits = 10.0 ** (math.floor(math.log10(s)) - 1)
        return math.floor(s / digits) * digits


@dataclass(frozen=True)
class Proposal:
    """Sections proposed for a surveyed mesh (``sections``: name → key → value) and why (``reasons``)."""

    sections: dict[str, dict[str, Any]]
    reasons: list[str] = field(default_factory=list)


def _boundary_loops(topo: Any) -> int:
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    edges = topo.edges[topo.edge_face_count == 1]
    if len(edges) == 0:
        return 0
    ids, inv = np.unique(edges, return_inverse=True)
    inv = inv.reshape(-1, 2)
    g = coo_matrix((np.ones(len(inv)), (inv[:, 0], inv[:, 1])), shape=(len(ids), len(ids)))
    return int(connected_components(g, directed=False)[0])


def survey(path: str | os.PathLike) -> MeshSurvey:
    """Measure a quad mesh file (``δ_f``, ``δ_P`` of both families and the conical residual as §3.3 and
    :func:`ppfab.metrics.quality` define them; singular vertices: interior vertices of valence ≠ 4)."""
    from ppfab.io import load_mesh
    from ppfab.metrics import quality
    from ppfab.support.lines import singular_vertices

    from ppfab.metrics import conjugacy_defect, dihedral_angles
    from ppfab.support.lines import polyline_planes
    from ppfab.support.structure import vertex_normals

    mesh = load_mesh(path)
    qm = mesh.to_quadmesh() if hasattr(mesh, "to_quadmesh") else mesh
    q = quality(mesh)
    e = qm.edge_lengths()
    topo = qm.topology
    ext = np.ptp(qm.vertices, axis=0)
    planes = polyline_planes(qm, vertex_normals(qm))
    tilt = [[float(planes.tilt_deg[k]) for k, p in enumerate(qm.polylines)
             if p.family == f and len(p) >= 3 and np.isfinite(planes.tilt_deg[k])] for f in (0, 1)]
    c = np.asarray(qm.vertices, dtype=float)[np.asarray(qm.faces)]
    kinks = dihedral_angles(np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]), topo.edge_faces)
    kink = float(np.nanmax(kinks)) if np.isfinite(kinks).any() else 0.0
    return MeshSurvey(Path(path), len(qm.vertices), len(qm.faces), (float(ext[0]), float(ext[1]), float(ext[2])),
                      float(e.mean()), float(e.max()), q.delta_f_max, q.delta_p_rows_max, q.delta_p_cols_max,
                      q.conical_max, int(singular_vertices(qm).sum()), _boundary_loops(topo),
                      bool(topo.families_consistent), q.grid_shape, conjugacy_defect(qm),
                      (max(tilt[0], default=0.0), max(tilt[1], default=0.0)),
                      (sum(t > MAX_NORMAL_ANGLE_DEG for t in tilt[0]), sum(t > MAX_NORMAL_ANGLE_DEG for t in tilt[1])),
                      (len(tilt[0]), len(tilt[1])), kink)


def propose(s: MeshSurvey) -> Proposal:
    """``[geometry] scale``, ``[optimize]``, ``[support]`` and ``[beams]`` for a surveyed mesh (module docstring)."""
    rows, cols = s.delta_p_rows_max, s.delta_p_cols_max
    reasons = [f"mean edge {s.edge_mean:.4g}, longest {s.edge_max:.4g} (file units): scale {s.scale:g} makes "
               f"the mean edge {s.edge_mean * s.scale:.0f} mm"]
    sections: dict[str, dict[str, Any]] = {"geometry": {"scale": s.scale}}
    if max(s.delta_f_max, rows, cols) <= PLANAR:
        reasons.append(f"δ_f {s.delta_f_max:.1e}, δ_P rows {rows:.1e}, cols {cols:.1e}: a PP mesh already, "
                       "no [optimize] needed")
        families = "both"
    elif max(rows, cols) <= CLOSE:
        reasons.append(f"δ_P rows {rows:.1e} and cols {cols:.1e} are both close to planar (≤ {CLOSE:g}): "
                       "[optimize] families = \"both\" (a PP mesh)")
        families = "both"
    else:
        if s.across[0] != s.across[1]:           # fewer polylines standing across the surface first
            families = "rows" if s.across[0] < s.across[1] else "cols"
            reasons.append(f"δ_P rows {rows:.1e}, cols {cols:.1e}; polylines whose plane lies more than "
                           f"{MAX_NORMAL_ANGLE_DEG:g}° from the normal: rows {s.across[0]}, cols {s.across[1]}: the "
                           f"{families} can carry more planar beams; [optimize] makes them planar (a P mesh), the "
                           "other family is not made planar")
        else:
            families = "rows" if rows <= cols else "cols"
            reasons.append(f"δ_P rows {rows:.1e}, cols {cols:.1e}: the {families} are closer to planar; [optimize] "
                           f"makes them planar (a P mesh), the other family is not made planar")
    planar_now = max(s.delta_f_max, rows, cols) <= PLANAR
    names = ("rows", "cols")
    usable = [s.across[f] < s.polylines[f] for f in (0, 1)]
    if planar_now and not any(usable):
        reasons[-1] = (f"δ_f {s.delta_f_max:.1e}, δ_P rows {rows:.1e}, cols {cols:.1e}: faces and polylines are "
                       f"planar, but every polyline plane lies more than {MAX_NORMAL_ANGLE_DEG:g}° from the surface "
                       f"normal (up to {max(s.tilt_max):.0f}°: a flat or nearly flat mesh), so no planar beam can "
                       "stand in them; this is not a PP gridshell")
    chosen = (0, 1) if families == "both" else (names.index(families),)
    if families == "both" and usable != [True, True] and any(usable):
        keep = names[usable.index(True)]
        reasons.append(f"the {names[usable.index(False)]} all lie in planes more than {MAX_NORMAL_ANGLE_DEG:g}° "
                       f"from the surface normal (up to {s.tilt_max[usable.index(False)]:.0f}°): no planar beam can "
                       f"stand in them, so only the {keep} are made planar beams (a P mesh)")
        families, chosen = keep, (names.index(keep),)
    elif families != "both" and not usable[chosen[0]] and usable[1 - chosen[0]]:
        other = names[1 - chosen[0]]
        reasons.append(f"but the {families} all lie in planes more than {MAX_NORMAL_ANGLE_DEG:g}° from the surface "
                       f"normal (up to {s.tilt_max[chosen[0]]:.0f}°) and cannot carry planar beams: the {other} are "
                       "made planar instead")
        families, chosen = other, (1 - chosen[0],)
    if s.conjugacy > CONJUGACY_LIMIT and not planar_now:
        reasons.append(f"conjugacy defect {s.conjugacy:.2f} (twist over normal curvature; a conjugate net has about "
                       f"0): the net is far from conjugate, so planar quads lie only far from this surface and "
                       f"ppfab build refuses to optimise it above {CONJUGACY_LIMIT:g}; remesh along conjugate curves "
                       "first (ppfab remesh MESH -o NET.obj --search-planes; ppfab new on a surface file writes "
                       "such a design), or raise [optimize] max_conjugacy_defect")
    elif not planar_now:
        reasons.append(f"conjugacy defect {s.conjugacy:.2f} (at most {CONJUGACY_LIMIT:g}): close enough to a "
                       "conjugate net for planar quads near the surface")
    across = sum(s.across[f] for f in chosen)
    if across:
        reasons.append(f"{across} of {sum(s.polylines[f] for f in chosen)} polylines of the "
                       f"{' and '.join(names[f] for f in chosen)} lie in planes more than {MAX_NORMAL_ANGLE_DEG:g}° "
                       f"from the surface normal (up to {max(s.tilt_max[f] for f in chosen):.0f}°) and cannot be "
                       "planar beams: [beams] fallback = \"segmented\" makes their edges one-edge plates "
                       "(`ppfab check MESH --polylines` lists them)")
    if families != "both" or not planar_now:
        sections["optimize"] = {"families": families}
    if families == "both":
        sections["support"] = {"method": "pp"}
        sections["beams"] = {"joint": "halflap"}
    else:
        sections["support"] = {"method": "p", "family": families}
        sections["beams"] = {"joint": "segmented", "continuous": families}
    if across or s.singular_vertices or s.holes or not s.families_consistent:
        sections["beams"]["fallback"] = "segmented"
        reasons.append(f"support method \"p\" (axes in the planes of the {families}); segmented joints: the "
                       f"{families} run through the nodes, the other members are cut between them")
    if s.conical_max <= 1e-3 and "optimize" in sections:
        reasons.append(f"conical residual {s.conical_max:.1e}: the mesh is nearly conical; "
                       "[optimize] keep_conical = true keeps it so (slower)")
    if s.singular_vertices or s.holes or not s.families_consistent:
        reasons.append(f"{s.singular_vertices} singular vertices, {s.holes} holes"
                       + ("" if s.families_consistent else ", polyline families not consistent")
                       + ": polylines that cannot be planar beams are left out ([support] exclude = [\"auto\"]; "
                         "`ppfab check MESH --polylines` lists them) and become one-edge plates ([beams] fallback "
                         "= \"segmented\")")
    gap = _joint_for_screws(s.kink_max_deg)
    if gap is not None:
        sections["panels"] = {"gap": gap}
        reasons.append(f"neighbouring faces kink by up to {s.kink_max_deg:.1f}°: where a kink closes a joint towards "
                       f"the glass's top, the clamping screws of a 10 mm joint would stand in the glass, which the "
                       f"build refuses; [panels] gap = {gap:g} clears them (fabrication.glazing.screws."
                       "joint_clearing_screws, a bound: narrow it where the build's check allows)")
        glazing = _glazing_for_joint(gap)
        if glazing:
            sections["glazing"] = glazing
            reasons.append("so that the panes still bite [panels] min_bite on the strips and the pressure plates "
                           "clamp both panes: " + ", ".join(f"[glazing] {k} = {v:g}" for k, v in glazing.items()))
    return Proposal(sections, reasons)


FLAT_BAR_WIDTHS = (60.0, 70.0, 80.0, 90.0, 100.0, 120.0)
"""mm: standard flat bar widths (EN 10058) a proposed glazing strip or pressure plate is taken from."""


def _glazing_for_joint(gap: float) -> dict[str, float]:
    """``[glazing]`` widths for a joint of ``gap`` mm: a strip wide enough for ``min_bite`` + 5 mm on each side of
    the joint (the kink takes about 3 mm of the bite: the tube mesh of compas_libigl bit 10.8 mm at a 33 mm joint
    on a 60 mm strip), a pressure plate for ``min_clamp_bite`` + 5 mm on each pane (its gasket and the kink take
    some: 2 mm left panes of the same tube mesh unclamped at a quarter of their edges); the next standard width, only
    where the default is narrower."""
    from .glazing.params import GlazingParams
    from .panels.params import PanelParams

    g, p = GlazingParams(), PanelParams()
    out = {}
    for key, default, need in (("width", g.width, gap + 2.0 * (p.min_bite + 5.0)),
                               ("pressure_plate_width", g.pressure_plate_width, gap + 2.0 * (g.min_clamp_bite + 5.0))):
        if need > default:
            out[key] = next((w for w in FLAT_BAR_WIDTHS if w >= need), float(math.ceil(need / 10.0) * 10.0))
    return out


def _joint_for_screws(kink_deg: float) -> float | None:
    """The ``[panels] gap`` (mm, whole) whose default-sized clamping screws clear the glass at a kink of
    ``kink_deg`` with the default strip, gasket and make-up, or ``None`` when the default joint does."""
    from .glazing.params import GlazingParams
    from .glazing.retention_strength import RetentionBolt
    from .glazing.screws import joint_clearing_screws
    from .panels.params import PanelParams

    panels, glazing = PanelParams(), GlazingParams()
    need = joint_clearing_screws(kink_deg, panels.pane_thickness, glazing.thickness + glazing.gasket_thickness,
                                 RetentionBolt.parse(glazing.retention_bolt).diameter)
    return float(math.ceil(need)) if need > panels.gap + 1e-9 else None


def toml_value(v: Any) -> str:
    """A TOML value for ``v`` (bool, number, string, list, table or a parameter record as an inline table).

    >>> toml_value([[0.0, 1e-06], "a"]), toml_value({"x": True})
    ('[[0.0, 1e-06], "a"]', '{ x = true }')
    """
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        v = {f.name: getattr(v, f.name) for f in dataclasses.fields(v)}
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ("nan" if math.isnan(v) else ("inf" if v > 0 else "-inf"))
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }" if v else "{}"
    raise TypeError(f"no TOML value for {v!r}")


def _defaults(cls: type, overrides: dict[str, Any] | None = None) -> list[tuple[str, Any, bool, str]]:
    """``(key, default, required, doc)`` of every field of a parameter record."""
    out = []
    for f in dataclasses.fields(cls):
        if f.default is not dataclasses.MISSING:
            d, req = f.default, False
        elif f.default_factory is not dataclasses.MISSING:
            d, req = f.default_factory(), False
        else:
            d, req = None, True
        if overrides and f.name in overrides:
            d = overrides[f.name]
        out.append((f.name, d, req, str(f.metadata.get("doc", ""))))
    return out


def _comment(text: str, indent: str = "") -> list[str]:
    return [indent + "# " + ln for ln in textwrap.wrap(text, 104)] if text else []


def _section(title: str, about: str, cls: type, values: dict[str, Any], overrides: dict[str, Any] | None = None,
             active: bool = True, skip: tuple[str, ...] = (), why: dict[str, str] | None = None) -> list[str]:
    """One section: its purpose, then per key its meaning and ``key = value`` (default, or the value given
    with the default noted); ``active = False`` comments the whole section out."""
    c = "" if active else "# "
    lines = [""] + _comment(about) + [f"{c}[{title}]"]
    for key, default, required, doc in _defaults(cls, overrides):
        if key in skip:
            continue
        lines += _comment(doc)
        if key in values:
            note = ("required" if required else f"default: {toml_value(default)}" if default is not None
                    else "default: none") if values[key] != default else ""
            if why and key in why:
                note = f"{note}; {why[key]}" if note else why[key]
            lines.append(f"{c}{key} = {toml_value(values[key])}" + (f"    # {note}" if note else ""))
        elif default is None:
            lines.append(f"# {key} =    # {'required' if required else 'default: none (not set)'}")
        else:
            lines.append(f"{c}{key} = {toml_value(default)}")
    return lines


def _smallest_example(method: str) -> Any:
    """The bundled example of ``method`` with the fewest faces (``None`` when there is none)."""
    from ppfab.geometry import build_geometry

    from .design import load_design
    from .examples import examples

    best, faces = None, math.inf
    for e in examples():
        if e.method != method:
            continue
        d = load_design(e.path)
        mesh = build_geometry(d.geometry, d.optimize, d.base_dir).mesh
        n = mesh.n_faces if hasattr(mesh, "n_faces") else len(mesh.faces)
        if n < faces:
            best, faces = e, n
    return best


def _is_triangle_mesh(source: str) -> bool:
    """Whether an OBJ/OFF file has a face that is not a quad (then it is a surface to remesh)."""
    import trimesh

    if not Path(source).is_file():
        return False
    from ppfab.errors import PpfabError
    from ppfab.io import read_mesh

    try:
        read_mesh(source)
        return False
    except PpfabError:
        try:
            loaded: Any = trimesh.load(source, force="mesh", process=False)
            return len(loaded.faces) > 0
        except Exception:                   # neither a quad mesh nor a triangle mesh: the quad reader's error
            return False


def _surface_start(source: str, out_dir: Path) -> tuple[dict[str, dict[str, Any]], list[str]]:
    """The sections of a starter design on a surface file, and the comment lines that say what was measured:
    a ``[surface]`` (sections net) with P optimisation, the P support and segmented beams."""
    import numpy as np

    from ppfab.errors import GeometryError
    from ppfab.surface import SurfaceSpec, remesh

    from .surfacefile import METRES_BELOW, read_surface

    if not Path(source).is_file():
        raise DesignError("new", f"{source}: no such surface file (.3dm, .obj, .off, .stl, .ply)")
    sf = read_surface(source)
    ext = sf.samples.points.max(axis=0) - sf.samples.points.min(axis=0)
    units = sf.samples.units if sf.kind == "mesh" else None   # the reader's guess, written down
    rel = os.path.relpath(Path(source).resolve(), out_dir).replace(os.sep, "/")
    spacing = float(min(1500.0, max(300.0, np.round(ext[:2].min() / 4.0, -2))))
    surface: dict[str, Any] = {"path": rel, "net": "sections", "spacing": spacing, "search_planes": True}
    if units:
        surface["units"] = units
    try:
        r = remesh(sf.samples, SurfaceSpec(path=rel, spacing=spacing, units=units, search_planes=True))
        n = np.round(r.frame.axes[0], 3).tolist()
        found = (f"the sections net at {spacing:g} mm has {int(r.net.grid_faces.sum())} panels, edges "
                 f"{r.panel_size_min:.2f}–{r.panel_size_max:.2f} × spacing (section planes with normal {n}, the "
                 f"best of {r.planes_tried} directions)")
    except GeometryError as exc:
        found = f"the sections net refuses: {exc}"
    given: dict[str, dict[str, Any]] = {
        "design": {"name": Path(source).stem},
        "surface": surface,
        "optimize": {"families": "rows", "target_delta_f": 1e-7, "target_delta_p": 1e-7, "fairness": "relative",
                     "weight_close": 1.0},
        "support": {"method": "p", "family": "rows"},
        "beams": {"joint": "segmented", "continuous": "rows", "fallback": "segmented"},
    }
    head = [f"# Starter design for the surface {Path(source).name}, written by `ppfab new`.",
            f"# Read: {sf.samples.source}, in {sf.samples.units}"
            + (f" (no units in the file: a mesh under {METRES_BELOW:g} units wide is taken as metres, a wider one "
               "as mm)" if units else "")
            + f"; {ext[0] / 1000:.1f} × {ext[1] / 1000:.1f} × {ext[2] / 1000:.1f} m.",
            f"# Measured: {found}.",
            "# Proposed: rows = the planar sections, made P by [optimize] close to the surface (relative fairness",
            "# and weight_close 1: the net is already on the surface and nearly conjugate); the P support;",
            "# segmented beams (the rows run through)."]
    return given, head


def starter_text(source: str | None, out: str | os.PathLike) -> str:
    """The text of a starter design for a construction method or a mesh file ``source`` (``None``: the default
    method), to be written to ``out`` (a mesh path is written relative to ``out``'s folder)."""
    from ppfab.constructions import get_construction, load_all

    from .design import SECTION_DEFAULTS, SECTION_TEXT, _section_types

    source = source or DEFAULT_METHOD
    out_dir = Path(out).resolve().parent
    given: dict[str, dict[str, Any]] = {}
    head: list[str]
    suffix = Path(source).suffix.lower()
    is_surface = suffix in (".3dm", ".stl", ".ply") or (suffix in (".obj", ".off") and _is_triangle_mesh(source))
    is_mesh = suffix in (".obj", ".off") and not is_surface
    if is_surface:
        given, head = _surface_start(source, out_dir)
        example = None
        method = None
    elif is_mesh:
        if not Path(source).is_file():
            raise DesignError("new", f"{source}: no such mesh file (a quad mesh .obj or .off)")
        s = survey(source)
        prop = propose(s)
        given = {k: dict(v) for k, v in prop.sections.items()}
        rel = os.path.relpath(Path(source).resolve(), out_dir).replace(os.sep, "/")
        given["geometry"]["mesh"] = rel
        given["design"] = {"name": Path(source).stem}
        ext = " × ".join(f"{x * s.scale / 1000:.1f}" for x in s.extent)
        head = [f"# Starter design for the mesh {Path(source).name}, written by `ppfab new`.",
                f"# Measured: {s.vertices} vertices, {s.faces} faces"
                + (f" (regular grid {s.grid_shape[0]} × {s.grid_shape[1]})" if s.grid_shape else "")
                + f", {ext} m at the proposed scale; max δ_f {s.delta_f_max:.1e}, max δ_P rows "
                  f"{s.delta_p_rows_max:.1e} / cols {s.delta_p_cols_max:.1e}, conical residual "
                  f"{s.conical_max:.1e} rad, {s.singular_vertices} singular vertices, {s.holes} holes.",
                "# Proposed from that:"] + [f"#  - {r}" for r in prop.reasons]
        example = None
        method = None
    else:
        registry = load_all()
        if source not in registry:
            from ppfab.schema import suggest
            raise DesignError("new", f"{source!r} is neither a construction method nor a mesh file (.obj, .off)"
                                     + suggest(source, sorted(registry)) + f"; methods: {', '.join(sorted(registry))}")
        method = source
        example = _smallest_example(method)
        if example is not None:
            doc = tomllib.loads(example.path.read_text(encoding="utf-8"))
            given = {k: dict(v) for k, v in doc.items() if isinstance(v, dict)}
        given.setdefault("geometry", {})["method"] = method
        c = get_construction(method)
        head = [f"# Starter design for the construction method '{method}' ({c.summary}; paper {c.section}),",
                "# written by `ppfab new`."
                + (f" Its values are those of the bundled example '{example.name}' (`ppfab examples`);"
                   " every other key is at its default." if example else " Every key is at its default.")]
    head += ["# Every section and key is listed with its default; build it with `ppfab build FILE -o OUT`."]
    lines = list(head)
    for name, get in _section_types().items():
        cls = get()
        values = dict(given.get(name, {}))
        if name == "geometry":
            params = values.pop("params", None)
            lines += _section(name, SECTION_TEXT.get(name, ""), cls, values, skip=("params",))
            if method is not None:
                c = get_construction(method)
                lines += _section("geometry.params", f"The parameters of '{method}' (`ppfab methods {method}`).",
                                  c.params, dict(params or given.get("geometry", {}).get("params", {})))
            continue
        active = (name != "optimize" or "optimize" in given) and (name != "surface" or is_surface)
        about = SECTION_TEXT.get(name, "")
        if name == "surface" and not active:
            about += " (Commented out: this design builds on its [geometry].)"
        elif not active:
            about += " (Commented out: a construction is planar by design; uncomment for a mesh file.)"
        lines += _section(name, about, cls, values, SECTION_DEFAULTS.get(name), active=active)
    return "\n".join(lines) + "\n"
