"""``report.html``: one self-contained page a fabricator can read offline.

Sections: summary (size, counts, areas, weights, lengths, sheets and
utilisation against a lower bound of the sheets), quality (δ_f, δ_P, panel
deviation in mm, torsion, conical residual, panels above tolerance), figures
(3D structure, histograms), drawings for installers (key plan, elevations, node sheets, node types, kerf
notes), cutting sheets (inline SVG with part labels), and
the parts and node tables with nest tags.
"""

from __future__ import annotations

import logging
from pathlib import PurePosixPath
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from .flatpart import place_points
from .htmlreport import HtmlReport, esc

if TYPE_CHECKING:  # pragma: no cover
    from .records import BuildRecord

log = logging.getLogger("ppfab")


def sheet_svg(sheet_size: tuple[float, float], usable: tuple[float, float, float, float],
              outlines: list[np.ndarray], labels: list[str], width_px: int = 520) -> str:
    """One cutting sheet as inline SVG (y up as in the DXF; labels are the nest tags / part ids)."""
    w, h = (float(x) for x in sheet_size)
    s = width_px / w
    hp = h * s

    def pts(p: np.ndarray) -> str:
        return " ".join(f"{x * s:.1f},{hp - y * s:.1f}" for x, y in p)

    x0, y0, x1, y1 = usable
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width_px}" height="{hp:.0f}" '
           f'viewBox="0 0 {width_px} {hp:.0f}" style="background:#fafbfc;border:1px solid #999">',
           f'<rect x="{x0 * s:.1f}" y="{hp - y1 * s:.1f}" width="{(x1 - x0) * s:.1f}" height="{(y1 - y0) * s:.1f}" '
           'fill="none" stroke="#aaa" stroke-dasharray="4 3"/>']
    font = max(5.0, min(9.0, 0.6 * s * 200))
    for poly, lab in zip(outlines, labels):
        c = np.asarray(poly).mean(axis=0)
        out.append(f'<polygon points="{pts(poly)}" fill="#cfe3f3" stroke="#1f4e79" stroke-width="0.6"/>')
        out.append(f'<text x="{c[0] * s:.1f}" y="{hp - c[1] * s:.1f}" font-size="{font:.1f}" '
                   f'text-anchor="middle" dominant-baseline="middle" fill="#102a43">{esc(lab)}</text>')
    out.append("</svg>")
    return "".join(out)


def _sheets(parts: list, nesting: Any) -> list[str]:
    by_id = {p.part_id: p for p in parts}
    svgs = []
    for k, group in enumerate(nesting.by_sheet()):
        outlines = [place_points(by_id[pl.part_id].outline, pl) for pl in group]
        labels = [pl.part_id for pl in group]
        fill = nesting.sheet_fill[k] if getattr(nesting, "sheet_fill", None) is not None else float("nan")
        svgs.append(f'<figure>{sheet_svg(nesting.sheet_size, nesting.usable, outlines, labels)}'
                    f"<figcaption>sheet {k + 1}/{nesting.sheets} — {len(group)} parts, "
                    f"fill {100 * fill:.1f} %</figcaption></figure>")
    return svgs


def structure_png(mesh_corners: np.ndarray, plates: list, title: str) -> bytes:
    """3D view of panels and beam plates."""
    from .figures import mesh_figure, save

    polys = [p.frame.to3d(p.outline) for p in plates]
    return save(mesh_figure(mesh_corners, title, plates=polys, size=(6.4, 4.2)))


def structure_below_png(mesh_corners: np.ndarray, plates: list, title: str) -> bytes:
    """The same seen from below, where the beam plates and their joints show."""
    from .figures import mesh_figure, save

    polys = [p.frame.to3d(p.outline) for p in plates]
    return save(mesh_figure(mesh_corners, title, plates=polys, size=(6.4, 4.2), elev=-32, azim=-60))


def histograms(panels: list, beam_records: list, node_rows: list[dict]) -> list[tuple[Callable[[], bytes], str]]:
    """The histograms of the report as ``(draw, title)``: ``draw()`` returns the PNG."""
    from .figures import histogram, save

    figs = [
        (lambda: np.array([p.area_mm2 for p in panels]) / 1e6, "Panel areas", "area [m²]"),
        (lambda: np.concatenate([np.asarray(p.corner_angles_deg) for p in panels]), "Panel corner angles",
         "angle [°]"),
        (lambda: np.array([r.length_mm for r in beam_records]) / 1000, "Beam plate lengths", "length [m]"),
        (lambda: np.array([float(r["dihedral_deg"]) for r in node_rows if r.get("dihedral_deg") is not None]),
         "Node dihedral angles (between the two beam planes)", "angle [°]"),
    ]

    def draw(values: Callable[[], np.ndarray], title: str, xlabel: str) -> Callable[[], bytes]:
        return lambda: save(histogram(values(), title, xlabel)) or b""

    return [(draw(v, t, x), t) for v, t, x in figs]


def drawn_figures(figures: list[tuple[Callable[[], bytes], str]]) -> tuple[list[tuple[bytes, str]], list[str]]:
    """Draw each figure; one that cannot be drawn becomes a note (a figure never stops a build)."""
    out, notes = [], []
    for draw, caption in figures:
        try:
            out.append((draw(), caption))
        except Exception as exc:  # noqa: BLE001 - any failure of a plotting library becomes a note
            notes.append(f"The figure “{caption}” could not be drawn ({type(exc).__name__}: {exc}).")
            log.warning("report: figure %r could not be drawn (%s: %s)", caption, type(exc).__name__, exc)
    return out, notes


def _svg_img(svg: str, alt: str) -> str:
    """An SVG drawing as a self-contained ``<img>`` (base64 data URI), as wide as the page."""
    import base64

    data = base64.b64encode(svg.encode("utf-8")).decode("ascii")
    return f'<img alt="{esc(alt)}" style="width:100%;height:auto" src="data:image/svg+xml;base64,{data}"/>'


def drawings_section(rep: HtmlReport, build: "BuildRecord", files: dict[str, Any], drawings: dict[str, str]) -> None:
    """The installers' drawings (key plan, elevations, node sheets, :mod:`fabrication.drawings`) embedded, the
    node types, and the kerf notes per cutting process."""
    from .contract import KERF_NOTES, node_sheet_file
    from .nodetypes import node_types

    rep.heading("Drawings for installers")
    rep.paragraph("Every panel and beam plate id is on the key plan; the elevations label the plates seen "
                  "broadside and the panels facing the viewer. The same drawings are in drawings/ as SVG files.",
                  "muted")
    for rel in files.get("drawings", []):
        if rel in drawings:
            rep.raw(f"<figure>{_svg_img(drawings[rel], rel)}<figcaption>{esc(rel)}</figcaption></figure>")
    types = node_types(build.nodes.records)
    node_sheets = [str(rel) for rel in files.get("node_sheets", [])]

    def sheets_of(type_id: str) -> str:
        """The sheets of one node type: ``node_type_<id>.svg`` and its continuations ``…-2.svg`` …"""
        stem = node_sheet_file(type_id).removesuffix(".svg")
        return ", ".join(rel for rel in node_sheets
                         if PurePosixPath(rel).name == f"{stem}.svg" or PurePosixPath(rel).name.startswith(f"{stem}-"))

    rep.heading("Node types", 3)
    rep.table(["type", "joint", "plates", "dihedral [°]", "nodes", "slot width [mm]", "sheet"],
              [(t.type_id, t.joint, len(t.roles), ", ".join(f"{a:g}" for a in t.angles_deg), len(t.nodes),
                "" if t.slot_width_range is None else f"{t.slot_width_range[0]:.2f}–{t.slot_width_range[1]:.2f}",
                sheets_of(t.type_id)) for t in types], left=(0, 1, 6))
    sheets = [rel for rel in files.get("node_sheets", []) if rel in drawings][:2]
    if sheets:
        rep.raw('<div class="figs">' + "".join(f"<figure>{_svg_img(drawings[rel], rel)}<figcaption>{esc(rel)}"
                                                 "</figcaption></figure>" for rel in sheets) + "</div>")
    rep.heading("Cutting processes", 3)
    r = build.design.beams.tool_radius
    rep.paragraph("Outlines are nominal (no kerf offset): the CAM applies its kerf compensation. Slot corners: "
                  + (f"dog-bone reliefs for a tool of radius {r:g} mm (beams.tool_radius)." if r > 0 else
                     "sharp (beams.tool_radius = 0, laser)."), "muted")
    rep.table(["process", "note"], list(KERF_NOTES.items()), left=(0, 1))


def build_report(build: "BuildRecord", files: dict[str, Any], parts_rows: list[dict],
                 drawings: dict[str, str] | None = None) -> str:
    """The report page of a build, listing the files written so far (``files``) and the parts table;
    ``drawings``: relative path → SVG text of the drawings written (embedded)."""
    s = build.summary
    q = build.quality
    panels = list(build.panels.panels)
    beams = build.beams
    design = build.design
    rep = HtmlReport(f"ppfab fabrication report — {design.info.name}")
    if design.info.description:
        rep.paragraph(design.info.description, "muted")

    rep.heading("Summary")
    ext = s.extent_mm
    rep.key_values([
        ("structure size (x × y × z)", f"{ext[0] / 1000:.2f} m × {ext[1] / 1000:.2f} m × {ext[2] / 1000:.2f} m"),
        ("construction", build.geometry.source),
        ("planar beam families", ", ".join(build.geometry.planar_families) or "—"),
        ("panels / panel types", f"{s.panels} / {s.panel_types}"),
        ("beams / plates / plate types", f"{s.beams} / {s.beam_plates} / {s.beam_types}"),
        ("nodes", s.nodes),
        ("glass area", f"{s.glass_area_m2:.1f} m²"),
        ("glass weight", f"{s.glass_weight_kg / 1000:.2f} t"),
        ("total beam length", f"{s.beam_length_m:.1f} m"),
        ("plate area / weight", f"{s.plate_area_m2:.1f} m² / {s.beam_mass_kg / 1000:.2f} t"),
        ("steel take-off (plates, strips, cover plates)", f"{s.steel_mass_kg / 1000:.2f} t"),
        ("weld length", f"{s.weld_length_m:.1f} m"),
        ("glass retention (blocks, stops, gaskets, plates, caps, screws)", f"{s.retention_mass_kg:.1f} kg"),
        ("glass sheets (utilisation; lower bound)",
         f"{s.glass_sheets} ({100 * s.glass_utilisation:.1f} %; ≥ {s.glass_lower_bound})"),
        ("plate sheets (utilisation; lower bound)",
         f"{s.plate_sheets} ({100 * s.plate_utilisation:.1f} %; ≥ {s.plate_lower_bound})"),
    ])

    rep.heading("Quality")
    tol = design.panels.planarity_tolerance
    over = [p for p in panels if p.deviation_mm > tol]
    rows = [
        ("δ_f (face planarity) max / mean", f"{q.delta_f_max:.2e} / {q.delta_f_mean:.2e}"),
        ("δ_P rows max / mean", f"{q.delta_p_rows_max:.2e} / {q.delta_p_rows_mean:.2e}"),
        ("δ_P columns max / mean", f"{q.delta_p_cols_max:.2e} / {q.delta_p_cols_mean:.2e}"),
        ("panel deviation from plane, max", f"{q.deviation_abs_max:.3g} mm (tolerance {tol:g} mm)"),
        ("support structure torsion, max", f"{s.torsion_max_deg:.3g}°"),
        ("torsion offset at beam depth, max", f"{beams.report.torsion_offset_max_mm:.3g} mm "
                                              f"(tolerance beams.max_torsion_mm {design.beams.max_torsion_mm:g} mm)"),
        ("node axis to surface normal, max", f"{float(build.support.normal_angle_deg.max()):.1f}° "
                                             f"(limit support.max_axis_angle_deg {design.support.max_axis_angle_deg:g}°)"),
        ("polylines left out of the planar families", len(build.support.left_out)),
        ("crease (dihedral angle between neighbouring panels), max", f"{q.crease_max:.1f}° (limit "
                                                                     f"panels.max_crease_deg "
                                                                     f"{design.panels.max_crease_deg:g}°)"),
        ("conical residual max / mean", f"{q.conical_max:.2e} / {q.conical_mean:.2e} rad"),
        ("circular residual max / mean (panel corners on a circle: 0)",
         f"{q.circular_max:.2e} / {q.circular_mean:.2e} rad"),
        ("panels above tolerance", len(over)),
        ("beam plates not slidable through their slots", beams.report.totals()["not_slidable"]),
    ]
    if build.geometry.surface_deviation_mm is not None:
        rows.append(("largest distance of a node to the designer's surface ([surface])",
                     f"{build.geometry.surface_deviation_mm:.2f} mm"))
    rep.key_values(rows)
    if over:
        rep.table(["panel", "deviation [mm]"], [(p.part_id, p.deviation_mm) for p in over])
    if build.support.left_out:
        rep.heading("Polylines left out of the planar families (beams of one edge each)", 3)
        rep.table(["polyline", "vertices", "why"],
                  [(k, len(build.support.polylines[k]), why) for k, why in build.support.left_out], left=(2,))
    flagged = [p for p in panels if p.flags]
    if flagged:
        rep.heading("Panels outside processing limits", 3)
        rep.table(["panel", "flags", "min corner [°]", "bbox [mm]"],
                  [(p.part_id, ", ".join(p.flags), min(p.corner_angles_deg), f"{p.bbox[0]:.0f} × {p.bbox[1]:.0f}")
                   for p in flagged])

    rep.heading("Figures")
    mesh = build.mesh
    qm = mesh.to_quadmesh() if hasattr(mesh, "to_quadmesh") else mesh
    plates = list(beams.plates)
    node_rows = list(build.nodes.records)
    figs, notes = drawn_figures(
        [(lambda: structure_png(qm.face_corners, plates, "panels and beam plates"), "3D structure, above"),
         (lambda: structure_below_png(qm.face_corners, plates, "beam plates from below"), "3D structure, below")]
        + histograms(panels, list(beams.report.records), node_rows))
    rep.figures(figs)
    for note in notes:
        rep.paragraph(note, "muted")

    drawings_section(rep, build, files, drawings or {})

    nest = build.nesting
    rep.heading("Cutting sheets — glass")
    rep.raw('<div class="figs">' + "".join(_sheets(list(nest.glass_parts), nest.glass)) + "</div>")
    rep.heading("Cutting sheets — beam plates")
    rep.raw('<div class="figs">' + "".join(_sheets(list(nest.beam_parts), nest.plates)) + "</div>")

    from .repetition import repetition
    from .report_glazing import glazing_sections

    glazing_sections(rep, build, repetition(build))
    place = {r["part_id"]: r for r in parts_rows}
    rep.heading("Panels")
    rep.table(["panel", "type", "face", "area [m²]", "weight [kg]", "min/max corner [°]", "deviation [mm]",
               "sheet", "nest tag", "flags"],
              [(p.part_id, p.type_id, p.face, float(place.get(p.part_id, {}).get("area_mm2", p.area_mm2)) / 1e6,
                float(place.get(p.part_id, {}).get("weight_kg", p.weight_kg)),
                f"{min(p.corner_angles_deg):.1f} / {max(p.corner_angles_deg):.1f}", p.deviation_mm,
                place.get(p.part_id, {}).get("sheet", ""), place.get(p.part_id, {}).get("nest_tag", ""),
                ", ".join(p.flags)) for p in panels], left=(0, 1, 9))
    rep.heading("Beam plates")
    rep.table(["plate", "beam", "family", "length [m]", "mass [kg]", "slots", "slidable", "extra clearance [mm]",
               "sheet", "nest tag"],
              [(r.part_id, r.beam_id, r.family, r.length_mm / 1000, r.mass_kg, r.slots, r.slidable,
                r.extra_clearance_mm, place.get(r.part_id, {}).get("sheet", ""),
                place.get(r.part_id, {}).get("nest_tag", "")) for r in beams.report.records], left=(0, 1, 2))
    rep.heading("Nodes")
    rep.table(["node", "vertex", "grid", "x [mm]", "y [mm]", "z [mm]", "beams", "joint", "dihedral [°]",
               "torsion [°]", "torsion [mm]"],
              [(r["node_id"], r["vertex"], "" if r["grid"] is None else f"{r['grid'][0]},{r['grid'][1]}",
                *(round(c, 1) for c in r["position"]), "; ".join(b["part_id"] for b in r["beams"]), r["joint"],
                "" if r["dihedral_deg"] is None else r["dihedral_deg"], r["torsion_deg"], r["torsion_mm"])
               for r in node_rows],
              left=(0, 2, 6, 7))
    rep.heading("Files")
    models = [(files[k], what) for k, what in (("glb", "3D view (glTF: drop it into any glTF viewer)"),
                                                ("ifc", "BIM (IFC4)"), ("rhino", "Rhino")) if k in files]
    if models:
        rep.raw("<p>" + " · ".join(f'<a href="{_href(str(f))}">{esc(str(f))}</a> {esc(what)}'
                                   for f, what in models) + "</p>")
    rows = [(path, key.replace("_", " ")) for key, value in sorted(files.items())
            for path in (value if isinstance(value, list) else [value])]
    rows.append(("manifest.json", "manifest: every file and its sha256"))
    rep.raw('<div class="scroll"><table class="files"><thead><tr><th class="l">file</th><th class="l">what</th>'
            "</tr></thead><tbody>" + "".join(f'<tr><td class="l"><a href="{_href(str(f))}">{esc(str(f))}</a></td>'
                                             f'<td class="l">{esc(what)}</td></tr>' for f, what in rows)
            + "</tbody></table></div>")
    return rep.html()


def _href(path: str) -> str:
    """A relative link to a file of the folder (``glass/glass_01.dxf``), percent-encoded and HTML-escaped."""
    from urllib.parse import quote

    return esc(quote(path.replace("\\", "/")))
