"""``erection.csv`` and ``drawings/erection.svg``: the erection sequence of :mod:`fabrication.erection`, one row per
part (and per weld) with its step, insertion direction and the step it needs done; manifest keys
``erection_csv`` and ``erection_drawing``.  A plate that no single direction puts through its slots is logged
(``ppfab verify``'s erection check measures whether its sweep passes through the rows)."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING

from ..contract import ERECTION_CSV
from ..erection import ERECTION_SVG
from . import Files, writer

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord


@writer("erection", order=77, declare=lambda build: {"erection_csv": ERECTION_CSV, "erection_drawing": ERECTION_SVG})
def write_erection(build: "BuildRecord", out: Path, files: Files) -> str:
    from ..contract import ERECTION_COLUMNS
    from ..erection import erection_plan
    from ..erection_drawing import erection_svg, plan_outlines
    from ..parts import csv_text

    plan = erection_plan(build.beams, build.glazing, build.panels.panels, build.retention)
    (out / ERECTION_CSV).write_text(csv_text(plan.rows(), ERECTION_COLUMNS), encoding="utf-8")
    svg = out / ERECTION_SVG
    svg.parent.mkdir(parents=True, exist_ok=True)
    outlines = plan_outlines(build.beams.plates, build.glazing, build.panels.panels)
    from .drawings import sheet_register

    sheet = sheet_register(build)[ERECTION_SVG].info
    svg.write_text(erection_svg(plan, outlines, sheet.title, sheet=sheet), encoding="utf-8")
    if plan.blocked:
        worst = sorted(plan.blocked, key=lambda b: -b.spread_deg)
        logging.getLogger("ppfab").warning(
            "erection: %d plate(s) have no single insertion direction, their slots and end cuts spreading up to "
            "%.1f° (%s): slid in as one piece each would push a mating plate further sideways in its slot than its "
            "clearance; the erector fits them in pieces, or before the plates they cross (erection.csv "
            "blocked_spread_deg); [beams] segment = [\"blocked\"] cuts them across the node axis at the "
            "nodes that give every part a way in, each part welded to the row there; shorter pieces "
            "(beams.max_length) or more slot play (beams.clearance) ease it",
            len(worst), worst[0].spread_deg, ", ".join(f"{b.part_id} {b.spread_deg:.1f}°" for b in worst[:6]))
    return f"{len(plan.steps)} steps, {len(plan.insertions)} rows" + \
        (f", {len(plan.blocked)} plates with no single insertion direction" if plan.blocked else "")
