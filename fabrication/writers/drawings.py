"""Drawings for installers (:mod:`fabrication.drawings`): ``drawings/key_plan.svg``, ``drawings/elevation_front.svg``,
``drawings/elevation_side.svg`` and ``drawings/nodes/node_type_NT01.svg`` … (one per node type,
:mod:`fabrication.nodetypes`); manifest keys ``drawings`` (the views) and ``node_sheets``.  Every sheet is on
``[output] paper`` with a title block numbering it within the set (:func:`sheet_register`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from . import Files, writer

from ..contract import DRAWINGS_DIR, NODE_SHEET_DIR, node_sheet_file, view_file
from ..paper import SheetInfo

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord


def drawing_files(build: "BuildRecord") -> Files:
    """The views (key plan and elevations) and the node sheets of the drawing set (:func:`sheet_register`; the
    erection drawing is the erection writer's)."""
    from ..drawings import VIEW_TITLES

    register = sheet_register(build)
    return {"drawings": [f"{DRAWINGS_DIR}/{view_file(view)}" for view in VIEW_TITLES],
            "node_sheets": [rel for rel, info in register.items() if info.node_type is not None]}


@writer("drawings", order=75, declare=drawing_files)
def write_drawings(build: "BuildRecord", out: Path, files: Files) -> str:
    from ..drawings import VIEW_TITLES, view_svg
    from ..node_sheets import node_sheet_svg
    from ..nodetypes import node_types

    folder = out / DRAWINGS_DIR
    (folder / NODE_SHEET_DIR).mkdir(parents=True, exist_ok=True)
    register = sheet_register(build)
    panels, plates = build.panels.panels, build.beams.plates
    views = []
    scales = []
    for view in VIEW_TITLES:
        rel = f"{DRAWINGS_DIR}/{view_file(view)}"
        res = view_svg(view, panels, plates, VIEW_TITLES[view], sheet=register[rel].info)
        (out / rel).write_text(res.svg, encoding="utf-8")
        views.append(rel)
        scales.append(f"1:{res.scale}")
    sheets = []
    params = build.beams.params
    types = {t.type_id: t for t in node_types(build.nodes.records)}
    for rel, info in register.items():
        if info.node_type is None:
            continue
        t = types[info.node_type]
        (out / rel).write_text(node_sheet_svg(t, params.depth, params.thickness, ends=plate_ends(build, t.nodes[0]),
                                              sheet=info.info, rows=info.rows), encoding="utf-8")
        sheets.append(rel)
    return f"{len(views)} views ({', '.join(scales)} on {build.design.output.paper}), {len(types)} node types"


@dataclass(frozen=True)
class RegisteredSheet:
    """A sheet of the drawing set: its title block, and for a node sheet its node type and the rows it lists."""

    info: SheetInfo
    node_type: str | None = None
    rows: range | None = None


def sheet_register(build: "BuildRecord") -> dict[str, RegisteredSheet]:
    """Every sheet of the drawing set in its order, by file (relative to the output folder): the key plan, the two
    elevations, the erection drawing, then the node sheets (a node type whose list does not fit one sheet has
    ``node_type_<id>-2.svg`` … after it), each numbered of the total, on ``[output] paper``."""
    from ..drawings import VIEW_TITLES
    from ..node_sheets import node_pages
    from ..erection import ERECTION_SVG
    from ..nodetypes import node_types
    from ..paper import issue_date

    paper = build.design.output.paper
    params = build.beams.params
    entries: list[tuple[str, str, str | None, range | None]] = [
        (f"{DRAWINGS_DIR}/{view_file(v)}", VIEW_TITLES[v], None, None) for v in VIEW_TITLES]
    entries.append((ERECTION_SVG, "Erection sequence (plan, coloured by step)", None, None))
    for t in node_types(build.nodes.records):
        pages = node_pages(t, params.depth, params.thickness, paper)
        stem = node_sheet_file(t.type_id).removesuffix(".svg")
        for k, rows in enumerate(pages, start=1):
            name = f"{stem}.svg" if k == 1 else f"{stem}-{k}.svg"
            more = f" ({k} of {len(pages)})" if len(pages) > 1 else ""
            entries.append((f"{DRAWINGS_DIR}/{NODE_SHEET_DIR}/{name}", f"Node type {t.type_id}{more}", t.type_id,
                            rows))
    project = build.design.info.name
    date = build.design.info.date or issue_date()
    return {rel: RegisteredSheet(SheetInfo(project, title, k, len(entries), paper, date), node_type, rows)
            for k, (rel, title, node_type, rows) in enumerate(entries, start=1)}


def plate_ends(build: "BuildRecord", record: dict) -> dict[str, np.ndarray]:
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
