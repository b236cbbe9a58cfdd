"""The tables: ``glass_order.csv`` (per panel type), ``parts.csv``/``parts.json`` (per part: the build's
:class:`~fabrication.model.PartsTable`, made by the pipeline) and ``nodes.csv``/``nodes.json`` (per vertex);
their columns are in :mod:`fabrication.contract`."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..contract import ORDER_ALL_COLUMNS, TYPE_DIR, type_file
from ..glassorder import glass_order_rows
from ..nodes import write_nodes_csv, write_nodes_json
from ..parts import csv_text, write_parts_csv, write_parts_json
from . import Files, writer

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord


def table_files(build: "BuildRecord") -> Files:
    """glass_order.csv (with ``per_type_dxf``), parts.csv and .json, nodes.csv and .json."""
    files: Files = {"glass_order_csv": "glass_order.csv"} if build.design.output.per_type_dxf else {}
    files["parts_csv"], files["parts_json"] = "parts.csv", "parts.json"
    files["nodes_csv"], files["nodes_json"] = "nodes.csv", "nodes.json"
    return files


@writer("tables", order=50, declare=table_files)
def write_tables(build: "BuildRecord", out: Path, files: Files) -> str:
    design = build.design
    parts = list(build.nesting.glass_parts)
    if design.output.per_type_dxf:
        type_files = {p.type_id or p.part_id: f"{TYPE_DIR}/{type_file(p.type_id or p.part_id)}" for p in parts}
        orders = glass_order_rows(parts, list(design.nesting.rotations), type_files, design.panels)
        (out / "glass_order.csv").write_text(csv_text(orders, ORDER_ALL_COLUMNS), encoding="utf-8")
    rows = list(build.parts)
    write_parts_csv(rows, out / "parts.csv")
    write_parts_json(rows, out / "parts.json", extra={"units": "mm"})
    beams = build.beams
    records = list(build.nodes.records)
    meta = {"support": build.support.summary(), "beam_depth_mm": beams.params.depth,
            "beam_thickness_mm": beams.params.thickness, "joint": beams.params.joint}
    write_nodes_csv(out / "nodes.csv", records)
    write_nodes_json(out / "nodes.json", records, meta)
    return f"{len(rows)} parts, {len(records)} nodes"
