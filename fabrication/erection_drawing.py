"""``drawings/erection.svg``: the plan (view from above) with every part filled in the colour of its erection step,
later steps drawn over earlier ones, and a legend naming each step (:mod:`fabrication.erection`)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import TYPE_CHECKING, Sequence

import numpy as np

from .contract import gasket_id
from .drawings import SvgSheet
from .paper import GAP, TEXT_MM, PaperSheet, SheetInfo, drawing_area, fitting_scales, scale_text
from .erection import STEP_TITLES, ErectionPlan

if TYPE_CHECKING:  # pragma: no cover
    from .beams.plates import BeamPlate
    from .glazing import Glazing
    from .panels import Panel

STEP_COLOURS = {"row": "#1f77b4", "column": "#d62728", "weld": "#7f7f7f", "splice": "#9467bd",
                "strip": "#2ca02c", "gasket": "#17becf", "panel": "#ff7f0e"}
"""The fill of each step's parts (welds have no solid and are listed in the legend only)."""


def plan_outlines(plates: "Sequence[BeamPlate]", glazing: "Glazing | None", panels: "Sequence[Panel]") -> \
        dict[str, np.ndarray]:
    """Part id → ``(k, 3)`` outline in model space of every solid part (a strip and its gasket share one)."""
    out: dict[str, np.ndarray] = {p.part_id: p.frame.to3d(p.outline) for p in plates}
    if glazing is not None:
        for sp in glazing.splices:
            ring = sp.frame.to3d(sp.outline)
            for pid in sp.part_ids:
                out[pid] = ring
        for st in glazing.strips:
            out[st.part_id] = out[gasket_id(st.part_id)] = st.frame.to3d(st.outline())
    for pane in panels:
        out[pane.part_id] = pane.frame.to3d(pane.outline)
    return out


def erection_svg(plan: ErectionPlan, outlines: dict[str, np.ndarray], title: str,
                 sheet: SheetInfo | None = None) -> str:
    """The SVG text of the plan coloured by step (``outlines`` from :func:`plan_outlines`), on a sheet of paper
    (``sheet``: title block; default A1, sheet 1 of 1) at the first standard scale at which the plan and the
    legend below it fit the drawing area."""
    info = sheet or SheetInfo(project="", title=title)
    rings = [outlines[p.part_id][:, :2] for p in plan.insertions if p.part_id in outlines]
    pts = np.vstack(rings) if rings else np.zeros((1, 2))
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    ax0, ay0, ax1, ay1 = drawing_area(info.paper)
    h = TEXT_MM["note"]
    line = 2.0 * h                                  # legend pitch on paper
    legend = GAP + line * (len(plan.steps) + 0.5)
    size = hi - lo
    s = next((k for k in fitting_scales(float(size[0]) + 2.0, float(size[1]) + 2.0, info.paper)
              if size[1] / k + 2.0 + legend <= ay1 - ay0), fitting_scales(1e12, 1e12, info.paper)[-1])
    pad = 1.0 * s
    view = SvgSheet((lo[0] - pad, lo[1] - pad, hi[0] + pad, hi[1] + pad), 1.0, title)
    stroke = 0.1 * s
    for p in plan.insertions:
        ring = outlines.get(p.part_id)
        if ring is None:
            continue
        colour = STEP_COLOURS.get(p.kind, "#000000")
        extra = {"data-part": p.part_id, "data-step": str(p.step)}
        if p.kind == "panel":
            extra["fill-opacity"] = "0.35"
        if p.kind == "gasket":                      # over its strip: outlined only, so the strip shows
            view.polygon(ring[:, :2], "none", colour, 2 * stroke, **extra)
        else:
            view.polygon(ring[:, :2], colour, "#102a43", stroke, **extra)
    page = PaperSheet(info, s)
    page.frame()
    el = page.embed(view.root, ax0, ay0, float(s))
    el.set("data-view", "erection")
    y = ay0 + float(el.get("height", "0")) + GAP + 0.5 * line
    legend_group = ET.SubElement(page.root, "g", {"class": "legend"})
    for k, kind in enumerate(plan.steps, start=1):
        page.rect(ax0, y - 0.35 * line, ax0 + line, y + 0.35 * line, 0.1, parent=legend_group,
                  fill=STEP_COLOURS.get(kind, "#000000"))
        page.text(f"step {k}: {STEP_TITLES[kind]}", ax0 + 1.5 * line, y, "note")
        y += line
    bx0, by0, _, _ = page.band_left()
    page.text(f"scale {scale_text(s)} on {info.paper}", bx0 + GAP, by0 + 9.0, "note")
    return page.tostring()
