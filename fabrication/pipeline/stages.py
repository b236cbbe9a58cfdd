"""``build(design) -> Build``: design → geometry → quality → support → panels → beams → glazing → nesting → nodes →
summary.

One function per stage, each returning a frozen record (:mod:`fabrication.pipeline.records`); :data:`STAGES`
names them in order and :func:`build` calls them in that order with typed arguments.  Every check that can
reject a design (a fold, non-planar panels in mm, degenerate beams, parts that fit no sheet) runs here,
before any file exists; :meth:`Build.write` then hands the record to the writers
(:mod:`fabrication.writers`).  Tests inject a failure by replacing a ``stage_<name>`` function of this
module.
"""

from __future__ import annotations

import logging
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ppfab.errors import DesignError, GeometryError, NonPlanarPanelError
from ppfab.geometry import Geometry, build_geometry
from ppfab.mesh import QuadGrid, QuadMesh, as_quadmesh
from ppfab.metrics import Quality
from ppfab.support.structure import SupportStructure

from ..beams import BeamSet
from ..beams.bevel_cut import bevelled_beams
from ..beams.notch import notched_beams
from ..nesting import Nesting
from ..design import Design
from ..progress import Progress
from .records import Build, NestingSet, NodeTable, PanelSet, Summary

if TYPE_CHECKING:  # pragma: no cover
    from ..glazing import Glazing

STAGES: tuple[str, ...] = ("geometry", "quality", "support", "panels", "beams", "glazing", "nesting", "nodes",
                           "summary")
"""The compute stages in order; stage ``name`` is the function ``stage_<name>`` of this module.  Panel
planarity (mm) is the root cause of most beam defects, so ``panels`` is checked before ``beams``."""


def build(design: Design, progress: Progress | None = None, allow_large: bool = False) -> Build:
    """Run every compute stage of a design and return the typed :class:`Build` (no file is written).

    Parameters
    ----------
    design : a validated design (:func:`fabrication.load_design` or :func:`fabrication.parse_design`)
    progress : a :class:`Progress` display (silent when omitted)
    allow_large : go on above ``[geometry] max_vertices``

    Raises a :class:`~ppfab.errors.PpfabError` naming the element and value at fault when the design cannot
    be fabricated correctly.
    """
    p = progress or Progress(quiet=True)
    try:
        geometry = stage_geometry(design, p, allow_large)
        quality = stage_quality(geometry, p)
        support = stage_support(design, geometry, p)
        panels = stage_panels(design, geometry, p, quality)
        beams = stage_beams(design, support, p, panels)
        glazing = stage_glazing(design, support, panels, beams, p)
        beams = notched_beams(beams, glazing)        # top edges cut down under the strips of other beams
        beams = bevelled_beams(beams, glazing)       # top edges raised and bevelled under leaning strips
        nesting = stage_nesting(design, panels, beams, p)
        nodes = stage_nodes(beams, p)
        summary = stage_summary(geometry, panels, beams, nesting, support, glazing)
    except BaseException:
        p.fail()
        raise
    from ..glazing.retention import refuse_blocks_in_glass, retention_mass_kg, retention_of
    from ..glazing.screws import refuse_screws_in_glass
    from ..glazing.seat import refuse_lifted_panes, seat_panes, seat_range
    from ..parts import parts_table

    seats = (seat_panes(panels.panels, glazing.strips, glazing.params.gasket_thickness)
             if glazing is not None and glazing.strips else ())
    if seats and glazing is not None:
        gp = glazing.params
        tilt = max([gp.max_tilt_deg] + [b.tilt_deg for b in glazing.bites])
        _, limit = seat_range(glazing.offset, gp.width, tilt, design.panels.planarity_tolerance)
        refuse_lifted_panes(seats, limit, glazing.offset)
    retention = retention_of(panels.panels, seats, glazing, support, float(design.panels.gap))
    refuse_screws_in_glass(retention, design.panels.gap)    # placed on the built panes and strips
    refuse_blocks_in_glass(retention, design.panels.gap)
    summary = replace(summary, retention_mass_kg=retention_mass_kg(retention))
    b = Build(design, geometry, quality, support, panels, beams, nesting, nodes, summary, glazing=glazing,
              seats=seats, retention=retention, times=p.times)
    return replace(b, parts=parts_table(b))                  # the parts list, once, for every writer


def stage_geometry(design: Design, progress: Progress, allow_large: bool) -> Geometry:
    """Construct the mesh, or read (and optimise) a mesh file, placed in mm (:func:`ppfab.geometry.build_geometry`)."""
    from .advice import refuse_far_from_conjugate
    from .structure_gate import refuse_before_optimising

    geo = design.geometry
    progress.start("geometry", f"construction '{geo.method}'" if geo.method else f"mesh {geo.mesh}")
    def before_optimize(mesh: QuadGrid | QuadMesh, families: tuple[str, ...]) -> None:
        from ppfab.metrics import conjugacy_defect

        if design.optimize is not None:
            refuse_far_from_conjugate(conjugacy_defect(mesh), design.optimize.max_conjugacy_defect)
        refuse_before_optimising(mesh, families, design.support.max_normal_angle_deg, list(design.support.exclude),
                                 design.beams.fallback)

    if design.surface is not None:
        from .surface_stage import surface_geometry

        g = surface_geometry(design, progress, allow_large, before_optimize)
    else:
        g = build_geometry(geo, design.optimize, design.base_dir, allow_large, note=progress.note,
                           on_iteration=progress.iteration, before_optimize=before_optimize)
    mesh = g.mesh
    shape = mesh.shape if isinstance(mesh, QuadGrid) else (mesh.grid.shape if mesh.grid is not None else None)
    progress.done(f"{'grid ' + 'x'.join(map(str, shape)) if shape else 'quad mesh'}")
    return g


MAX_EXTENT_MM = 1e9
"""A placed mesh reaching further than this from the origin (1000 km) has wrong units: refused."""


def stage_quality(geometry: Geometry, progress: Progress) -> Quality:
    """Measure δ_f, δ_P, deviation (mm), conical residual and folds; a folded or self-intersecting mesh, or one
    placed absurdly far out (wrong units), stops the build."""
    from ppfab.intersections import self_intersections
    from ppfab.metrics import quality

    progress.start("quality")
    v = np.asarray(geometry.mesh.vertices, dtype=float)
    reach = float(np.abs(v).max()) if np.all(np.isfinite(v)) else float("inf")
    if not reach <= MAX_EXTENT_MM:
        raise GeometryError(f"the placed mesh reaches {reach:.3g} mm from the origin (more than {MAX_EXTENT_MM:.0e} mm): "
                            "check [geometry] scale (mesh units to millimetres) and translate", element="mesh",
                            value=reach)
    meet = self_intersections(geometry.mesh)
    if len(meet):
        f, g = (int(k) for k in meet[0])
        raise GeometryError(f"the mesh passes through itself: faces {f} and {g} (OBJ order) meet though they share no "
                            f"corner ({len(meet)} such pair(s)); it cannot be built", element=f"faces {f}, {g}",
                            value=float(len(meet)))
    q = quality(geometry.mesh)
    if q.flipped_edges:
        raise GeometryError(f"the mesh is folded: {q.flipped_edges} edge(s) join faces with opposite normals "
                            "(the surface passes through a cuspidal edge)", element="mesh", value=q.flipped_edges)
    if q.degenerate_edges:
        raise GeometryError(f"the mesh has {q.degenerate_edges} zero-length edge(s)", element="mesh")
    progress.done(f"δ_f max {q.delta_f_max:.1e}, δ_P rows {q.delta_p_rows_max:.1e} "
                  f"cols {q.delta_p_cols_max:.1e}, panel deviation {q.deviation_abs_max:.2g} mm")
    return q


def stage_support(design: Design, geometry: Geometry, progress: Progress) -> SupportStructure:
    """Node axes and support planes (:mod:`ppfab.support`) of the placed mesh; axes further from the surface
    normals than ``[support] max_axis_angle_deg`` stop the build (:mod:`ppfab.support.quality`)."""
    from ppfab.support.params import BeamContext
    from ppfab.support.quality import check_axis_angles
    from ppfab.support.select import support_structure

    from ..panels.panel import outside_sign

    progress.start("support")
    beams = BeamContext(design.beams.depth, design.beams.max_torsion_mm)
    params = design.support
    if params.flip and design.glazing.support == "strip":
        # the beams on the outside: the glass would hang below them, its strips and retention inside the steel
        raise DesignError("support.flip", "true hangs the beams on the glass's outside, where the glazing strips "
                                          "and retention parts of [glazing] would lie inside the plates; set "
                                          "[glazing] support = \"none\" (a glazing system of your own under the "
                                          "steel) or leave flip = false")
    if outside_sign(geometry.mesh, design.panels.outside) < 0:      # the glass is on the faces' back: the beams
        params = replace(params, flip=not params.flip)               # hang on their front (axes turned with it)
    support = support_structure(geometry.mesh, params, planar_families=geometry.planar_families or None,
                                beams=beams)
    check_axis_angles(support, design.support.max_axis_angle_deg)
    s = support.summary()
    progress.done(f"{s.get('kind', '?')}, torsion max {s.get('torsion_max_deg', 0.0):.2g}°")
    return support


def stage_panels(design: Design, geometry: Geometry, progress: Progress, quality: Quality | None = None) -> PanelSet:
    """Glass panels (planarity in mm checked first), flattened, labelled, grouped into types; a mesh file
    whose panels are not planar is refused with what to do (:mod:`fabrication.pipeline.advice`), and so is a
    mesh folded beyond ``panels.max_crease_deg`` between neighbouring panels (:mod:`fabrication.panels.crease`)."""
    from ..panels import make_panels, panel_types
    from ..panels.crease import check_creases, part_ids_by_face
    from .advice import planarity_advice

    progress.start("panels")
    try:
        panels = make_panels(geometry.mesh, design.panels)
    except NonPlanarPanelError as exc:
        advice = planarity_advice(design, quality, geometry.optimize_result) if quality is not None else ""
        if not advice:
            raise
        raise NonPlanarPanelError(exc.offenders, exc.tolerance_mm, advice) from None
    check_creases(geometry.mesh, design.panels.max_crease_deg, part_ids_by_face(panels))
    if panels:
        from ..panels.makeup import check_overhead

        # inclination of a pane from the vertical: arcsin |n_z| (z is up); the steepest-lying pane is named
        incl = np.degrees(np.arcsin(np.clip([abs(float(q.frame.normal[2])) for q in panels], 0.0, 1.0)))
        k = int(np.argmax(incl))
        check_overhead(design.panels.layers, float(incl[k]), panels[k].part_id)
    types = panel_types(panels)
    progress.done(f"{len(panels)} panels, {len(types)} types")
    return PanelSet(tuple(panels), types)


def strip_ups(design: Design, support: SupportStructure, panels: PanelSet):
    """The glazing strips' ups by mesh edge (:data:`fabrication.glazing.splices.EdgeUps`), ``None`` without strips
    (``[glazing] support = "none"``)."""
    from ..glazing.bite import edge_normals
    from ..glazing.splices import edge_ups

    if design.glazing.support == "none":
        return None
    return edge_ups(support.edges, edge_normals(panels.panels, support.vertices, support.edges))


def stage_beams(design: Design, support: SupportStructure, progress: Progress,
                panels: PanelSet | None = None) -> BeamSet:
    """Planar beam plates with joints; a degenerate plate stops the build naming its part id.  Cuts of split
    beams stay clear of the joints by what their splice needs (``[splices] kind``,
    :meth:`~fabrication.glazing.splices.SpliceParams.clearances`): half a cover plate plus half the depth for a
    bolted splice, ``weld_clear`` for a welded one; with the ``panels``, the bolted splices' cover plates (and so
    their holes in the pieces) stand clear of the glazing strips leaning over them (:func:`strip_ups`)."""
    from ..beams import build_beams
    from ..contract import beam_ids
    from .structure_gate import honour_structure, structure_change

    progress.start("beams")
    change = structure_change(support, beam_ids(support))     # after the panels: their refusal comes first
    honour_structure(change, design.beams.fallback)
    if change.changed:
        logging.getLogger("ppfab").warning(
            "[beams] fallback = \"segmented\": %d polyline(s) of the requested planar families are not planar beams "
            "and become %d one-edge plates (the report lists them and why)", len(change.left_out), change.edges)
    params = design.beams
    sheet_len = design.beam_nesting.usable()
    usable_len = max(sheet_len[2] - sheet_len[0], sheet_len[3] - sheet_len[1])
    if params.max_length == 0 or params.max_length > usable_len:
        raise DesignError("beams.max_length", f"beam pieces up to {params.max_length:g} mm do not fit the "
                                              f"usable plate length {usable_len:g} mm of [beam_nesting]; "
                                              "set beams.max_length to at most the usable length")
    usable_width = min(sheet_len[2] - sheet_len[0], sheet_len[3] - sheet_len[1])
    beams = build_beams(support, params, strict=True, max_height=usable_width,
                        splice_clearances=design.splices.clearances(params.depth), splice_params=design.splices,
                        splice_ups=strip_ups(design, support, panels) if panels is not None else None)
    refuse_crossing_plates(beams)
    added = beams.node_breaks
    if added:
        ids = beam_ids(support)
        cuts = sum(len(k) for _, k in added)
        logging.getLogger("ppfab").warning(
            "[beams] segment = [\"blocked\"]: %d column beam(s) that no single direction puts into their half-lap "
            "slots are cut across the node axis at %d node(s), each part welded to the row there (%s)", len(added),
            cuts, ", ".join(f"{ids[l]} at {len(k)}" for l, k in added[:8]) + (" …" if len(added) > 8 else ""))
    t = beams.report.totals()
    progress.done(f"{t['plates']} plates, {t['slots']} slots, {t['length_m']:.0f} m"
                  + (f", {len(added)} blocked column beams cut at nodes" if added else ""))
    return beams


def refuse_crossing_plates(beams: BeamSet) -> None:
    """Stop a build whose plates of different beams pass through each other at a node (``joint = "none"``: plain
    intersecting plates, for checking a structure, not for cutting): its own self-check would reject the files
    after writing them all (12 mm overlaps on smallest_roof; 3,600 pairs on a circular mesh's one-edge beams)."""
    from ppfab.errors import DesignError

    crossing = [j for j in beams.joints if j.kind == "plain" and any(not a[4] for a in j.angles)]
    if crossing:
        first = crossing[0]
        raise DesignError("beams.joint", f"'{beams.params.joint}' leaves the plates of different beams passing "
                                         f"through each other at {len(crossing)} node(s) (e.g. N{first.vertex:04d}: "
                                         f"{', '.join(first.parts[:3])}): plain intersecting plates check a "
                                         "structure but cannot be cut; use 'halflap' (both families planar) or "
                                         "'segmented' (one family continuous)")


def stage_glazing(design: Design, support: SupportStructure, panels: PanelSet, beams: BeamSet,
                  progress: Progress) -> "Glazing":
    """Glazing strips on the beams, the bite of every pane edge on them (a pane edge below ``[panels] min_bite``
    stops the build, naming it), the splices of split beams and the weld data of butt joints
    (:mod:`fabrication.glazing`)."""
    from ..glazing import make_glazing

    progress.start("glazing")
    g = make_glazing(support, list(panels.panels), beams, design.glazing, design.splices, design.panels.min_bite)
    bite = f"bite min {g.bite_min:.1f} mm, " if g.bites else ""
    progress.done(f"{len(g.strips)} strips, {bite}{len(g.splices)} splices, {len(g.welds)} welds")
    return g


def stage_nesting(design: Design, panels: PanelSet, beams: BeamSet, progress: Progress) -> NestingSet:
    """Nest glass panels and beam plates on their stock sheets and verify every placement with shapely."""
    from ..nesting import nest, verify_nesting
    from ..panels import type_flat_parts

    progress.start("nesting")
    glass_parts = type_flat_parts(list(panels.panels))
    beam_parts = beams.flat_parts()
    nestings: list[Nesting] = []
    notes = []
    for parts, params, what in ((glass_parts, design.nesting, "glass"), (beam_parts, design.beam_nesting, "plates")):
        def shown(done: float, total: float, sheets: int | None, what: str = what, n: int = len(parts)) -> None:
            progress.advance(done / 1e6, total / 1e6, f"{what}, {n} parts: "
                             + (f"best {sheets} sheets" if sheets else "first layout"))
        nesting = nest(parts, params, on_progress=shown)
        verify_nesting(parts, nesting, params)
        notes.append(f"{what}: {nesting.sheets} sheets ({100 * nesting.utilisation:.1f} %, "
                     f"bound {nesting.lower_bound})")
        nestings.append(nesting)
    progress.done("; ".join(notes))
    return NestingSet(tuple(glass_parts), tuple(beam_parts), nestings[0], nestings[1])


def stage_nodes(beams: BeamSet, progress: Progress) -> NodeTable:
    """One record per vertex: position, axis, the plates meeting there, angles, torsion (:mod:`fabrication.nodes`)."""
    from ..nodes import node_records

    return NodeTable(tuple(node_records(beams)))


def stage_summary(geometry: Geometry, panels: PanelSet, beams: BeamSet, nesting: NestingSet,
                  support: SupportStructure, glazing: "Glazing | None" = None) -> Summary:
    """Totals for the manifest, the report and ``--json``; the steel take-off adds the glazing strips and
    splice cover plates (their ``parts.csv`` masses) to the beam plates, and the weld length sums ``welds.csv``."""
    mesh = geometry.mesh
    qm = as_quadmesh(mesh)
    v = qm.vertices
    bt = beams.report.totals()
    gn, bn = nesting.glass, nesting.plates
    from ..panels import type_flat_parts

    cut = type_flat_parts(list(panels.panels))        # the glass as cut: each pane to its type's outline
    return Summary(
        extent_mm=[float(x) for x in np.ptp(v, axis=0)],
        panels=len(panels.panels), panel_types=len(panels.types),
        glass_area_m2=float(sum(p.area for p in cut) / 1e6),
        glass_weight_kg=float(sum(float(p.meta["weight_kg"]) for p in cut)),
        beams=bt["beams"], beam_plates=bt["plates"], beam_types=bt["types"],
        beam_length_m=bt["length_m"], beam_mass_kg=bt["mass_kg"],
        plate_area_m2=float(sum(p.area for p in nesting.beam_parts) / 1e6),
        nodes=int(len(v)),
        glass_sheets=gn.sheets, glass_utilisation=gn.utilisation, glass_lower_bound=gn.lower_bound,
        plate_sheets=bn.sheets, plate_utilisation=bn.utilisation, plate_lower_bound=bn.lower_bound,
        torsion_max_deg=float(np.degrees(support.torsion.max())) if len(support.edges) else 0.0,
        steel_mass_kg=float(bt["mass_kg"]) + (_glazing_steel_kg(glazing, beams) if glazing is not None else 0.0),
        weld_length_m=float(sum(w.length_mm for w in glazing.welds) / 1e3) if glazing is not None else 0.0,
    )


def _glazing_steel_kg(glazing: "Glazing", beams: BeamSet) -> float:
    """Mass of the glazing strips and splice cover plates, kg, as their ``parts.csv`` rows give it."""
    from ..glazing.rows import splice_rows, strip_rows

    rows = (strip_rows(glazing, beams) if glazing.strips else []) + splice_rows(glazing, beams)
    return float(sum(float(r["mass_kg"]) for r in rows))
