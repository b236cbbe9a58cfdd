"""panels.step against the mesh: one solid per panel, named by its part id, in the glass assembly (in a row
assembly below it, or directly in it as earlier builds wrote it), whose vertices are the face's corners on its
least-squares plane and the same moved by the glass thickness along the face normal; its header names ppfab.
The file is read once (it was read twice, here and by the ``step`` check, before the two were merged)."""

from __future__ import annotations

import numpy as np

from . import Verification, check
from ._shapes import set_distance, solid_points


@check("panels_step", 62)
def check_panels_step(v: Verification) -> None:
    m = v.data.get("manifest", {})
    rel = m.get("files", {}).get("panels_step")
    mesh = v.data.get("mesh")
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
    every = {r["part_id"] for r in v.data.get("parts", []) if r["kind"] == "panel"}
    for s in read:
        if s.name not in every:
            v.error(rel, s.name or "(unnamed)", "solid is not a panel in parts.csv")
        elif s.path[1:2] != (STEP_GLASS_GROUP,):
            v.error(rel, s.name, f"sits under {'/'.join(s.path)}, expected the {STEP_GLASS_GROUP} assembly "
                                 "(below the design's)")
    t = float(m.get("fabrication", {}).get("glass_thickness", 0.0))
    panels = {r["part_id"]: r for r in v.data.get("parts", []) if r["kind"] == "panel" and r.get("face", "") != ""}
    names = [n for n, _ in pairs]
    for name in sorted(every - set(names)):
        v.error(rel, name, "panel has no solid")
    for name in sorted({n for n in names if names.count(n) > 1}):
        v.error(rel, name, "more than one solid carries this name")
    for name, solid in pairs:
        row = panels.get(name)
        if row is None:
            continue                                    # not a panel: named above
        c = mesh.vertices[mesh.faces[int(row["face"])]]
        centre = c.mean(axis=0)
        n = np.linalg.svd(c - centre)[2][2]
        proj = c - np.outer((c - centre) @ n, n)
        pts = solid_points(solid)
        err = min(set_distance(pts, np.concatenate([proj, proj + s * t * n])) for s in (1.0, -1.0))
        if not err <= 1e-6:
            v.error(rel, name, f"solid is {err:.3g} mm from face {row['face']} of mesh.obj and its {t:g} mm offset")
    v.checked.append("panels_step")
