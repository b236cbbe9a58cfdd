"""beams.step: one valid solid per beam part, named by its part id, a plate of the beam thickness."""

from __future__ import annotations

import numpy as np

from . import Verification, check


@check("step", 60)
def check_step(v: Verification) -> None:
    """beams.step: one valid solid per beam part, named by its part id, a plate of the beam thickness."""
    files = v.data.get("manifest", {}).get("files", {})
    rel = files.get("beams_step")
    if rel is None:
        return
    from build123d import import_step

    from ..writers.step import named_solids

    try:
        pairs = named_solids(import_step(str(v.folder / rel)))
    except Exception as exc:  # noqa: BLE001
        v.error(rel, "", f"cannot be read by the CAD kernel ({exc})")
        return
    v.data["beam_solids"] = {name: solid for name, solid in reversed(pairs)}
    beams = {r["part_id"]: r for r in v.data.get("parts", []) if r["kind"] == "beam"}
    t = float(v.data["manifest"].get("fabrication", {}).get("beam_thickness", 0.0))
    names = [n for n, _ in pairs]
    for name in sorted(set(beams) - set(names)):
        v.error(rel, name, "beam part has no solid")
    for name in sorted({n for n in names if names.count(n) > 1}):
        v.error(rel, name, "more than one solid carries this name")
    for name, solid in pairs:
        if name not in beams:
            v.error(rel, name or "(unnamed)", "solid is not a beam part in parts.csv")
            continue
        if not solid.is_valid:
            v.error(rel, name, "solid is not valid (BRepCheck)")
        pts = np.array([tuple(p) for p in solid.vertices()])
        c = pts - pts.mean(axis=0)
        normal = np.linalg.svd(c)[2][2]
        spread = float(np.ptp(c @ normal))
        if t and abs(spread - t) > 1e-6 * max(1.0, t):
            v.error(rel, name, f"solid is {spread:.6g} mm thick, expected {t:g} mm")
        area = float(beams[name].get("area_mm2") or 0.0)
        if t and area and abs(solid.volume - area * t) > 1e-4 * area * t:
            v.error(rel, name, f"volume {solid.volume:.6g} mm³ ≠ outline area × thickness {area * t:.6g} mm³")
    v.checked.append("step")
