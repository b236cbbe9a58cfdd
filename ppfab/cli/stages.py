"""Fabrication stages of ``ppfab build`` (support → beams → panels → nesting → files → report).

Every stage that can reject the design (torsion-free support, degenerate
beams, non-planar panels, parts that fit no sheet) runs before any
fabrication file is written; all files go into the build's temporary folder,
which only becomes the output folder when every stage succeeded.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..errors import DesignError
from ..mesh import QuadGrid

if TYPE_CHECKING:  # pragma: no cover
    from .pipeline import BuildContext


def stage_support(ctx: "BuildContext") -> None:
    """Node axes and support planes (:mod:`ppfab.support`) of the placed mesh."""
    from ..support import support_structure

    ctx.progress.start("support")
    params = ctx.design.section("support")
    support = support_structure(ctx.data["mesh"], params, planar_families=ctx.data.get("planar_families") or None)
    ctx.data["support"] = support
    s = support.summary()
    ctx.progress.done(f"{s.get('kind', '?')}, torsion max {s.get('torsion_max_deg', 0.0):.2g}°")


def stage_beams(ctx: "BuildContext") -> None:
    """Planar beam plates with joints; a degenerate plate stops the build naming its part id."""
    from fabrication.beams import build_beams

    ctx.progress.start("beams")
    params = ctx.design.section("beams")
    sheet_len = ctx.design.section("beam_nesting").usable()
    usable_len = max(sheet_len[2] - sheet_len[0], sheet_len[3] - sheet_len[1])
    if params.max_length == 0 or params.max_length > usable_len:
        raise DesignError("beams.max_length", f"beam pieces up to {params.max_length:g} mm do not fit the "
                                              f"usable plate length {usable_len:g} mm of [beam_nesting]; "
                                              "set beams.max_length to at most the usable length")
    beams = build_beams(ctx.data["support"], params, strict=True)
    ctx.data["beams"] = beams
    t = beams.report.totals()
    ctx.progress.done(f"{t['plates']} plates, {t['slots']} slots, {t['length_m']:.0f} m")


def stage_panels(ctx: "BuildContext") -> None:
    """Glass panels (planarity in mm checked first), flattened, labelled, grouped into types."""
    from fabrication.panels import make_panels, panel_types

    ctx.progress.start("panels")
    panels = make_panels(ctx.data["mesh"], ctx.design.section("panels"))
    ctx.data["panels"] = panels
    ctx.data["panel_types"] = panel_types(panels)
    ctx.progress.done(f"{len(panels)} panels, {len(ctx.data['panel_types'])} types")


def _nest(ctx: "BuildContext", parts: list, section: str, what: str):
    from fabrication.nesting import nest, verify_nesting

    params = ctx.design.section(section)
    nesting = nest(parts, params)
    verify_nesting(parts, nesting, params)
    ctx.progress.note(f"{what}: {nesting.sheets} sheets ({100 * nesting.utilisation:.1f} %, "
                      f"bound {nesting.lower_bound});")
    return nesting


def stage_nesting(ctx: "BuildContext") -> None:
    """Nest glass panels and beam plates on their stock sheets and verify every placement."""
    ctx.progress.start("nesting")
    glass_parts = [p.flat_part() for p in ctx.data["panels"]]
    beam_parts = ctx.data["beams"].flat_parts()
    ctx.data["glass_parts"], ctx.data["beam_parts"] = glass_parts, beam_parts
    ctx.data["glass_nesting"] = _nest(ctx, glass_parts, "nesting", "glass")
    ctx.data["beam_nesting"] = _nest(ctx, beam_parts, "beam_nesting", "plates")
    ctx.progress.done()


def stage_files(ctx: "BuildContext") -> None:
    """STEP solids, DXF cutting sheets, per-type DXFs, order list, parts and node lists."""
    from fabrication.beams.solids import export_panels_step
    from fabrication.dxf import write_sheet_dxfs
    from fabrication.nodes import node_records, write_nodes
    from fabrication.parts import (order_rows, part_rows, write_order_list, write_parts_csv, write_parts_json,
                                   write_type_dxfs)

    out, files, d = ctx.out, ctx.files, ctx.data
    ctx.progress.start("files", "STEP…")
    beams = d["beams"]
    beams.export_step(out / "beams.step")
    files["beams_step"] = "beams.step"
    if ctx.design.section("output").panels_step:
        panels = d["panels"]
        export_panels_step(np.array([p.corners_3d for p in panels]), out / "panels.step",
                           ctx.design.section("panels").thickness, [p.part_id for p in panels])
        files["panels_step"] = "panels.step"
    ctx.progress.note("DXF…")
    name = ctx.design.info.name
    glass = write_sheet_dxfs(d["glass_parts"], d["glass_nesting"], out / "glass", "glass", f"{name} glass")
    plates = write_sheet_dxfs(d["beam_parts"], d["beam_nesting"], out / "beams", "plates", f"{name} beam plates")
    files["glass_sheets"] = [str(p.relative_to(out)) for p in glass]
    files["beam_sheets"] = [str(p.relative_to(out)) for p in plates]
    if ctx.design.section("output").per_type_dxf:
        types = write_type_dxfs(d["glass_parts"], out / "glass" / "types", "type")
        files["panel_type_dxfs"] = [f"glass/types/{v}" for v in types.values()]
        order = order_rows(d["glass_parts"], list(ctx.design.section("nesting").rotations),
                           {k: f"glass/types/{v}" for k, v in types.items()})
        write_order_list(order, out / "glass_order.csv")
        files["glass_order_csv"] = "glass_order.csv"
    rows = part_rows(d["glass_parts"], d["glass_nesting"].placements, files["glass_sheets"]) + \
        part_rows(d["beam_parts"], d["beam_nesting"].placements, files["beam_sheets"])
    write_parts_csv(rows, out / "parts.csv")
    write_parts_json(rows, out / "parts.json", extra={"units": "mm"})
    files["parts_csv"], files["parts_json"] = "parts.csv", "parts.json"
    d["node_records"] = node_records(beams)
    write_nodes(out, beams, records=d["node_records"])
    files["nodes_csv"], files["nodes_json"] = "nodes.csv", "nodes.json"
    d["parts_rows"] = rows
    d["summary"] = summary(ctx)
    ctx.progress.done(f"{len(glass)} glass + {len(plates)} plate sheets")


def fabrication_params(ctx: "BuildContext") -> dict:
    """Every fabrication parameter used, for ``manifest.json['fabrication']``."""
    from ..schema import as_plain

    design = ctx.design
    out = {}
    out.update(design.section("beams").manifest())
    panels = design.section("panels")
    nesting = design.section("nesting")
    out.update({"panel_gap": panels.gap, "planarity_tolerance": panels.planarity_tolerance,
                "glass_thickness": panels.thickness, "glass_makeup": panels.makeup,
                "sheet": list(nesting.sheet), "sheet_margin": nesting.margin, "part_spacing": nesting.spacing})
    for name in ("support", "beams", "panels", "nesting", "beam_nesting", "output"):
        out[name] = as_plain(design.section(name))
    return out


def summary(ctx: "BuildContext") -> dict:
    """Totals for the manifest, the report and ``--json``."""
    d = ctx.data
    mesh = d["mesh"]
    qm = mesh.to_quadmesh() if isinstance(mesh, QuadGrid) else mesh
    v = qm.vertices
    panels = d["panels"]
    bt = d["beams"].report.totals()
    gn, bn = d["glass_nesting"], d["beam_nesting"]
    return {
        "extent_mm": [float(x) for x in np.ptp(v, axis=0)],
        "panels": len(panels), "panel_types": len(d["panel_types"]),
        "glass_area_m2": float(sum(p.area_mm2 for p in panels) / 1e6),
        "glass_weight_kg": float(sum(p.weight_kg for p in panels)),
        "beams": bt["beams"], "beam_plates": bt["plates"], "beam_types": bt["types"],
        "beam_length_m": bt["length_m"], "beam_mass_kg": bt["mass_kg"],
        "plate_area_m2": float(sum(p.area for p in d["beam_parts"]) / 1e6),
        "nodes": int(len(v)),
        "glass_sheets": gn.sheets, "glass_utilisation": gn.utilisation, "glass_lower_bound": gn.lower_bound,
        "plate_sheets": bn.sheets, "plate_utilisation": bn.utilisation, "plate_lower_bound": bn.lower_bound,
        "torsion_max_deg": float(np.degrees(d["support"].torsion.max())) if len(d["support"].edges) else 0.0,
    }


def stage_report(ctx: "BuildContext") -> None:
    """``report.html`` (self-contained: inline CSS, figures as data URIs, sheets as inline SVG)."""
    if not ctx.design.section("output").report:
        return
    from fabrication.report import build_report

    ctx.progress.start("report")
    html = build_report(ctx.data, ctx.design, ctx.files)
    (ctx.out / "report.html").write_text(html, encoding="utf-8")
    ctx.files["report_html"] = "report.html"
    ctx.progress.done(f"{len(html) / 1e6:.1f} MB")
