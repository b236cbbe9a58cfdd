"""Drawings for installers (:mod:`fabrication.drawings`): ``drawings/key_plan.svg``, ``drawings/elevation_front.svg``,
``drawings/elevation_side.svg`` and ``drawings/nodes/node_type_NT01.svg`` … (one per node type,
:mod:`fabrication.nodetypes`); manifest keys ``drawings`` (the views) and ``node_sheets``."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from . import Files, writer

from ..contract import DRAWINGS_DIR, NODE_SHEET_DIR, node_sheet_file, view_file

if TYPE_CHECKING:  # pragma: no cover
    from ..pipeline.records import Build


@writer("drawings", order=75)
def write_drawings(build: "Build", out: Path, files: Files) -> str:
    from ..drawings import VIEW_TITLES, node_sheet_svg, view_svg
    from ..nodetypes import node_types

    folder = out / DRAWINGS_DIR
    (folder / NODE_SHEET_DIR).mkdir(parents=True, exist_ok=True)
    name = build.design.info.name
    panels, plates = build.panels.panels, build.beams.plates
    views = []
    for view in VIEW_TITLES:
        res = view_svg(view, panels, plates, f"{name}: {VIEW_TITLES[view]}")
        path = folder / view_file(view)
        path.write_text(res.svg, encoding="utf-8")
        views.append(f"{DRAWINGS_DIR}/{view_file(view)}")
    sheets = []
    params = build.beams.params
    types = node_types(build.nodes.records)
    for t in types:
        rel = f"{DRAWINGS_DIR}/{NODE_SHEET_DIR}/{node_sheet_file(t.type_id)}"
        (out / rel).write_text(node_sheet_svg(t, params.depth, params.thickness, ends=plate_ends(build, t.nodes[0])),
                               encoding="utf-8")
        sheets.append(rel)
    files["drawings"] = views
    files["node_sheets"] = sheets
    return f"{len(views)} views, {len(types)} node types"


def plate_ends(build: "Build", record: dict) -> dict[str, np.ndarray]:
    """For each plate that ends at the node of ``record`` (a ``nodes.json`` record): the direction ``(3,)`` from
    the node along the plate's polyline to its next node (where the plate lies)."""
    k = int(record["vertex"])
    v = np.asarray(build.support.vertices, dtype=float)
    out: dict[str, np.ndarray] = {}
    for b in record["beams"]:
        plate = build.beams.by_id.get(b["part_id"])
        if b.get("role") != "end" or plate is None:
            continue
        nodes = [int(x) for x in plate.nodes]
        if k not in nodes or len(nodes) < 2:
            continue
        i = nodes.index(k)
        other = nodes[1] if i == 0 else nodes[i - 1]
        out[b["part_id"]] = v[other] - v[k]
    return out
