"""panels.step against the mesh: one solid per panel, named by its part id, in the glass assembly (in a row
assembly below it, or directly in it as earlier builds wrote it), whose vertices are the face's corners on its
least-squares plane inset by half the panel gap (the pane as cut) and moved along the face normal by the pane's
seat ``z`` and by ``z`` + the glass thickness, the seat within :func:`._solids.seat_range` (the contact with
the gaskets is the clash check's, :mod:`.clash`); its header names ppfab.  The file is read once (it was read twice, here and by the ``step`` check,
before the two were merged)."""

from __future__ import annotations

import numpy as np

from . import Verification, check
from ._shapes import set_distance, solid_points
from ._solids import reference_outline, seat_range


@check("panels_step")
def check_panels_step(v: Verification) -> None:
    m = v.manifest
    rel = m.get("files", {}).get("panels_step")
    mesh = v.mesh
    if rel is None or mesh is None:
        return
    from ..contract import STEP_GLASS_GROUP
    from ._step_read import read_or_report
    from .step import check_header

    check_header(v, rel)
    read = read_or_report(v, rel)
    if read is None:
        return
    pairs = [(s.name, s.solid) for s in read]
    every = {r["part_id"] for r in (v.parts or []) if r["kind"] == "panel"}
    for s in read:
        if s.name not in every:
            v.error(rel, s.name or "(unnamed)", "solid is not a panel in parts.csv")
        elif s.path[1:2] != (STEP_GLASS_GROUP,):
            v.error(rel, s.name, f"sits under {'/'.join(s.path)}, expected the {STEP_GLASS_GROUP} assembly "
                                 "(below the design's)")
    fab = m.get("fabrication", {})
    t = float(fab.get("glass_thickness", 0.0))
    gap = float(fab.get("panel_gap", 0.0))
    lo, hi = seat_range(v)
    panels = {r["part_id"]: r for r in (v.parts or []) if r["kind"] == "panel" and r.get("face", "") != ""}
    names = [n for n, _ in pairs]
    for name in sorted(every - set(names)):
        v.error(rel, name, "panel has no solid")
    for name in sorted({n for n in names if names.count(n) > 1}):
        v.error(rel, name, "more than one solid carries this name")
    for name, solid in pairs:
        row = panels.get(name)
        if row is None:
            continue                                    # not a panel: named above
        ring = reference_outline(v, row)
        if ring is None:
            continue
        n = np.linalg.svd(ring - ring.mean(axis=0))[2][2]
        pts = solid_points(solid)
        mid = float(((pts - ring[0]) @ n).mean()) if len(pts) else 0.0
        side = 1.0 if mid >= 0 else -1.0                # the side of the face the pane lies on
        z0 = abs(mid) - 0.5 * t
        err = set_distance(pts, np.concatenate([ring + side * z0 * n, ring + side * (z0 + t) * n]))
        if not err <= 1e-3:
            v.error(rel, name, f"solid is {err:.3g} mm from face {row['face']} of mesh.obj inset by "
                               f"{0.5 * gap:g} mm and moved along its normal")
        elif not lo - 1e-3 <= z0 <= hi + 1e-3:
            v.error(rel, name, f"solid lies {z0:.3g} mm off face {row['face']} of mesh.obj, outside the seat "
                               f"range {max(lo, 0.0):.3g} … {hi:.3g} mm")
    v.checked.append("panels_step")

