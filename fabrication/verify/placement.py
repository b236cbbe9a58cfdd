"""The placement rule of parts.csv: ``x, y, rotation_deg, mirrored`` map each part's own outline onto its CUT
polyline within 1e-6 mm — a panel's own outline is its type's (``glass/types/``), a beam plate's is its
solid's outline in the frame of parts.csv (``beams.step``; the union of its two faces, which a bevelled top
edge makes differ)."""

from __future__ import annotations

import numpy as np

from ..contract import csv_value
from ..flatpart import Placement, place_points
from . import Verification, check
from ._shapes import cyclic_distance, number, set_distance

TOLERANCE_MM = 1e-6


@check("placement")
def check_placement(v: Verification) -> None:
    cut = v.cut
    types = v.type_outlines
    plates = v.plate_cut_outlines or v.plate_outlines
    for row in (v.parts or []):
        pid = row["part_id"]
        if pid not in cut:
            continue
        rel, points = cut[pid]
        if row["kind"] == "panel":
            own = types.get(csv_value(row["type_id"]))
        else:
            own = plates.get(pid)
        if own is None:
            continue
        x, y, rot = number(row["x"]), number(row["y"]), number(row["rotation_deg"])
        mirrored = row.get("mirrored", "0") in ("1", "True", "true")
        if not np.all(np.isfinite([x, y, rot])):
            v.error("parts.csv", pid, f"placement x={row['x']!r}, y={row['y']!r}, rotation_deg={row['rotation_deg']!r} "
                                      "is not a number")
            continue
        placed = place_points(np.asarray(own, dtype=float), Placement(pid, 0, x, y, rot, mirrored))
        if mirrored:
            placed = placed[::-1]
        if row["kind"] == "panel":
            err = cyclic_distance(np.asarray(points, dtype=float), placed)
        else:
            err = set_distance(np.asarray(points, dtype=float), placed)
        if not err <= TOLERANCE_MM:
            what = "its type's outline" if row["kind"] == "panel" else "its plate outline (beams.step)"
            v.error(rel, pid, f"parts.csv placement (x {x:g}, y {y:g}, rotation {rot:g}°, mirrored {int(mirrored)}) "
                              f"maps {what} {err:.3g} mm from the CUT polyline")
    v.checked.append("placement")
