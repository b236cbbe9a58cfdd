"""``drawings/erection.svg``: the plan (view from above) with every part filled in the colour of its erection step,
later steps drawn over earlier ones, and a legend naming each step (:mod:`fabrication.erection`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np

from .contract import gasket_id
from .drawings import SvgSheet
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


def erection_svg(plan: ErectionPlan, outlines: dict[str, np.ndarray], title: str, width_px: float = 2400.0) -> str:
    """The SVG text of the plan coloured by step (``outlines`` from :func:`plan_outlines`)."""
    rings = [outlines[p.part_id][:, :2] for p in plan.insertions if p.part_id in outlines]
    pts = np.vstack(rings) if rings else np.zeros((1, 2))
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = 0.04 * float(max(hi - lo)) + 1.0
    sheet = SvgSheet((lo[0] - pad, lo[1] - pad, hi[0] + pad, hi[1] + pad), width_px, title)
    size = float(max(hi - lo)) + 2 * pad
    stroke = 0.0008 * size
    for p in plan.insertions:
        ring = outlines.get(p.part_id)
        if ring is None:
            continue
        colour = STEP_COLOURS.get(p.kind, "#000000")
        extra = {"data-part": p.part_id, "data-step": str(p.step)}
        if p.kind == "panel":
            extra["fill-opacity"] = "0.35"
        if p.kind == "gasket":                      # over its strip: outlined only, so the strip shows
            sheet.polygon(ring[:, :2], "none", colour, 2 * stroke, **extra)
        else:
            sheet.polygon(ring[:, :2], colour, "#102a43", stroke, **extra)
    line = 0.03 * size
    sheet.extend_down(line * (len(plan.steps) + 1.5))
    y = lo[1] - pad - line
    for k, kind in enumerate(plan.steps, start=1):
        box = np.array([[lo[0], y - 0.35 * line], [lo[0] + line, y - 0.35 * line], [lo[0] + line, y + 0.35 * line],
                        [lo[0], y + 0.35 * line]])
        sheet.polygon(box, STEP_COLOURS.get(kind, "#000000"), "#102a43", stroke)
        sheet.text(f"step {k}: {STEP_TITLES[kind]}", np.array([lo[0] + 1.5 * line, y]), 0.6 * line, anchor="start")
        y -= line
    return sheet.tostring()
