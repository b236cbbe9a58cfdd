"""``erection.csv`` and ``drawings/erection.svg``: the erection sequence of :mod:`fabrication.erection`, one row per
part (and per weld) with its step, insertion direction and the step it needs done; manifest keys
``erection_csv`` and ``erection_drawing``.  A plate that no single direction puts through its slots is logged
(``ppfab verify``'s erection check measures whether its sweep passes through the rows)."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING

from . import Files, writer

if TYPE_CHECKING:  # pragma: no cover
    from ..pipeline.records import Build


@writer("erection", order=77)
def write_erection(build: "Build", out: Path, files: Files) -> str:
    from ..erection import ERECTION_COLUMNS, ERECTION_CSV, ERECTION_SVG, erection_plan
    from ..erection_drawing import erection_svg, plan_outlines
    from ..parts import csv_text

    from ..glazing.retention import build_retention

    plan = erection_plan(build.beams, build.glazing, build.panels.panels, build_retention(build))
    (out / ERECTION_CSV).write_text(csv_text(plan.rows(), ERECTION_COLUMNS), encoding="utf-8")
    files["erection_csv"] = ERECTION_CSV
    svg = out / ERECTION_SVG
    svg.parent.mkdir(parents=True, exist_ok=True)
    outlines = plan_outlines(build.beams.plates, build.glazing, build.panels.panels)
    from .drawings import sheet_register

    sheet = sheet_register(build)[ERECTION_SVG].info
    svg.write_text(erection_svg(plan, outlines, sheet.title, sheet=sheet), encoding="utf-8")
    files["erection_drawing"] = ERECTION_SVG
    for b in plan.blocked:
        logging.getLogger("ppfab").warning("erection: %s", b)
    return f"{len(plan.steps)} steps, {len(plan.insertions)} rows" + \
        (f", {len(plan.blocked)} plates with no single insertion direction" if plan.blocked else "")
