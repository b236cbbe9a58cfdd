"""The tables: ``glass_order.csv`` (per panel type), ``parts.csv``/``parts.json`` (per part) and
``nodes.csv``/``nodes.json`` (per vertex); their columns are in :mod:`fabrication.contract`."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..contract import ORDER_ALL_COLUMNS, TYPE_DIR, type_file
from ..glassorder import glass_order_rows
from ..nodes import write_nodes_csv, write_nodes_json
from ..parts import csv_text, part_rows, write_parts_csv, write_parts_json
from . import Files, writer

if TYPE_CHECKING:  # pragma: no cover
    from ..pipeline.records import Build


def parts_table(build: "Build", files: Files) -> list[dict]:
    """The rows of ``parts.csv``: glass panels, then beam plates, with their sheet files from ``files``; then the
    glazing strips, splice cover plates and retention parts (:mod:`fabrication.glazing.rows`)."""
    nest = build.nesting
    glass_sheets = files.get("glass_sheets", [])
    beam_sheets = files.get("beam_sheets", [])
    assert isinstance(glass_sheets, list) and isinstance(beam_sheets, list)
    rows = part_rows(list(nest.glass_parts), nest.glass.placements, glass_sheets) + \
        part_rows(list(nest.beam_parts), nest.plates.placements, beam_sheets)
    g = build.glazing
    if g is None:
        return rows
    from ..glazing.rows import beam_joins, splice_rows, strip_rows

    joins = beam_joins(g)
    bite: dict[str, float] = {}
    for b in g.bites:
        bite[b.panel] = min(bite.get(b.panel, float("inf")), b.bite)
    for row in rows:
        if row["kind"] == "beam" and row["part_id"] in joins:
            row.update(joins[row["part_id"]])
        elif row["kind"] == "panel" and row["part_id"] in bite:
            row["bite_min_mm"] = round(bite[row["part_id"]], 3)
            row["setting_blocks"] = f"2 x {g.params.setting_block_length:g} mm"
    from ..glazing.retention import build_retention
    from ..glazing.rows import retention_part_rows

    retention = build_retention(build) if g.strips else None
    extra = retention_part_rows(retention) if retention is not None else []
    return rows + strip_rows(g, build.beams) + splice_rows(g, build.beams) + extra


@writer("tables", order=50)
def write_tables(build: "Build", out: Path, files: Files) -> str:
    design = build.design
    parts = list(build.nesting.glass_parts)
    if design.output.per_type_dxf:
        type_files = {p.type_id or p.part_id: f"{TYPE_DIR}/{type_file(p.type_id or p.part_id)}" for p in parts}
        orders = glass_order_rows(parts, list(design.nesting.rotations), type_files, design.panels)
        (out / "glass_order.csv").write_text(csv_text(orders, ORDER_ALL_COLUMNS), encoding="utf-8")
        files["glass_order_csv"] = "glass_order.csv"
    rows = parts_table(build, files)
    write_parts_csv(rows, out / "parts.csv")
    write_parts_json(rows, out / "parts.json", extra={"units": "mm"})
    files["parts_csv"], files["parts_json"] = "parts.csv", "parts.json"
    beams = build.beams
    records = list(build.nodes.records)
    meta = {"support": build.support.summary(), "beam_depth_mm": beams.params.depth,
            "beam_thickness_mm": beams.params.thickness, "joint": beams.params.joint}
    write_nodes_csv(out / "nodes.csv", records)
    write_nodes_json(out / "nodes.json", records, meta)
    files["nodes_csv"], files["nodes_json"] = "nodes.csv", "nodes.json"
    return f"{len(rows)} parts, {len(records)} nodes"
