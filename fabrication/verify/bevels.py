"""bevels.csv against the files: every strip's lean on its beam plate, re-measured, and the bevel it calls for.

For each glazing strip of ``parts.csv``: its normal ``u`` is the thin direction of its solid in glazing.step (the
least-variance direction of its vertices), the plate under it is a beam row of ``parts.csv`` of the strip's
``beam`` holding both its ``edge_nodes`` (else one of them), with unit plane normal ``n_p`` and thickness ``t``.
The lean is ``λ = arcsin |u·n_p|``; bevels.csv must state it within :data:`LEAN_TOL`, the overlap
``(t/2)·sin λ`` and ``Δ = (t/2)·tan λ`` within 0.01 mm, and a bevel exactly where ``λ`` exceeds
``glazing.bevel_min_deg`` (:mod:`fabrication.glazing.bevel`).
"""

from __future__ import annotations

import math

import numpy as np

from ..contract import BEVEL_COLUMNS
from . import Verification, check
from ._shapes import literal, number, solid_points

LEAN_TOL = 0.05
"""Degrees: how far the stated lean may be from the one re-measured (the STEP file's decimals on an 8 mm thick
strip's vertices)."""


@check("bevels", 67)
def check_bevels(v: Verification) -> None:
    from ._step_read import read_or_report

    m = v.data.get("manifest", {})
    files = m.get("files", {})
    rel, rel_g = files.get("bevels_csv"), files.get("glazing_step")
    if rel is None or rel_g is None:
        return
    rows = v.read_table(rel, BEVEL_COLUMNS)
    read = read_or_report(v, rel_g)
    if rows is None or read is None:
        return
    threshold = float(m.get("fabrication", {}).get("glazing", {}).get("bevel_min_deg", 0.0))
    solids = {s.name: s.solid for s in read if s.name.startswith("GS-")}
    parts = v.data.get("parts", [])
    strips = {r["part_id"]: r for r in parts if r.get("kind") == "strip"}
    plates: dict[str, list[tuple[set[int], np.ndarray, float]]] = {}
    for r in parts:
        pl, nodes = literal(r.get("plane", "")), literal(r.get("nodes", ""))
        if r.get("kind") == "beam" and isinstance(pl, list) and len(pl) == 4 and isinstance(nodes, list):
            n = np.asarray(pl[:3], dtype=float)
            plates.setdefault(r.get("beam_id", ""), []).append(({int(k) for k in nodes}, n / np.linalg.norm(n),
                                                                number(r.get("thickness_mm"))))
    stated = {r.get("strip", ""): r for r in rows}
    for pid in sorted(set(strips) - set(stated)):
        v.error(rel, pid, "strip has no row")
    for pid, r in sorted(stated.items()):
        s, solid = strips.get(pid), solids.get(pid)
        if s is None or solid is None:
            v.error(rel, pid, f"is not a strip of parts.csv with a solid in {rel_g}")
            continue
        try:
            i, j = (int(x) for x in s.get("edge_nodes", "").split(";"))
        except ValueError:
            continue                                 # the glazing_step check names a bad edge_nodes
        mine = plates.get(s.get("beam", ""), [])
        plate = next((p for p in mine if i in p[0] and j in p[0]), next((p for p in mine if i in p[0] or j in p[0]),
                                                                      None))
        if plate is None:
            continue                                 # the glazing_step check names a strip without a plate
        pts = solid_points(solid)
        u = np.linalg.svd(pts - pts.mean(axis=0))[2][2]
        sin = min(1.0, abs(float(u @ plate[1])))
        lean = math.degrees(math.asin(sin))
        half = 0.5 * plate[2]
        want = {"lean_deg": (lean, LEAN_TOL), "overlap_mm": (half * sin, 0.01),
                "delta_mm": (half * math.tan(math.radians(lean)), 0.01)}
        for key, (value, tol) in want.items():
            got = number(r.get(key))
            if not abs(got - value) <= tol:
                v.error(rel, pid, f"{key} {r.get(key)!r} is not the {value:.3f} re-measured from {rel_g} and the "
                                  "plate's plane in parts.csv")
        bevelled = r.get("bevel", "") != "square"
        if lean > threshold + LEAN_TOL and not bevelled:
            v.error(rel, pid, f"leans {lean:.2f}° on its plate, more than glazing.bevel_min_deg = {threshold:g}°, "
                              "but has no bevel")
        elif lean < threshold - LEAN_TOL and bevelled:
            v.error(rel, pid, f"is bevelled but leans only {lean:.2f}° (glazing.bevel_min_deg = {threshold:g}°)")
    v.checked.append("bevels")
