"""The report's sections on the glass support, the splices and welds, and repetition (panel and node types)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from .htmlreport import HtmlReport
    from .records import BuildRecord


def glazing_sections(rep: "HtmlReport", build: "BuildRecord", repetition: dict[str, Any]) -> None:
    """Append the sections to ``rep``."""
    g = build.glazing
    if g is not None and g.strips:
        p = g.params
        bites = np.array([b.bite for b in g.bites])
        tilt = np.array([b.tilt_deg for b in g.bites])
        rep.heading("Glass support")
        rep.paragraph(f"Every beam span carries a {p.width:g} × {p.thickness:g} mm glazing strip ({p.material}) with a "
                      f"{p.gasket_thickness:g} mm {p.gasket_material} gasket; the panes rest {g.offset:g} mm above "
                      f"the beams' top edges. {len(g.strips)} strips, cut from {p.bar_length:g} mm bars "
                      "(strip_cuts.csv).")
        rep.table(["pane edges", "bite min [mm]", "bite median [mm]", "required [mm]", "tilt max [°]"],
                  [(len(bites), float(bites.min()), float(np.median(bites)), build.design.panels.min_bite,
                    float(tilt.max()))])
        worst = sorted(g.bites, key=lambda b: b.bite)[:5]
        rep.table(["pane", "edge", "strip", "bite [mm]", "supported [mm]", "edge [mm]"],
                  [(b.panel, b.edge, b.strip, b.bite, b.supported, b.length) for b in worst], left=(0, 2))
        from .glazing.slope import DRAINAGE_NOTE, flat_panes

        flat = flat_panes(build.panels.panels, p.min_slope_deg)
        if flat:
            rep.paragraph(f"Drainage: {len(flat)} pane(s) slope less than glazing.min_slope_deg = "
                          f"{p.min_slope_deg:g}°: " + ", ".join(f"{f.part_id} ({f.slope_deg:.2f}°)" for f in flat[:20])
                          + (f" and {len(flat) - 20} more" if len(flat) > 20 else "") + f"; {DRAINAGE_NOTE}.")
    if g is not None and (g.splices or g.welds):
        rep.heading("Splices and welds")
        sp = g.splice_params
        if g.splices:
            rep.paragraph(f"{len(g.splices)} splices: at every cut of a split beam two {sp.plate_thickness:g} mm "
                          f"cover plates with {len(g.splices[0].holes)} × {sp.bolt} bolts in {sp.hole:g} mm holes "
                          "(splices.step, splices/*.dxf; the same holes are cut in the beam pieces, bolts.csv lists the bolt "
                          "sets).")
            rep.table(["cover plates", "beam", "joins"],
                      [(" / ".join(s.part_ids), s.beam_id, " + ".join(s.pieces)) for s in g.splices[:12]],
                      left=(0, 1, 2))
        welded = [w for w in g.welds if w.joint == "splice"]
        if welded:
            rep.paragraph(f"{len(welded)} welded splices (splices.kind = \"{sp.kind}\"): where a beam's edges are "
                          "too short for a cover plate clear of the joints, its pieces are butt-welded across the "
                          f"cut with full penetration, at least {sp.weld_clear:g} mm from every slot and plate end "
                          "at the top and the bottom edge (welds.csv, joint = splice).")
        if g.welds:
            kinds: dict[str, list[float]] = {}
            for w in g.welds:
                kinds.setdefault(w.preparation, []).append(w.length_mm)
            rep.table(["weld preparation", "joints", "length [m]"],
                      [(k, len(v), sum(v) / 1000) for k, v in kinds.items()], left=(0,))
    rep.heading("Repetition")
    pt, nt = repetition["panel_types"], repetition["node_types"]
    rep.table(["tolerance [mm]", *pt.keys()], [("panel types", *pt.values())])
    rep.table(["tolerance [°]", *nt.keys()], [("node types", *nt.values())])
    rep.paragraph(f"The panels are cut as {repetition['panel_types_used']} types (panels.type_tolerance "
                  f"{repetition['panel_type_tolerance_mm']:g} mm).", "muted")
